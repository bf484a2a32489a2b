// Replicates (experiments/replicates.hpp): a sweep measured R times over, each group in a new process
// per pass, and every comparison pooled over the passes. Against a fake clock whose every process
// carries its own offset for one run (what code placement and machine state do on llvmpipe), with
// frames tight enough that one process alone would call that offset a difference.
#include <cmath>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "experiments/replicates.hpp"
#include "experiments/runner.hpp"
#include "experiments/sweep_dir.hpp"
#include "render/frame_stats.hpp"
#include "tests/test_experiments_fixture.hpp"

namespace fs = std::filesystem;
using namespace bvhlab;
using namespace bvhlab::experiments_test;
using nlohmann::json;

namespace {

// Every group execution is a process: the median-split run gets that process's offset (the list
// below, in order of execution) on top of its true ratio to sah-binned; frames share a per-round
// machine load and add 0.5% jitter each; the first run has an A/A control from the same process
// (which, like the real one, does not see the other run's offset).
struct ProcessClock {
  double medianRatio = 1.0;  // true median / sah-binned
  std::vector<double> offsets = {0.05, -0.02, 0.01, -0.03, 0.02, 0.0, 0.015, -0.01};
  int processes = 0;
  std::map<std::string, int> calls;
  std::string failKey;  // this run fails in every process

  json operator()(GroupRequest& g) {
    const double offset = offsets[size_t(processes) % offsets.size()];
    std::mt19937_64 rng(77 + processes++);
    std::normal_distribution<double> load(0.0, 0.2), jitter(0.0, 0.005);
    const int rounds = 40;
    std::vector<std::vector<double>> ms(g.runs.size() + 1);
    for (int r = 0; r < rounds; ++r) {
      const double machine = std::exp(load(rng));
      for (size_t i = 0; i < g.runs.size(); ++i) {
        const bool median = g.runs[i].spec.axis("builder")->value["name"] == "median";
        ms[i].push_back(10.0 * (median ? medianRatio * (1.0 + offset) : 1.0) * machine * std::exp(jitter(rng)));
      }
      const bool median0 = g.runs[0].spec.axis("builder")->value["name"] == "median";
      ms.back().push_back(10.0 * (median0 ? medianRatio * (1.0 + offset) : 1.0) * machine * std::exp(jitter(rng)));
    }
    json out = json::object();
    for (size_t i = 0; i < g.runs.size(); ++i) {
      const RunSpec& s = g.runs[i].spec;
      ++calls[s.key];
      if (s.key == failKey) {
        out[s.key] = {{"error", "shader failed to compile (fake)"}};
        continue;
      }
      const std::string builder = s.axis("builder")->value["name"];
      json r = fakeMeasuredRun(ms[i], g.session);
      r.update({{"program", 0},
                {"tree_hash", builder + "-tree"},
                {"sah_cost", builder == "median" ? 44.0 : 34.0},
                {"effective_depth", 1}});
      if (i == 0) r["aa_shared_control_frame_ms_all"] = ms.back();
      out[s.key] = r;
    }
    return out;
  }
};

// `experiment`: more [experiment] lines (replicates = R).
std::string twoBuilders(const std::string& experiment = "") {
  return "[experiment]\nname = \"replicates\"\n" + experiment + R"(
[axes]
scenes = "a.off"
builders = ["median", "sah-binned"]
kernels = "stack-ordered"
leaf_sizes = 4
)";
}

const json& builderComparison(const json& findings) {
  for (const json& c : findings["comparisons"])
    if (c["kind"] == "axis" && c["axis"] == "builder") return c;
  throw std::runtime_error("no builder comparison in findings.json");
}

class Replicates : public Experiments {
 protected:
  void SetUp() override {
    Experiments::SetUp();
    fs::copy_file(kFixtures / "quad.off", root / "a.off", fs::copy_options::overwrite_existing);
  }
  RunOptions sweep(const fs::path& out, ProcessClock& clock, const std::string& extra = "") {
    RunOptions o = sweepOptions(root / "cfg.toml", twoBuilders(extra), out, kNames);
    o.groupExecutor = [&clock](GroupRequest& g) { return clock(g); };
    return o;
  }
};

}  // namespace

