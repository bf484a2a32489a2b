// Interleaved measurement and its verdicts: the runner's groups, the A/A control, findings.json
// against a fake clock with known effects, "same tree", resuming after a group is killed, and the
// real `bvhlab measure` child process (llvmpipe) on a tiny mesh.
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <sstream>

#include <gtest/gtest.h>

#include "datasets/image_io.hpp"
#include "experiments/config.hpp"
#include "experiments/executor.hpp"
#include "experiments/runner.hpp"
#include "experiments/sweep_dir.hpp"
#include "render/frame_stats.hpp"
#include "tests/test_experiments_fixture.hpp"

namespace fs = std::filesystem;
using namespace bvhlab;
using nlohmann::json;

namespace {

const fs::path kFixtures = fs::path(BVHLAB_SOURCE_DIR) / "tests" / "fixtures" / "experiments";
const KnownNames kNames{{"median", "sah-binned", "embree"}, {"stack-ordered", "stackless"}};
constexpr const char* kDeathTestDirEnv = "BVHLAB_MEASUREMENT_DEATH_TEST_DIR";

void writeText(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

json readJsonFile(const fs::path& p) {
  std::ifstream in(p);
  return json::parse(in);
}

// A fake clock for whole groups: every round draws each run once; the machine drifts (a ramp and a
// random load shared by the round) and each frame adds its own 1% jitter. True times: median-split
// trees 1.3x the others; sah-binned at leaf 16 builds the same tree as at leaf 4 (same hash) but
// the fake reports it 10% slower, so only the tree hash can make that verdict "same tree".
struct FakeClock {
  int rounds = 40;
  std::map<std::string, int> calls;  // per run key
  int groups = 0;

  static double trueMs(const RunSpec& s) {
    const std::string builder = s.axis("builder")->value["name"];
    const std::string leaf = s.axis("leaf_size")->label;
    double ms = builder == "median" ? 13.0 : 10.0;
    if (builder == "sah-binned" && leaf == "16") ms *= 1.10;
    return ms;
  }
  static std::string treeHash(const RunSpec& s) {
    const std::string builder = s.axis("builder")->value["name"];
    const std::string leaf = s.axis("leaf_size")->label;
    return builder == "sah-binned" ? "00000000000000aa" : builder + "-" + leaf;
  }

  json operator()(GroupRequest& g) {
    ++groups;
    std::mt19937_64 rng(1000 + groups);
    std::normal_distribution<double> load(0.0, 0.2), jitter(0.0, 0.01);
    std::vector<std::vector<double>> ms(g.runs.size() + 1);
    for (int r = 0; r < rounds; ++r) {
      const double machine = (1.0 + 0.01 * r) * std::exp(load(rng));
      for (size_t i = 0; i < g.runs.size(); ++i)
        ms[i].push_back(trueMs(g.runs[i].spec) * machine * std::exp(jitter(rng)));
      ms.back().push_back(trueMs(g.runs[0].spec) * machine * std::exp(jitter(rng)));  // the A/A control
    }
    json out = json::object();
    for (size_t i = 0; i < g.runs.size(); ++i) {
      const RunSpec& s = g.runs[i].spec;
      ++calls[s.key];
      json r = experiments_test::fakeMeasuredRun(ms[i], g.session);
      r.update({{"tree_hash", treeHash(s)},
                {"sah_cost", s.axis("builder")->value["name"] == "median" ? 44.0 : 34.0},
                {"node_visits_per_ray", s.axis("builder")->value["name"] == "median" ? 12.0 : 9.0},
                {"triangle_tests_per_ray", 3.0},
                {"effective_depth", 1}});
      if (i == 0) {
        const auto aa = pairedRatio(ms[0], ms.back());
        r["aa_control_ratio"] = aa->estimate;
        r["aa_control_ci_low"] = aa->low;
        r["aa_control_ci_high"] = aa->high;
      }
      out[s.key] = r;
    }
    return out;
  }
};

class Measurement : public ::testing::Test {
 protected:
  void SetUp() override {
    if (const char* inherited = std::getenv(kDeathTestDirEnv)) {
      root = inherited;
    } else {
      std::string tmpl = (fs::path(::testing::TempDir()) / "bvhlab-measurement-XXXXXX").string();
      ASSERT_NE(::mkdtemp(tmpl.data()), nullptr);
      root = tmpl;
    }
    ::setenv("BVHLAB_SOURCE_DIR", BVHLAB_SOURCE_DIR, 1);
    fs::copy_file(kFixtures / "quad.off", root / "a.off", fs::copy_options::overwrite_existing);
    fs::copy_file(kFixtures / "quad.off", root / "b.off", fs::copy_options::overwrite_existing);
  }
  void TearDown() override {
    if (!std::getenv(kDeathTestDirEnv) && !std::getenv("BVHLAB_KEEP_TEST_DIRS")) fs::remove_all(root);
  }

  RunOptions options(const std::string& config, const fs::path& out) {
    return experiments_test::sweepOptions(root / "cfg.toml", config, out, kNames);
  }

  fs::path root;
};

const char* kBuilders = R"(
[axes]
scenes = "a.off"
builders = ["median", "sah-binned", "embree"]
kernels = "stack-ordered"
leaf_sizes = [4, 16]
)";

const json* findComparison(const json& findings, const std::string& kind, const std::string& axis,
                           const std::string& a, const std::string& b, const std::string& context) {
  for (const json& c : findings["comparisons"])
    if (c["kind"] == kind && c["axis"] == axis && c["a_label"] == a && c["b_label"] == b &&
        (context.empty() || c["context"] == context))
      return &c;
  return nullptr;
}

}  // namespace

