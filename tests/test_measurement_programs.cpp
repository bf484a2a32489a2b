// Program placement in measurements (render/program_cache.hpp, experiments/README.md "One program per
// shader text"): runs of one shader text share a program and their comparisons use the shared-program
// control's band; share_programs = false; program copies and the intervals across them. Fake groups
// for the findings, and the real `bvhlab measure` child (llvmpipe) on a tiny mesh for the rows (those
// tests are named Real*: labelled "gl" in tests/CMakeLists.txt).
#include <cmath>
#include <random>

#include "render/frame_stats.hpp"
#include "tests/test_experiments_fixture.hpp"

using namespace bvhlab::experiments_test;

namespace {

class MeasurementPrograms : public Experiments {
 protected:
  void SetUp() override {
    Experiments::SetUp();
    fs::copy_file(kFixtures / "quad.off", root / "a.off", fs::copy_options::overwrite_existing);
  }
  // A sweep of `config` into `out`, groups measured by the caller's executor (or a real child).
  RunOptions groupOptions(const std::string& config, const fs::path& out) {
    return sweepOptions(root / "cfg.toml", config, out, kNames);
  }
  // The real child on the quad: two builders, one kernel, 6 fixed rounds at 32x18, plus `measure`
  // (one more [measure] line).
  RunOptions realOptions(const std::string& measure) {
    RunOptions o = groupOptions("[render]\nwidth = 32\nheight = 18\nwarmup = 1\nheatmaps = false\n"
                                "[measure]\nmin_frames = 6\nmax_frames = 6\n" + measure + "\n"
                                "[axes]\nscenes = \"a.off\"\nbuilders = [\"median\", \"sah-binned\"]\n"
                                "kernels = \"stack-ordered\"\n",
                                root / "out");
    o.binary = BVHLAB_BINARY;
    return o;
  }
};

// A fake group of two builders whose frames carry `copies` program copies: in copy j the second
// builder's tree takes effect * exp(placement[j]) the first's time (what llvmpipe does: each
// compiled copy of the shared program moves the ratio a little), with small frame jitter.
GroupExecutor copiesExecutor(int copies, double effect, std::vector<double> placement) {
  return [=](GroupRequest& g) {
    std::mt19937_64 rng(11);
    std::normal_distribution<double> load(0.0, 0.2), jitter(0.0, 0.002);
    const int rounds = 40;
    json result = json::object();
    std::vector<json> lists(g.runs.size(), json::array());
    std::vector<std::vector<double>> perRound(g.runs.size(), std::vector<double>(rounds));
    std::vector<double> control;  // the first run's A/A control: its copy 0 again, over its own buffers
    for (int j = 0; j < copies; ++j) {
      std::vector<std::vector<double>> ms(g.runs.size());
      for (int r = 0; r < rounds; ++r) {
        const double machine = std::exp(load(rng));
        for (size_t i = 0; i < g.runs.size(); ++i) {
          const bool second = g.runs[i].spec.axis("builder")->label == "embree";
          ms[i].push_back(10.0 * (second ? effect * std::exp(placement[size_t(j)]) : 1.0) * machine * std::exp(jitter(rng)));
        }
        if (j == 0) control.push_back(10.0 * machine * std::exp(jitter(rng)));
      }
      for (size_t i = 0; i < g.runs.size(); ++i) {
        lists[i].push_back(ms[i]);
        for (int r = 0; r < rounds; ++r) perRound[i][size_t(r)] += ms[i][size_t(r)] / copies;
      }
    }
    for (size_t i = 0; i < g.runs.size(); ++i) {
      const RunSpec& s = g.runs[i].spec;
      json r = {{"frame_ms", medianOf(perRound[i])}, {"frame_ms_all", perRound[i]}, {"frames", rounds},
                {"session", g.session}, {"tree_hash", s.axis("builder")->label}, {"program", 0}};
      if (copies > 1) r["frame_ms_copies"] = lists[i], r["program_copies"] = copies;
      if (i == 0) r["aa_shared_control_frame_ms_all"] = control;
      result[s.key] = r;
    }
    return result;
  };
}

const char* kTwoBuilders = R"(
[axes]
scenes = "a.off"
builders = ["sah-binned", "embree"]
kernels = "stack-ordered"
)";

const json& builderComparison(const json& findings) {
  for (const json& c : findings["comparisons"])
    if (c["kind"] == "axis" && c["axis"] == "builder") return c;
  throw std::runtime_error("no builder comparison");
}

}  // namespace