TEST(ReplicateStems, NameTheReplicate) {
  EXPECT_EQ(replicateStem("0123456789abcdef", 0), "0123456789abcdef");
  EXPECT_EQ(replicateStem("0123456789abcdef", 12), "0123456789abcdef.r12");
  EXPECT_EQ(replicateOfStem("0123456789abcdef"), 0);
  EXPECT_EQ(replicateOfStem("0123456789abcdef.r12"), 12);
  EXPECT_EQ(replicateOfStem("0123456789abcdef.r0"), std::nullopt) << "replicate 0 is the bare key";
  EXPECT_EQ(replicateOfStem("0123456789abcdef.r"), std::nullopt);
  EXPECT_EQ(replicateOfStem("0123456789abcdef.r1x"), std::nullopt);
  EXPECT_EQ(replicateOfStem("0123456789abcdef.visits"), std::nullopt);
}

TEST(ReplicatePooling, FewReplicatesTakeTheHullAndTheWidestBandManyTheirOrderStatistics) {
  auto at = [](double estimate, double halfWidth) {
    return Interval{estimate, estimate - halfWidth, estimate + halfWidth, kConfidence, 40};
  };
  // Three replicates: median of the estimates, hull of the intervals, widest band.
  const auto three = poolReplicateRatios({{at(1.05, 0.004), 0.01}, {at(0.98, 0.004), 0.03}, {at(1.01, 0.004), 0.0}});
  ASSERT_TRUE(three);
  EXPECT_DOUBLE_EQ(three->ratio.estimate, 1.01);
  EXPECT_DOUBLE_EQ(three->ratio.low, 0.976);
  EXPECT_DOUBLE_EQ(three->ratio.high, 1.054);
  EXPECT_DOUBLE_EQ(three->band, 0.03);
  EXPECT_EQ(three->over, "replicates (hull)");
  EXPECT_EQ(three->ratio.n, 3u);

  // A replicate without an interval says nothing; fewer than two that do: no pooled ratio.
  EXPECT_FALSE(poolReplicateRatios({{at(1.05, 0.004), 0.0}, {std::nullopt, 0.5}}));
  const auto two = poolReplicateRatios({{at(1.05, 0.004), 0.0}, {std::nullopt, 0.5}, {at(1.07, 0.01), 0.02}});
  ASSERT_TRUE(two);
  EXPECT_DOUBLE_EQ(two->band, 0.02) << "the replicate without an interval does not lend its band";

  // Six: the order-statistic interval over the six estimates (ranks 1 and 6: [min, max]), no band.
  std::vector<ReplicateRatio> six;
  for (double e : {1.10, 1.06, 1.12, 1.08, 1.09, 1.11}) six.push_back({at(e, 0.001), 0.2});
  const auto pooled = poolReplicateRatios(six);
  ASSERT_TRUE(pooled);
  EXPECT_EQ(pooled->over, "replicates");
  EXPECT_DOUBLE_EQ(pooled->band, 0.0);
  EXPECT_DOUBLE_EQ(pooled->ratio.low, 1.06);
  EXPECT_DOUBLE_EQ(pooled->ratio.high, 1.12);
  EXPECT_DOUBLE_EQ(pooled->ratio.estimate, 1.095);
}