TEST_F(Measurement, RunsOfOneSceneAndSettingsAreOneGroupAndTheirFramesPair) {
  FakeClock clock;
  RunOptions o = options(std::string(kBuilders) + "\n[[sweep]]\nname = 'a'\n[[sweep]]\nname = 'b'\nscenes = 'b.off'\n",
                         root / "out");
  o.groupExecutor = [&](GroupRequest& g) { return clock(g); };
  const SweepOutcome outcome = runSweep(o);
  EXPECT_EQ(outcome.executed, 12u);
  EXPECT_EQ(clock.groups, 2) << "one group per scene";
  std::map<std::string, std::set<std::string>> sessions;  // scene -> sessions
  for (const auto& [key, record] : readRecords(SweepDir{root / "out"})) {
    EXPECT_EQ(record["status"], "ok");
    EXPECT_EQ(record["group_runs"], 6);
    sessions[record["params"]["axes"][0]["label"]].insert(record["session"].get<std::string>());
  }
  ASSERT_EQ(sessions.size(), 2u);
  for (const auto& [scene, s] : sessions) EXPECT_EQ(s.size(), 1u) << scene;
  EXPECT_NE(*sessions["a"].begin(), *sessions["b"].begin());

  // group_size splits a group; [measure] settings reach the group file.
  FakeClock small;
  RunOptions o2 = options(std::string("[measure]\ngroup_size = 4\nmin_frames = 8\nmax_frames = 30\ntarget_ci_pct = 1.5\n") +
                              kBuilders,
                          root / "out2");
  std::vector<json> specs;
  o2.groupExecutor = [&](GroupRequest& g) {
    specs.push_back(measureSpec("/bin/bvhlab", g));
    return small(g);
  };
  runSweep(o2);
  ASSERT_EQ(specs.size(), 2u);
  EXPECT_EQ(specs[0]["runs"].size(), 4u);
  EXPECT_EQ(specs[1]["runs"].size(), 2u);
  EXPECT_EQ(specs[0]["min_frames"], 8);
  EXPECT_EQ(specs[0]["max_frames"], 30);
  EXPECT_EQ(specs[0]["target_ci_pct"], 1.5);
  EXPECT_EQ(specs[0]["runs"][0]["args"][0], (root / "a.off").string()) << "render's arguments, no binary";
}