// Program placement (render/program_cache.hpp): a fake group where runs of one kernel share a
// program, embree's tree is truly 3% slower than sah-binned, and the separately compiled copy of the first
// run's program (the "program" control) is 8% slow, as llvmpipe's unlucky copies are. Between runs
// of one program the shared-program control's narrow band applies, so the 3% is called; across
// kernels (two programs) the program control's band does. Without a shared control (older results)
// the program band applies everywhere and the 3% is not called.
TEST_F(MeasurementPrograms, RunsThatShareAProgramUseTheSharedControlsBand) {
  const std::string config = R"(
[axes]
scenes = "a.off"
builders = ["sah-binned", "embree"]
kernels = ["stack-ordered", "stackless"]
)";
  for (const bool sharedControl : {true, false}) {
    SCOPED_TRACE(sharedControl ? "with a shared control" : "without");
    const fs::path out = root / (sharedControl ? "shared" : "program-only");
    RunOptions o = groupOptions(config, out);
    o.groupExecutor = [&](GroupRequest& g) {
      std::mt19937_64 rng(7);
      std::normal_distribution<double> load(0.0, 0.2), jitter(0.0, 0.005);
      const size_t n = g.runs.size();
      std::vector<std::vector<double>> ms(n + 2);  // the runs, then the program and shared controls
      auto trueMs = [&](size_t i) { return g.runs[i].spec.axis("builder")->label == "embree" ? 10.3 : 10.0; };
      for (int r = 0; r < 60; ++r) {
        const double machine = std::exp(load(rng));
        for (size_t i = 0; i < n; ++i) ms[i].push_back(trueMs(i) * machine * std::exp(jitter(rng)));
        ms[n].push_back(trueMs(0) * 1.08 * machine * std::exp(jitter(rng)));      // another copy, unlucky
        ms[n + 1].push_back(trueMs(0) * machine * std::exp(jitter(rng)));         // the same program
      }
      json result = json::object();
      for (size_t i = 0; i < n; ++i) {
        const RunSpec& s = g.runs[i].spec;
        json r = {{"frame_ms", medianOf(ms[i])}, {"frame_ms_all", ms[i]}, {"frames", 60},
                  {"session", g.session},        {"tree_hash", s.axis("builder")->label},
                  {"program", s.axis("kernel")->label == "stackless" ? 1 : 0}};
        if (i == 0) {
          r["aa_control_frame_ms_all"] = ms[n];
          if (sharedControl) r["aa_shared_control_frame_ms_all"] = ms[n + 1];
        }
        result[s.key] = r;
      }
      return result;
    };
    runSweep(o);
    const json f = readJsonFile(out / "findings.json");
    ASSERT_EQ(f["noise"].size(), sharedControl ? 2u : 1u);
    double programBand = 0.0, sharedBand = 0.0;
    for (const json& e : f["noise"]) {
      const double band = std::max(std::abs(std::log(e["ci_low"].get<double>())), std::abs(std::log(e["ci_high"].get<double>())));
      (e["control"] == "program" ? programBand : sharedBand) = band;
    }
    EXPECT_GT(programBand, 0.06);  // the unlucky copy's 8%
    if (sharedControl) EXPECT_LT(sharedBand, 0.02);

    int builderPairs = 0, kernelPairs = 0;
    for (const json& c : f["comparisons"]) {
      if (c["kind"] != "axis") continue;
      if (c["axis"] == "builder") {
        ++builderPairs;
        EXPECT_TRUE(c["shared_program"]) << c.dump();
        EXPECT_EQ(c["a_label"], "embree");
        EXPECT_NEAR(c["ratio"].get<double>(), 1.03, 0.01);
        EXPECT_NEAR(c["band"].get<double>(), sharedControl ? sharedBand : programBand, 1e-12);
        EXPECT_EQ(c["verdict"], sharedControl ? "slower" : "no detectable difference") << c.dump();
      } else if (c["axis"] == "kernel") {
        ++kernelPairs;
        EXPECT_FALSE(c["shared_program"]) << c.dump();
        EXPECT_NEAR(c["band"].get<double>(), programBand, 1e-12);
        EXPECT_EQ(c["verdict"], "no detectable difference") << c.dump();
      }
    }
    EXPECT_EQ(builderPairs, 2);  // one per kernel
    EXPECT_EQ(kernelPairs, 2);   // one per builder
  }
}

// share_programs = false: every run compiles its own program (no `program`, no shared control).
TEST_F(MeasurementPrograms, RealShareProgramsFalseGivesEveryRunItsOwnProgram) {
  RunOptions o = realOptions("share_programs = false");
  ASSERT_EQ(runSweep(o).failed, 0u);
  int controls = 0;
  for (const auto& [key, record] : readRecords(SweepDir{root / "out"})) {
    ASSERT_EQ(record["status"], "ok") << record.dump();
    const json& r = record["result"];
    EXPECT_TRUE(r["program"].is_null()) << r["program"];
    EXPECT_FALSE(r.contains("aa_shared_control_ratio"));
    controls += r.contains("aa_control_ratio") ? 1 : 0;
  }
  EXPECT_EQ(controls, 1);
  for (const json& c : readJsonFile(root / "out" / "findings.json")["comparisons"]) EXPECT_FALSE(c["shared_program"]);
}