TEST_F(Replicates, AProcessOffsetThatOneReplicateCallsADifferenceIsNotCalledOverThree) {
  // One replicate: the first process's 5% offset, with tight paired frames, reads as a difference
  // (sah-binned "faster" than median, the baseline: the config's first builder).
  ProcessClock one;
  runSweep(sweep(root / "one", one));
  const json oneFindings = readJsonFile(root / "one" / "findings.json");
  const json& single = builderComparison(oneFindings);
  EXPECT_EQ(single["a_label"], "sah-binned");
  EXPECT_EQ(single["b_label"], "median");
  EXPECT_EQ(single["baseline"], true);
  EXPECT_EQ(single["verdict"], "faster") << single.dump();
  EXPECT_EQ(single["interval_over"], "rounds");

  // Three replicates (+5%, -2%, +1%): each process paired as before, the hull spans 1.
  ProcessClock three;
  const SweepOutcome o = runSweep(sweep(root / "three", three, "replicates = 3\n"));
  EXPECT_EQ(three.processes, 3);
  EXPECT_EQ(o.executed, 6u);
  const json f = readJsonFile(root / "three" / "findings.json");
  const json& c = builderComparison(f);
  EXPECT_EQ(c["interval_over"], "replicates (hull)");
  EXPECT_EQ(c["n"], 3);
  ASSERT_EQ(c["replicate_ratios"].size(), 3u);
  std::vector<double> ratios = c["replicate_ratios"];
  if (c["a_label"] == "sah-binned")  // sah-binned / median, the baseline
    for (double& r : ratios) r = 1.0 / r;
  std::sort(ratios.begin(), ratios.end());  // median / sah-binned: the offsets -2%, +1%, +5%
  EXPECT_NEAR(ratios[0], 0.98, 0.005);
  EXPECT_NEAR(ratios[2], 1.05, 0.005);
  EXPECT_LT(c["ci_low"].get<double>(), 1.0);
  EXPECT_GT(c["ci_high"].get<double>(), 1.0);
  EXPECT_EQ(c["verdict"], "no detectable difference") << c.dump();
  // Every replicate's controls are in the noise table, with their replicate.
  int withReplicate = 0;
  for (const json& n : f["noise"]) withReplicate += n.contains("replicate");
  EXPECT_EQ(f["noise"].size(), 3u);
  EXPECT_EQ(withReplicate, 3);

  // Rows: replicate 0's record, the pooled median and every replicate's row.
  const json rows = readJsonFile(root / "three" / "results.json")["rows"];
  ASSERT_EQ(rows.size(), 2u);
  for (const json& row : rows) {
    EXPECT_EQ(row["replicates"], 3);
    ASSERT_EQ(row["replicate_rows"].size(), 3u);
    std::vector<double> medians = row["frame_ms_replicates"];
    EXPECT_DOUBLE_EQ(row["frame_ms"].get<double>(), medianOf(medians));
    std::set<std::string> sessions;
    for (const json& r : row["replicate_rows"]) sessions.insert(r["session"].get<std::string>());
    EXPECT_EQ(sessions.size(), 3u) << "each replicate in its own process";
    EXPECT_TRUE(fs::exists(SweepDir{root / "three"}.record(row["key"], 2)));
  }
  const std::string csv = readText(root / "three" / "results.csv");
  EXPECT_NE(csv.find(",replicates,"), std::string::npos);
  EXPECT_EQ(csv.find("replicate_rows"), std::string::npos) << "nested rows stay out of the CSV";

  // The report says how the pooled comparisons read, and which replicate each control belongs to.
  const std::string html = readText(writeReport(root / "three"));
  EXPECT_NE(html.find("measured in 3 replicates"), std::string::npos);
  EXPECT_NE(html.find("3 replicates (hull)"), std::string::npos);
  EXPECT_NE(html.find(", replicate 2"), std::string::npos);
}

TEST_F(Replicates, ATrueDifferenceIsCalledOverThreeAndOverSixAcrossReplicates) {
  ProcessClock three;
  three.medianRatio = 1.10;
  runSweep(sweep(root / "three", three, "replicates = 3\n"));
  const json f3 = readJsonFile(root / "three" / "findings.json");
  const json& c3 = builderComparison(f3);
  EXPECT_EQ(c3["verdict"], "faster") << c3.dump();  // sah-binned / median (the baseline)
  EXPECT_EQ(c3["interval_over"], "replicates (hull)");

  ProcessClock six;
  six.medianRatio = 1.10;
  runSweep(sweep(root / "six", six, "replicates = 6\n"));
  const json f6 = readJsonFile(root / "six" / "findings.json");
  const json& c6 = builderComparison(f6);
  EXPECT_EQ(c6["interval_over"], "replicates");
  EXPECT_EQ(c6["band"], 0.0);
  std::vector<double> ratios = c6["replicate_ratios"];
  ASSERT_EQ(ratios.size(), 6u);
  EXPECT_DOUBLE_EQ(c6["ci_low"].get<double>(), *std::min_element(ratios.begin(), ratios.end()));
  EXPECT_DOUBLE_EQ(c6["ci_high"].get<double>(), *std::max_element(ratios.begin(), ratios.end()));
  EXPECT_NEAR(1.0 / c6["ratio"].get<double>(), 1.10 * 1.005, 0.01);
  EXPECT_EQ(c6["verdict"], "faster");
}