TEST_F(Measurement, FakeClockWithKnownEffectsGivesTheRightVerdicts) {
  FakeClock clock;
  // The baseline builder named in the config (else it would be median, the first value).
  RunOptions o = options(std::string(kBuilders) + "[findings]\nbaseline = { builder = \"sah-binned\" }\n", root / "out");
  o.groupExecutor = [&](GroupRequest& g) { return clock(g); };
  runSweep(o);
  const json f = readJsonFile(root / "out" / "findings.json");
  ASSERT_EQ(f["format"], 2);
  EXPECT_EQ(f["baselines"]["builder"], "sah-binned");

  // The median-split tree is 1.3x: slower than the baseline builder, with paired frames.
  const json* medianVsBest = nullptr;
  for (const json& c : f["comparisons"])
    if (c["kind"] == "builder-best" && c["a_label"] == "median") medianVsBest = &c;
  ASSERT_NE(medianVsBest, nullptr);
  EXPECT_EQ((*medianVsBest)["verdict"], "slower");
  EXPECT_TRUE((*medianVsBest)["paired"]);
  EXPECT_NEAR((*medianVsBest)["ratio"].get<double>(), 1.3, 0.03);
  EXPECT_LT((*medianVsBest)["ci_low"].get<double>(), 1.3);
  EXPECT_GT((*medianVsBest)["ci_high"].get<double>(), 1.3);
  EXPECT_EQ((*medianVsBest)["counts"]["sah_cost"], json::array({44.0, 34.0}));

  // At leaf 4, sah-binned and embree are equally fast: never a direction.
  int equalPairs = 0;
  for (const json& c : f["comparisons"])
    if (c["axis"] == "builder" && c["context"] == "leaf_size=4" && c["a_label"] != "median" && c["b_label"] != "median") {
      ++equalPairs;
      EXPECT_EQ(c["verdict"], "no detectable difference") << c.dump();
    }
  EXPECT_EQ(equalPairs, 1);
  // Median vs the baseline at leaf 4 and at leaf 16: slower both times.
  for (const json& c : f["comparisons"])
    if (c["kind"] == "axis" && c["axis"] == "builder" && c["a_label"] == "median") {
      EXPECT_EQ(c["verdict"], "slower");
    }

  // sah-binned leaf 16 vs 4: the same tree (same hash, same shader) although the fake clock says
  // 10% slower: the verdict must come from the tree, not the clock.
  const json* sameTree = findComparison(f, "axis", "leaf_size", "16", "4", "sah-binned");
  ASSERT_NE(sameTree, nullptr);
  EXPECT_EQ((*sameTree)["verdict"], "same tree");
  EXPECT_GT((*sameTree)["ratio"].get<double>(), 1.05);
  // A different tree at the same times is not "same tree": median leaf 4 vs 16 have different hashes.
  const json* medianLeaf = findComparison(f, "axis", "leaf_size", "16", "4", "median");
  if (!medianLeaf) medianLeaf = findComparison(f, "axis", "leaf_size", "4", "16", "median");
  ASSERT_NE(medianLeaf, nullptr);
  EXPECT_EQ((*medianLeaf)["verdict"], "no detectable difference");

  // The A/A control is the noise floor: one entry, its interval covering 1, and it sets the band.
  ASSERT_EQ(f["noise"].size(), 1u);
  const json& noise = f["noise"][0];
  EXPECT_LE(noise["ci_low"].get<double>(), 1.0);
  EXPECT_GE(noise["ci_high"].get<double>(), 1.0);
  const double band = std::max(std::abs(std::log(noise["ci_low"].get<double>())),
                               std::abs(std::log(noise["ci_high"].get<double>())));
  EXPECT_NEAR((*medianVsBest)["band"].get<double>(), band, 1e-12);

  // Every ratio sits inside its interval, and a direction is only claimed outside the band.
  for (const json& c : f["comparisons"]) {
    ASSERT_FALSE(c["ci_low"].is_null()) << c.dump();
    EXPECT_LE(c["ci_low"].get<double>(), c["ratio"].get<double>());
    EXPECT_GE(c["ci_high"].get<double>(), c["ratio"].get<double>());
    if (c["verdict"] == "slower") {
      EXPECT_GT(c["ci_low"].get<double>(), std::exp(c["band"].get<double>()));
    }
    if (c["verdict"] == "faster") {
      EXPECT_LT(c["ci_high"].get<double>(), std::exp(-c["band"].get<double>()));
    }
  }
  // The bunny-like scene has effective depth 1 but no depth axis: nothing skipped.
  EXPECT_TRUE(f["skipped"].empty());
  // Predictors: 6 runs in one context; SAH ranks median (44) above the rest (34, tied).
  ASSERT_EQ(f["predictors"].size(), 1u);
  EXPECT_GT(f["predictors"][0]["spearman"]["sah_cost"].get<double>(), 0.5);
}

