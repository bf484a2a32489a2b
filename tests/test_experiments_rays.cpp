// The rays axis of experiment configs: runs that trace a ray workload (`bvhlab trace`) instead of
// rendering frames: config parsing and validation, the command line, and a real sweep through the
// runner to results, findings and the report's ray sections.
#include <fstream>
#include <map>
#include <set>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_run.hpp"
#include "datasets/scene.hpp"
#include "experiments/config.hpp"
#include "experiments/executor.hpp"
#include "experiments/process.hpp"
#include "render/workloads.hpp"

namespace {

using namespace bvhlab;
using namespace bvhlab::clitest;
using nlohmann::json;

[[maybe_unused]] ::testing::Environment* const kRemoveTestDir = ::testing::AddGlobalTestEnvironment(new RemoveTestDir);

ExperimentConfig parse(const std::string& text) {
  const fs::path file = writeTemp("rays/cfg.toml", text);
  writeTemp("rays/m.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  return parseExperimentConfig(text, file, registeredNames());
}

TEST(ExperimentRays, AxisExpandsAndOnlyTraceRunsKeyTheTraceSettings) {
  const ExperimentConfig cfg = parse(R"(
[trace]
count = 5000
seed = 3
[axes]
scenes = "m.off"
builders = ["median", "sah-binned"]
rays = ["primary", "diffuse", "ao"]
)");
  ASSERT_EQ(cfg.runs.size(), 6u);
  EXPECT_EQ(cfg.runs[1].axis("workload")->label, "diffuse");
  EXPECT_NE(cfg.runs[0].keyJson().dump().find("\"count\":5000"), std::string::npos);
  // A render run's key does not change with [trace] (configs written before the axis keep their keys).
  const ExperimentConfig plain = parse("[axes]\nscenes = \"m.off\"\n");
  const ExperimentConfig withTrace = parse("[trace]\ncount = 7\n[axes]\nscenes = \"m.off\"\n");
  EXPECT_EQ(plain.runs[0].key, withTrace.runs[0].key);
  // The axis's values are the trace command's workloads.
  EXPECT_EQ(workloadNames().size(), 5u);
}

TEST(ExperimentRays, ValidationNamesTheKey) {
  struct Case {
    const char* text;
    std::vector<std::string> expected;
  };
  const Case cases[] = {
      {"[axes]\nscenes = 'm.off'\nrays = 'difuse'\n", {"cfg.toml:3", "axes.rays", "unknown workload 'difuse'", "diffuse"}},
      {"[axes]\nscenes = 'm.off'\nrays = 'ao'\ndepths = [1, 2]\n", {"axes.rays", "'depth'"}},
      {"[trace]\ncount = 0\n[axes]\nscenes = 'm.off'\n", {"cfg.toml:2", "trace.count"}},
      {"[trace]\nao_radius = 2.0\n[axes]\nscenes = 'm.off'\n", {"cfg.toml:2", "trace.ao_radius", "(0, 1]"}},
      {"[trace]\ncolor = 1\n[axes]\nscenes = 'm.off'\n", {"cfg.toml:2", "trace.color", "unknown key"}},
      {"[trace]\nembree_threads = -1\n[axes]\nscenes = 'm.off'\n", {"cfg.toml:2", "trace.embree_threads"}},
      {"[trace]\nmin_sample_ms = -1\n[axes]\nscenes = 'm.off'\n", {"cfg.toml:2", "trace.min_sample_ms", "[0, 10000]"}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.text);
    try {
      parse(c.text);
      ADD_FAILURE() << "expected an InputError";
    } catch (const InputError& e) {
      for (const std::string& s : c.expected) EXPECT_NE(std::string(e.what()).find(s), std::string::npos) << e.what();
    }
  }
}

TEST(ExperimentRays, TraceRunsRunTheTraceCommand) {
  const ExperimentConfig cfg = parse(R"(
[render]
frames = 6
warmup = 1
[measure]
max_frames = 20
target_ci_pct = 4
[trace]
count = 1234
seed = 9
ao_radius = 0.25
[axes]
scenes = { file = "m.off", eye = [1, 2, 3] }
builders = { name = "sah-binned", bins = 16 }
kernels = "stackless"
leaf_sizes = 2
robust = "fast"
rays = "ao"
)");
  ASSERT_EQ(cfg.runs.size(), 1u);
  RunRequest req{cfg.runs[0], testDir() / "i.png", testDir() / "v.png", "", ""};
  const std::string line = shellQuote(renderCommandLine("/bin/bvhlab", req));
  for (const char* part : {"/bin/bvhlab trace ", "m.off --json --count 1234 --seed 9 --ao-radius 0.25 --frames 6 --warmup 1",
                           "--max-frames 20 --target-ci-pct 4", "--eye 1,2,3", "--builder sah-binned --bins 16",
                           "--kernel stackless", "--leaf-size 2", "--robust fast", "--rays ao"})
    EXPECT_NE(line.find(part), std::string::npos) << part << " not in: " << line;
  for (const char* absent : {" -o ", "--visits-out", "--width", "--embree-threads"})
    EXPECT_EQ(line.find(absent), std::string::npos) << line;
}

// [trace] embree_threads (with env LP_NUM_THREADS, one core per tracer): on the trace command line and
// in the keys of trace runs only when set, so configs without it keep their keys.
TEST(ExperimentRays, EmbreeThreadsReachTheTraceCommandAndOnlyTraceKeys) {
  const char* base = "[axes]\nscenes = 'm.off'\n[[sweep]]\nname = 'a'\nrays = 'primary'\n[[sweep]]\nname = 'b'\n";
  const ExperimentConfig plain = parse(base);
  const ExperimentConfig oneCore = parse(std::string("[render]\nenv = { LP_NUM_THREADS = '1' }\n[trace]\nembree_threads = 1\n") + base);
  const ExperimentConfig oneThread = parse(std::string("[trace]\nembree_threads = 1\n") + base);
  ASSERT_EQ(plain.runs.size(), 2u);
  ASSERT_EQ(oneThread.runs.size(), 2u);
  ASSERT_TRUE(oneThread.runs[0].axis("workload"));
  ASSERT_FALSE(oneThread.runs[1].axis("workload"));
  EXPECT_NE(plain.runs[0].key, oneThread.runs[0].key);  // the traced run: another yardstick, another run
  EXPECT_EQ(plain.runs[1].key, oneThread.runs[1].key);  // the rendered run: unchanged
  const std::string line =
      shellQuote(renderCommandLine("/bin/bvhlab", RunRequest{oneCore.runs[0], testDir() / "i.png", "", "", ""}));
  EXPECT_NE(line.find("--embree-threads 1"), std::string::npos) << line;
  EXPECT_EQ(oneCore.runs[0].render.env.at("LP_NUM_THREADS"), "1");
  // The setting survives the plan file (runs are read back from plan.json on resume).
  EXPECT_EQ(RunSpec::fromJson(oneThread.runs[0].toJson()).render.embreeThreads, 1);

  // [trace] min_sample_ms likewise: on the trace command line, in trace keys only, through plan.json;
  // absent, no flag (the tracer's default for its renderer).
  const ExperimentConfig sampled = parse(std::string("[trace]\nmin_sample_ms = 12.5\n") + base);
  ASSERT_EQ(sampled.runs.size(), 2u);
  EXPECT_NE(plain.runs[0].key, sampled.runs[0].key);
  EXPECT_EQ(plain.runs[1].key, sampled.runs[1].key);
  const std::string sampledLine =
      shellQuote(renderCommandLine("/bin/bvhlab", RunRequest{sampled.runs[0], testDir() / "i.png", "", "", ""}));
  EXPECT_NE(sampledLine.find("--min-sample-ms 12.5"), std::string::npos) << sampledLine;
  EXPECT_EQ(line.find("--min-sample-ms"), std::string::npos) << line;
  EXPECT_EQ(RunSpec::fromJson(sampled.runs[0].toJson()).render.minSampleMs, 12.5);
}

// A real sweep: a generated mesh, two builders, two workloads, through `bvhlab run`. Its timed samples
// are at least 15 ms long (as on a GPU, where the default asks for 10): 3,000 rays take less on
// llvmpipe, so each sample is several dispatches, and the report's provenance says so.
TEST(ExperimentRays, SweepRecordsTraceResultsAndTheReportShowsThem) {
  const fs::path cfg = writeTemp("rays-run/cfg.toml", R"(
[experiment]
name = "rays-test"
description = "trace runs"
[render]
frames = 6
warmup = 1
[measure]
max_frames = 6
[trace]
count = 3000
min_sample_ms = 15
[axes]
scenes = { generate = "large", triangles = 20000, seed = 2, name = "cloud" }
builders = ["median", "sah-binned"]
rays = ["primary", "diffuse"]
)");
  const fs::path out = testDir() / "rays-run/out";
  Result r = run("run " + cfg.string() + " --out " + out.string());
  ASSERT_EQ(r.code, 0) << r.err;
  std::ifstream in(out / "results.json");
  const json results = json::parse(in);
  size_t traced = 0;
  for (const json& row : results["rows"]) {
    if (row.value("control_of", json()).is_string()) continue;
    ASSERT_EQ(row["status"], "ok") << row.dump();
    ++traced;
    EXPECT_EQ(row["rays"], 3000);
    EXPECT_GT(row["mrays_per_s"].get<double>(), 0.0);
    EXPECT_GT(row["embree_mrays_per_s"].get<double>(), 0.0);
    EXPECT_EQ(row["hit_mismatches"], 0);
    EXPECT_TRUE(row["workload"] == "primary" || row["workload"] == "diffuse");
    EXPECT_FALSE(row["node_visits_per_ray_ci_low"].is_null());
    EXPECT_EQ(row["min_sample_ms"], 15.0);
    EXPECT_GT(row["dispatches_per_sample"].get<int>(), 1) << row.dump();
  }
  EXPECT_EQ(traced, 4u);
  std::ifstream fin(out / "findings.json");
  const json findings = json::parse(fin);
  size_t builderComparisons = 0;
  for (const json& c : findings["comparisons"])
    if (c["axis"] == "builder" && c["context"].get<std::string>().find("workload=") != std::string::npos)
      ++builderComparisons;
  EXPECT_GE(builderComparisons, 2u) << findings.dump();
  std::ifstream hin(out / "report.html");
  const std::string html((std::istreambuf_iterator<char>(hin)), {});
  for (const char* id : {"id=\"rays\"", "id=\"rays-table-cloud\"", "visits vs sah-binned", "id=\"plot-scaling\"",
                         "dispatches a timed sample (at least 15 ms)"})
    EXPECT_NE(html.find(id), std::string::npos) << id;
}

// Traced runs of one scene and settings are ONE trace group (`bvhlab measure` with "command":
// "trace"): one session, the same rounds for every run, runs with the same rays share one Embree
// batch (`yardstick`), the first run carries the A/A control, and the findings pair the runs' rounds
// directly (not through Embree).
TEST(ExperimentRays, TraceRunsAreOneGroupWhoseRoundsPair) {
  const fs::path cfg = writeTemp("rays-group/cfg.toml", R"(
[experiment]
name = "rays-group"
description = "a trace group"
[render]
warmup = 1
[measure]
min_frames = 8
max_frames = 8
[trace]
count = 2000
[axes]
scenes = { generate = "large", triangles = 5000, seed = 3, name = "cloud" }
builders = ["median", "sah-binned"]
rays = ["primary", "diffuse"]
)");
  const fs::path out = testDir() / "rays-group/out";
  Result r = run("run " + cfg.string() + " --out " + out.string());
  ASSERT_EQ(r.code, 0) << r.err;
  std::ifstream in(out / "results.json");
  const json results = json::parse(in);
  std::set<std::string> sessions;
  std::map<std::string, std::set<int>> yardsticks;  // workload -> yardstick indices
  int controls = 0, rows = 0;
  for (const json& row : results["rows"]) {
    ASSERT_EQ(row["status"], "ok") << row.dump();
    ++rows;
    sessions.insert(row["session"].get<std::string>());
    yardsticks[row["workload"].get<std::string>()].insert(row["yardstick"].get<int>());
    EXPECT_EQ(row["rounds"], 8);
    EXPECT_EQ(row["frame_ms_all"].size(), 8u);
    EXPECT_EQ(row["embree_ms_all"].size(), 8u);
    EXPECT_EQ(row["hit_mismatches"], 0);
    if (row.contains("aa_control_frame_ms_all")) {
      ++controls;
      EXPECT_EQ(row["aa_control_frame_ms_all"].size(), 8u);
      EXPECT_TRUE(row.contains("aa_control_ratio"));
    }
  }
  EXPECT_EQ(rows, 4);
  EXPECT_EQ(sessions.size(), 1u);
  EXPECT_EQ(controls, 1);
  ASSERT_EQ(yardsticks.size(), 2u);
  EXPECT_EQ(yardsticks["primary"].size(), 1u);  // both builders traced the same primary rays
  EXPECT_EQ(yardsticks["diffuse"].size(), 1u);
  EXPECT_NE(*yardsticks["primary"].begin(), *yardsticks["diffuse"].begin());
  std::ifstream fin(out / "findings.json");
  const json findings = json::parse(fin);
  size_t builderComparisons = 0;
  for (const json& c : findings["comparisons"]) {
    if (c["axis"] != "builder") continue;
    ++builderComparisons;
    EXPECT_TRUE(c["paired"]) << c.dump();
    EXPECT_EQ(c["interval_over"], "rounds") << c.dump();
    EXPECT_TRUE(c["normalised_by"].is_null()) << c.dump();
  }
  EXPECT_GE(builderComparisons, 2u) << findings.dump();  // per workload (and "each at its best")
  EXPECT_EQ(findings["noise"].size(), 1u) << findings.dump();
}

// A trace group hands back the runs that would pass its memory budget (render/trace_group.cpp), and
// the runner traces them in later groups: with a budget of one byte's worth, every group keeps only
// its first run, and every run still ends ok, each in its own session.
TEST(ExperimentRays, RunsATraceGroupHandsBackAreTracedInLaterGroups) {
  const fs::path cfg = writeTemp("rays-deferred/cfg.toml", R"(
[experiment]
name = "rays-deferred"
description = "deferred trace runs"
[render]
warmup = 1
env = { BVHLAB_TRACE_GROUP_MEMORY_FRACTION = "1e-12" }
[measure]
min_frames = 3
max_frames = 3
aa_control = false
[trace]
count = 500
[axes]
scenes = { generate = "large", triangles = 2000, seed = 3, name = "cloud" }
builders = ["median", "sah-binned", "lbvh"]
rays = "primary"
)");
  const fs::path out = testDir() / "rays-deferred/out";
  Result r = run("run " + cfg.string() + " --out " + out.string());
  ASSERT_EQ(r.code, 0) << r.err;
  std::ifstream in(out / "results.json");
  const json results = json::parse(in);
  std::set<std::string> sessions;
  for (const json& row : results["rows"]) {
    ASSERT_EQ(row["status"], "ok") << row.dump();
    sessions.insert(row["session"].get<std::string>());
    EXPECT_EQ(row["frame_ms_all"].size(), 3u);
  }
  EXPECT_EQ(results["rows"].size(), 3u);
  EXPECT_EQ(sessions.size(), 3u);
}

// A trace group's file: a run that cannot be traced fails alone; with program copies every run keeps
// each copy's rounds; an unknown command is refused with the key.
TEST(ExperimentRays, TraceGroupFileErrors) {
  writeTemp("rays-group-file/m.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n3 0 1 2\n3 1 3 2\n");
  const std::string mesh = (testDir() / "rays-group-file/m.off").string();
  auto group = [&](const std::string& extra) {
    json spec = {{"session", "s"}, {"min_frames", 3}, {"max_frames", 3}, {"aa_control", false},
                 {"runs", {{{"key", "good"}, {"args", {mesh, "--json", "--count", "64", "--rays", "primary"}}},
                           {{"key", "bad"}, {"args", {mesh, "--json", "--kernel", "no-such-kernel"}}}}}};
    spec.update(json::parse(extra));
    return writeTemp("rays-group-file/g.json", spec.dump());
  };
  Result r = run("measure " + group(R"({"command": "trace"})").string());
  ASSERT_EQ(r.code, 0) << r.err;
  const json out = json::parse(r.out);
  EXPECT_EQ(out["command"], "trace");
  EXPECT_EQ(out["runs"]["good"]["frame_ms_all"].size(), 3u) << r.out;
  EXPECT_EQ(out["runs"]["good"]["rays"], 64);
  EXPECT_NE(out["runs"]["bad"]["error"].get<std::string>().find("no-such-kernel"), std::string::npos) << r.out;
  EXPECT_FALSE(out["runs"]["good"].contains("frame_ms_copies"));
  r = run("measure " + group(R"({"command": "trace", "program_copies": 2})").string());
  ASSERT_EQ(r.code, 0) << r.err;
  const json copies = json::parse(r.out)["runs"]["good"];
  ASSERT_EQ(copies["frame_ms_copies"].size(), 2u) << r.out;
  for (const json& ms : copies["frame_ms_copies"]) EXPECT_EQ(ms.size(), 3u);
  EXPECT_EQ(copies["frame_ms_all"].size(), 3u);
  EXPECT_EQ(copies["program_copies"], 2);
  // One sample length for the whole group (the largest of its runs' --min-sample-ms): dispatches per
  // sample from the warm-up's shortest dispatch, in the group's JSON and in every run's.
  json sampled = {{"session", "s"}, {"min_frames", 3}, {"max_frames", 3}, {"aa_control", false}, {"command", "trace"},
                  {"runs", {{{"key", "a"}, {"args", {mesh, "--json", "--count", "64", "--min-sample-ms", "30"}}},
                            {{"key", "b"}, {"args", {mesh, "--json", "--count", "64", "--builder", "median"}}}}}};
  r = run("measure " + writeTemp("rays-group-file/sampled.json", sampled.dump()).string());
  ASSERT_EQ(r.code, 0) << r.err;
  const json many = json::parse(r.out);
  EXPECT_EQ(many["min_sample_ms"], 30.0);
  EXPECT_GT(many["dispatches_per_sample"].get<int>(), 1) << r.out;  // 64 rays: far under 30 ms
  for (const char* key : {"a", "b"}) {
    EXPECT_EQ(many["runs"][key]["dispatches_per_sample"], many["dispatches_per_sample"]) << key;
    EXPECT_EQ(many["runs"][key]["frame_ms_all"].size(), 3u) << key;
    EXPECT_EQ(many["runs"][key]["hit_mismatches"], 0) << key;
  }
  EXPECT_EQ(out["dispatches_per_sample"], 1);  // the first group: llvmpipe's default, one a sample
  r = run("measure " + group(R"({"command": "draw"})").string());
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.err.find("command: \"draw\" (render | trace)"), std::string::npos) << r.err;
}

}  // namespace