TEST_F(Replicates, ResumeMeasuresOnlyMissingReplicatesAndMoreReplicatesAddPasses) {
  ProcessClock clock;
  runSweep(sweep(root / "out", clock, "replicates = 2\n"));
  EXPECT_EQ(clock.processes, 2);
  const SweepOutcome again = runSweep(sweep(root / "out", clock, "replicates = 2\n"));
  EXPECT_EQ(again.executed, 0u);
  EXPECT_EQ(again.skipped, 4u);
  EXPECT_EQ(clock.processes, 2);

  // The flag overrides the config: two more passes, the first two kept.
  RunOptions more = sweep(root / "out", clock, "replicates = 2\n");
  more.replicates = 4;
  const SweepOutcome o = runSweep(more);
  EXPECT_EQ(o.executed, 4u);
  EXPECT_EQ(clock.processes, 4);
  const auto replicas = readReplicateRecords(SweepDir{root / "out"});
  ASSERT_EQ(replicas.size(), 2u);
  for (const auto& [key, byReplicate] : replicas) {
    ASSERT_EQ(byReplicate.size(), 3u) << key;
    for (const auto& [r, record] : byReplicate) EXPECT_EQ(record["replicate"], r);
  }
  EXPECT_EQ(readRecords(SweepDir{root / "out"}).size(), 2u) << "replicate files are not runs of their own";
  EXPECT_EQ(readJsonFile(root / "out" / "results.json")["summary"]["replicate_runs"], 6);
}

TEST_F(Replicates, ARunThatFailsInReplicateZeroIsNotMeasuredAgainInTheOthers) {
  ProcessClock clock;
  const ExperimentConfig cfg = parse(twoBuilders("replicates = 3\n"));
  for (const RunSpec& r : cfg.runs)
    if (r.axis("builder")->value["name"] == "median") clock.failKey = r.key;
  runSweep(sweep(root / "out", clock, "replicates = 3\n"));
  EXPECT_EQ(clock.calls[clock.failKey], 1);
  const json rows = readJsonFile(root / "out" / "results.json")["rows"];
  ASSERT_EQ(rows.size(), 2u);
  for (const json& row : rows) {
    if (row["key"] == clock.failKey) {
      EXPECT_EQ(row["status"], "failed");
      EXPECT_FALSE(row.contains("replicate_rows"));
    } else {
      EXPECT_EQ(row["replicates"], 3);
    }
  }
  EXPECT_EQ(readReplicateRecords(SweepDir{root / "out"}).count(clock.failKey), 0u);
}

TEST_F(Replicates, MergeAsReplicatesAppendsEachDirectorysPasses) {
  ProcessClock first, second;
  first.medianRatio = second.medianRatio = 1.10;
  second.offsets = {-0.01};
  RunOptions a = sweep(root / "a", first);  // one config (one hash): --replicates on the command line
  a.replicates = 2;
  runSweep(a);
  runSweep(sweep(root / "b", second));
  mergeSweeps({root / "a", root / "b"}, root / "ab", true);
  const auto replicas = readReplicateRecords(SweepDir{root / "ab"});
  ASSERT_EQ(replicas.size(), 2u);
  for (const auto& [key, byReplicate] : replicas) {
    ASSERT_EQ(byReplicate.size(), 2u);
    // b's replicate 0 became replicate 2 of the merge.
    const json b0 = readJsonFile(SweepDir{root / "b"}.record(key));
    EXPECT_EQ(byReplicate.at(2)["session"], b0["session"]);
    EXPECT_EQ(byReplicate.at(2)["replicate"], 2);
  }
  const json merged = readJsonFile(root / "ab" / "findings.json");
  const json& c = builderComparison(merged);
  EXPECT_EQ(c["n"], 3);
  EXPECT_EQ(c["interval_over"], "replicates (hull)");

  // Merging replicates into an existing sweep would count them twice.
  EXPECT_THROW(mergeSweeps({root / "b"}, root / "ab", true), InputError);
  // A plain merge keeps replicates where they are.
  mergeSweeps({root / "a"}, root / "copy");
  for (const auto& [key, byReplicate] : readReplicateRecords(SweepDir{root / "copy"}))
    EXPECT_EQ(byReplicate.size(), 1u) << key;
  EXPECT_EQ(readJsonFile(root / "copy" / "findings.json")["comparisons"][0]["n"], 2);
}

TEST_F(Replicates, TheConfigKeyIsChecked) {
  EXPECT_EQ(parse(twoBuilders("replicates = 4\n")).replicates, 4);
  EXPECT_EQ(parse(twoBuilders()).replicates, 1);
  try {
    parse(twoBuilders("replicates = 0\n"));
    FAIL() << "replicates = 0 accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("experiment.replicates"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("cfg.toml:"), std::string::npos) << e.what();
  }
}