TEST_F(Measurement, DepthIsComparedOnlyWhereItChangesTheRays) {
  FakeClock clock;
  RunOptions o = options(R"(
[axes]
scenes = "a.off"
builders = ["median", "sah-binned"]
leaf_sizes = 4
depths = [1, 3]
)",
                         root / "out");
  o.groupExecutor = [&](GroupRequest& g) { return clock(g); };
  runSweep(o);
  const json f = readJsonFile(root / "out" / "findings.json");
  ASSERT_EQ(f["skipped"].size(), 1u);
  EXPECT_NE(f["skipped"][0].get<std::string>().find("depth comparisons on a skipped"), std::string::npos);
  for (const json& c : f["comparisons"]) EXPECT_NE(c["axis"], "depth");
}

TEST_F(Measurement, AKilledGroupResumesWithoutLosingFinishedGroups) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  const std::string config = std::string(kBuilders) + "\n[[sweep]]\nname = 'a'\n[[sweep]]\nname = 'b'\nscenes = 'b.off'\n";
  ::setenv(kDeathTestDirEnv, root.c_str(), 1);
  EXPECT_EXIT(
      {
        FakeClock clock;
        RunOptions o = options(config, root / "out");
        o.groupExecutor = [&](GroupRequest& g) -> json {
          if (clock.groups == 1) std::_Exit(3);  // dies while measuring the second group
          return clock(g);
        };
        runSweep(o);
        std::_Exit(0);
      },
      ::testing::ExitedWithCode(3), "");
  ::unsetenv(kDeathTestDirEnv);

  const std::map<std::string, json> afterKill = readRecords(SweepDir{root / "out"});
  ASSERT_EQ(afterKill.size(), 6u) << "the first group's six runs were written before the second started";
  for (const auto& [key, record] : afterKill) EXPECT_EQ(record["params"]["axes"][0]["label"], "a");

  FakeClock clock;
  RunOptions o = options(config, root / "out");
  o.groupExecutor = [&](GroupRequest& g) { return clock(g); };
  const SweepOutcome resumed = runSweep(o);
  EXPECT_EQ(resumed.skipped, 6u);
  EXPECT_EQ(resumed.executed, 6u);
  EXPECT_EQ(clock.groups, 1);
  for (const auto& [key, record] : afterKill) EXPECT_EQ(clock.calls.count(key), 0u) << "finished run " << key << " redone";
  EXPECT_EQ(readJsonFile(root / "out" / "results.json")["rows"].size(), 12u);
}

TEST_F(Measurement, AGroupThatCrashesFailsItsRunsAndTheSweepGoesOn) {
  // A stand-in `bvhlab` whose measure dies on the scene named b.off.
  const fs::path fake = root / "fake_bvhlab.sh";
  writeText(fake, "#!/bin/sh\nif grep -q b.off \"$2\"; then echo 'measure: error: boom' >&2; kill -SEGV $$; fi\n"
                  "echo '{\"runs\": {}}'\n");
  fs::permissions(fake, fs::perms::owner_all);
  RunOptions o = options(std::string(kBuilders) + "\n[[sweep]]\nname = 'a'\n[[sweep]]\nname = 'b'\nscenes = 'b.off'\n",
                         root / "out");
  o.binary = fake;
  const SweepOutcome outcome = runSweep(o);
  EXPECT_EQ(outcome.executed, 12u);
  EXPECT_EQ(outcome.failed, 12u);
  for (const auto& [key, record] : readRecords(SweepDir{root / "out"})) {
    const std::string error = record["error"];
    if (record["params"]["axes"][0]["label"] == "b") {
      EXPECT_NE(error.find("signal 11"), std::string::npos) << error;
      EXPECT_NE(error.find("the whole group of 6 runs"), std::string::npos) << error;
    } else {
      EXPECT_NE(error.find("no entry for this run"), std::string::npos) << error;
    }
    EXPECT_NE(record["command"].get<std::string>().find("measure"), std::string::npos);
  }
}