// With six copies, the interval is over the copies' ratios: a 1% effect that the placements move by
// up to +-2% is not called, although each copy's rounds (and the pooled rounds) resolve it; a 6%
// effect is. With five copies (no 95% order-statistic interval over five values) the findings fall
// back to the pooled rounds.
TEST_F(MeasurementPrograms, SixProgramCopiesGiveAnIntervalAcrossCopies) {
  const std::vector<double> placement = {-0.02, 0.02, -0.015, 0.015, -0.01, 0.01};
  struct Case {
    int copies;
    double effect;
    const char* over;
    const char* verdict;
  };
  for (const Case& k : {Case{6, 1.01, "program copies", "no detectable difference"}, Case{6, 1.06, "program copies", "slower"},
                        Case{5, 1.01, "rounds", "slower"},
                        // One copy: its placement (-2%) puts embree at 1.01 x 0.98 of sah-binned, and
                        // the rounds of that one program resolve it as a difference.
                        Case{1, 1.01, "rounds", "faster"}}) {
    SCOPED_TRACE(std::to_string(k.copies) + " copies, effect " + std::to_string(k.effect));
    const fs::path out = root / ("c" + std::to_string(k.copies) + "-" + std::to_string(int(k.effect * 100)));
    RunOptions o = groupOptions(kTwoBuilders, out);
    o.groupExecutor = copiesExecutor(k.copies, k.effect, placement);
    runSweep(o);
    const json findings = readJsonFile(out / "findings.json");
    const json& c = builderComparison(findings);
    EXPECT_EQ(c["interval_over"], k.over) << c.dump();
    EXPECT_EQ(c["verdict"], k.verdict) << c.dump();
    if (k.copies == 6) {
      // The session's shared-program control still sets the band: copies span code placements within
      // one process, not what differs between processes.
      EXPECT_EQ(c["band_source"], "shared control") << c.dump();
      EXPECT_GT(c["band"].get<double>(), 0.0);
      EXPECT_EQ(c["n"], 6);
      // [min, max] of the six per-copy ratios: the placements' whole spread.
      EXPECT_NEAR(c["ci_low"].get<double>(), k.effect * std::exp(-0.02), 0.003);
      EXPECT_NEAR(c["ci_high"].get<double>(), k.effect * std::exp(0.02), 0.003);
    }
  }
}

// The real child with program_copies = 6: six frame lists per run, the run's frames their median per
// round, findings across the copies; and the config refuses copies without interleaving.
TEST_F(MeasurementPrograms, RealProgramCopiesAreDrawnAndCombined) {
  RunOptions o = realOptions("program_copies = 6");
  ASSERT_EQ(runSweep(o).failed, 0u);
  for (const auto& [key, record] : readRecords(SweepDir{root / "out"})) {
    ASSERT_EQ(record["status"], "ok") << record.dump();
    const json& r = record["result"];
    EXPECT_EQ(r["program_copies"], 6);
    ASSERT_EQ(r["frame_ms_copies"].size(), 6u);
    for (const json& list : r["frame_ms_copies"]) EXPECT_EQ(list.size(), 6u);
    // The run's frame of round i is the median of the six copies' frames of round i.
    const std::vector<double> all = r["frame_ms_all"];
    ASSERT_EQ(all.size(), 6u);
    for (size_t i = 0; i < all.size(); ++i) {
      std::vector<double> round;
      for (const json& list : r["frame_ms_copies"]) round.push_back(list[i].get<double>());
      EXPECT_DOUBLE_EQ(all[i], medianOf(round));
    }
  }
  const json f = readJsonFile(root / "out" / "findings.json");
  ASSERT_FALSE(f["comparisons"].empty());
  for (const json& c : f["comparisons"]) EXPECT_EQ(c["interval_over"], "program copies") << c.dump();

  writeText(root / "bad.toml", "[measure]\nprogram_copies = 6\ninterleave = false\n[axes]\nscenes = \"a.off\"\n");
  try {
    loadExperimentConfig(root / "bad.toml", kNames);
    ADD_FAILURE() << "program_copies without interleave was accepted";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("bad.toml:2: measure.program_copies: needs interleave = true"), std::string::npos)
        << e.what();
  }
}