TEST_F(Measurement, MeasureConfigIsValidated) {
  struct Case {
    const char* text;
    const char* expected;
  };
  const Case cases[] = {
      {"[measure]\nmin_frames = 20\nmax_frames = 10\n", "below min_frames"},
      {"[render]\nframes = 5\n[measure]\nmin_frames = 20\n", "give it in one place"},
      {"[measure]\ntarget_ci_pct = 0\n", "(0, 100]"},
      {"[measure]\ntarget = 2\n", "unknown key; [measure] has"},
      {"[measure]\ngroup_size = 0\n", "outside"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.text);
    writeText(root / "v.toml", std::string(c.text) + "[axes]\nscenes = 'a.off'\n");
    try {
      loadExperimentConfig(root / "v.toml", kNames);
      ADD_FAILURE() << "expected an InputError";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(c.expected), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("v.toml:"), std::string::npos) << e.what();
    }
  }
  // min_frames is frames by another name; max_frames defaults to at least it.
  writeText(root / "v.toml", "[measure]\nmin_frames = 150\n[axes]\nscenes = 'a.off'\n");
  const ExperimentConfig cfg = loadExperimentConfig(root / "v.toml", kNames);
  EXPECT_EQ(cfg.runs[0].render.frames, 150);
  EXPECT_EQ(cfg.runs[0].render.maxFrames, 150);
}

// The real thing: `bvhlab measure` renders a group on llvmpipe. A run with an unknown kernel fails
// alone; the others share one session, have as many frames as there were rounds, an interval, and
// one of them carries the A/A control.
TEST_F(Measurement, RealMeasureProcessTimesAGroupInterleaved) {
  RunOptions o = options(R"(
[render]
width = 48
height = 27
warmup = 1
heatmaps = false
[measure]
min_frames = 8
max_frames = 16
target_ci_pct = 50
[axes]
scenes = { generate = "soup", triangles = 300, seed = 1 }
builders = ["median", "sah-binned"]
kernels = ["stack-ordered", "no-such-kernel"]
)",
                         root / "out");
  o.names = KnownNames{};  // let the renderer, not the config, refuse the kernel
  o.binary = BVHLAB_BINARY;
  const SweepOutcome outcome = runSweep(o);
  EXPECT_EQ(outcome.executed, 4u);
  EXPECT_EQ(outcome.failed, 2u);
  std::set<std::string> sessions, programs;
  std::set<int> stackSizes, depths;
  int controls = 0;
  for (const auto& [key, record] : readRecords(SweepDir{root / "out"})) {
    const std::string kernel = record["params"]["axes"][2]["label"];
    if (kernel == "no-such-kernel") {
      EXPECT_EQ(record["status"], "failed");
      EXPECT_NE(record["error"].get<std::string>().find("kernel"), std::string::npos) << record["error"];
      continue;
    }
    ASSERT_EQ(record["status"], "ok") << record.dump();
    const json& r = record["result"];
    sessions.insert(r["session"].get<std::string>());
    const int frames = r["frames"];
    EXPECT_GE(frames, 8);
    EXPECT_LE(frames, 16);
    EXPECT_EQ(r["frame_ms_all"].size(), size_t(frames));
    EXPECT_EQ(r["rounds"], frames);
    EXPECT_LE(r["frame_ms_ci_low"].get<double>(), r["frame_ms"].get<double>());
    EXPECT_GE(r["frame_ms_ci_high"].get<double>(), r["frame_ms"].get<double>());
    EXPECT_EQ(r["tree_hash"].get<std::string>().size(), 16u);
    EXPECT_GE(r["epo"].get<double>(), 0.0);
    if (r.contains("aa_control_ratio")) {
      ++controls;
      EXPECT_EQ(r["aa_control_frame_ms_all"].size(), size_t(frames));
      EXPECT_EQ(r["aa_shared_control_frame_ms_all"].size(), size_t(frames));
      EXPECT_TRUE(r.contains("aa_shared_control_ratio"));
    }
    // The two trees have different depths, but one stack size and one shader text: one program.
    programs.insert(r["program"].dump());
    stackSizes.insert(r["bvh_stack_size"].get<int>());
    depths.insert(r["bvh_depth"].get<int>());
    EXPECT_GE(r["bvh_stack_size"].get<int>(), r["bvh_depth"].get<int>());
    EXPECT_TRUE(fs::exists(root / "out" / record["image"].get<std::string>()));
  }
  EXPECT_EQ(sessions.size(), 1u);
  EXPECT_EQ(controls, 1);
  EXPECT_EQ(programs, std::set<std::string>{"0"});
  EXPECT_EQ(stackSizes.size(), 1u);
  EXPECT_EQ(depths.size(), 2u) << "the fixture should give the two builders trees of different depths";
  const json f = readJsonFile(root / "out" / "findings.json");
  ASSERT_FALSE(f["comparisons"].empty());
  for (const json& c : f["comparisons"]) {
    EXPECT_TRUE(c["paired"]) << c.dump();
    EXPECT_TRUE(c["shared_program"]) << c.dump();
  }
}

// Ctrl-C (SIGINT) or SIGTERM to `bvhlab run` stops the group's child too, keeps what finished, and
// says how to resume; nothing is left running.
TEST_F(Measurement, SigintStopsTheRunningGroupsChildAndSaysHowToResume) {
  const fs::path marker = root / "child.pid";
  const fs::path fake = root / "slow_bvhlab.sh";
  // The stand-in measure writes its pid, then takes far longer than the test waits.
  writeText(fake, "#!/bin/sh\necho $$ > '" + marker.string() + "'\nexec sleep 60\n");
  fs::permissions(fake, fs::perms::owner_all);
  writeText(root / "cfg.toml", kBuilders);
  const std::string err = (root / "stderr.txt").string();
  const std::string cmd = std::string("exec ") + BVHLAB_BINARY + " run " + (root / "cfg.toml").string() + " --out " +
                          (root / "out").string() + " --binary " + fake.string() + " --no-report 2> " + err;
  const pid_t runner = ::fork();
  ASSERT_GE(runner, 0);
  if (runner == 0) {
    ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    std::_Exit(127);
  }
  // Wait for the child measure to start (at most 20 s).
  for (int i = 0; i < 200 && !fs::exists(marker); ++i) ::usleep(100000);
  ASSERT_TRUE(fs::exists(marker)) << "the runner never started its group";
  ::usleep(200000);  // the pid line is written
  std::ifstream in(marker);
  pid_t child = 0;
  in >> child;
  ASSERT_GT(child, 0);
  ASSERT_EQ(::kill(runner, SIGINT), 0);
  int status = 0;
  const auto start = std::chrono::steady_clock::now();
  ASSERT_EQ(::waitpid(runner, &status, 0), runner);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 10.0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 128 + SIGINT);
  // The child is gone (reaped by the runner, so not even a zombie answers).
  EXPECT_NE(::kill(child, 0), 0) << "the group's child " << child << " is still running";
  std::ifstream e(err);
  const std::string text((std::istreambuf_iterator<char>(e)), {});
  EXPECT_NE(text.find("interrupted"), std::string::npos) << text;
  EXPECT_NE(text.find("resume with: bvhlab run"), std::string::npos) << text;
  EXPECT_TRUE(readRecords(SweepDir{root / "out"}).empty()) << "the killed group's runs stay pending";
}
