// Verdicts that can fail when they should (experiments/findings.hpp, docs/measurement.md): no verdict
// without a noise band, the multiple-comparison adjustment, fixed baselines, intervals that hold under
// autocorrelated rounds, and a fake clock with drift and AR(1) noise that checks the whole rule both
// ways (identical configurations are rarely called, a real 10% difference is).
#include <cmath>
#include <map>
#include <random>

#include "experiments/findings.hpp"
#include "experiments/findings_adjust.hpp"
#include "experiments/findings_command.hpp"
#include "test_experiments_fixture.hpp"

using namespace bvhlab::experiments_test;

namespace {

// ---- a fake clock ------------------------------------------------------------------------------------
// One process's rounds: every run's frame in round t is base * exp(drift_t + own_t + jitter), where
// drift_t is shared by all runs of the process (the machine: a slow ramp plus an AR(1) wander), own_t
// an AR(1) series of the run's own (what lasts longer than a round for one run) and jitter i.i.d.
struct FakeClock {
  double phi = 0.8;         // AR(1) coefficient of each run's own series
  double sigma = 0.01;      // its innovation sd (log scale)
  double jitter = 0.005;    // i.i.d. sd per frame (log scale)
  double ramp = 0.2;        // drift over the whole process (log scale): cancels in paired ratios
  int rounds = 200;
  std::mt19937_64 rng;

  explicit FakeClock(uint64_t seed) : rng(seed) {}
  double normal() { return std::normal_distribution<double>(0.0, 1.0)(rng); }
  std::vector<double> drift() {
    std::vector<double> d(static_cast<size_t>(rounds));
    double w = 0.0;
    for (int t = 0; t < rounds; ++t) {
      w = 0.95 * w + 0.02 * normal();
      d[size_t(t)] = ramp * double(t) / double(rounds) + w;
    }
    return d;
  }
  std::vector<double> series(double baseMs, const std::vector<double>& drift) {
    std::vector<double> out;
    double own = sigma / std::sqrt(1.0 - phi * phi) * normal();  // start in the stationary law
    for (int t = 0; t < rounds; ++t) {
      own = phi * own + sigma * normal();
      out.push_back(baseMs * std::exp(drift[size_t(t)] + own + jitter * normal()));
    }
    return out;
  }
};

json rowOf(const std::string& key, const std::string& builder, const std::string& session,
           const std::vector<double>& frames) {
  std::vector<double> sorted = frames;
  std::sort(sorted.begin(), sorted.end());
  return {{"key", key},           {"status", "ok"},      {"scene", "s"},       {"builder", builder},
          {"kernel", "k"},        {"session", session},  {"program", 0},       {"frame_ms_all", frames},
          {"frame_ms", sorted[sorted.size() / 2]}};
}

// `configs` identical configurations (b0 .. b{configs-1}) measured in one process, each `slower[i]`
// times its base time; the first run carries a shared-program A/A control (when `control`).
json oneProcess(FakeClock& clock, int configs, const std::vector<double>& factor, bool control,
                const std::string& session = "g0") {
  const std::vector<double> drift = clock.drift();
  json rows = json::array();
  for (int i = 0; i < configs; ++i) {
    const std::string b = "b" + std::to_string(i);
    json row = rowOf(session + "-" + b, b, session, clock.series(20.0 * factor[size_t(i)], drift));
    if (control && i == 0) row["aa_shared_control_frame_ms_all"] = clock.series(20.0, drift);
    rows.push_back(std::move(row));
  }
  return rows;
}

size_t countVerdict(const json& f, const std::string& verdict) {
  size_t n = 0;
  for (const json& c : f["comparisons"]) n += c["verdict"] == verdict;
  return n;
}

const json kNoOrder = json::object();

TEST(FindingsCalibration, IdenticalConfigurationsUnderDriftAndAr1AreRarelyCalledAndATenPercentDifferenceIs) {
  constexpr int kConfigs = 20, kProcesses = 10;
  size_t pairs = 0, directional = 0;
  for (int p = 0; p < kProcesses; ++p) {
    FakeClock clock(1000 + uint64_t(p));
    const json f = computeFindings(oneProcess(clock, kConfigs, std::vector<double>(kConfigs, 1.0), true), kNoOrder);
    for (const json& c : f["comparisons"]) {
      if (c["kind"] != "axis") continue;
      ++pairs;
      directional += c["verdict"] == "faster" || c["verdict"] == "slower";
      EXPECT_TRUE(c["p_value"].is_number()) << c.dump();
    }
  }
  ASSERT_EQ(pairs, size_t(kProcesses * (kConfigs - 1)));
  std::printf("identical pairs called faster or slower: %zu of %zu\n", directional, pairs);
  EXPECT_LE(double(directional) / double(pairs), 0.05) << directional << " of " << pairs << " identical pairs called";

  // The same processes with b7 10% slower: called every time, and nothing else is.
  size_t called = 0, others = 0;
  for (int p = 0; p < kProcesses; ++p) {
    FakeClock clock(1000 + uint64_t(p));
    std::vector<double> factor(kConfigs, 1.0);
    factor[7] = 1.10;
    const json f = computeFindings(oneProcess(clock, kConfigs, factor, true), kNoOrder);
    for (const json& c : f["comparisons"]) {
      if (c["kind"] != "axis") continue;
      const bool dir = c["verdict"] == "faster" || c["verdict"] == "slower";
      if (c["a_label"] == "b7") called += c["verdict"] == "slower";
      else others += dir;
    }
  }
  EXPECT_EQ(called, size_t(kProcesses)) << "a real 10% difference must be called slower in every process";
  EXPECT_LE(double(others) / double(kProcesses * (kConfigs - 2)), 0.05);
}

// ---- no verdict without a band -----------------------------------------------------------------------
TEST(FindingsBands, InterleaveFalseAndNoControlSweepsIssueNoDirectionalVerdict) {
  FakeClock clock(7);
  const std::vector<double> factor = {1.0, 1.3, 0.7, 1.0};  // large differences: called when a band exists
  // aa_control = false: one session, no control.
  const json noControl = computeFindings(oneProcess(clock, 4, factor, false), kNoOrder);
  // interleave = false: every run its own process (its own session), no control.
  json isolated = json::array();
  for (int i = 0; i < 4; ++i) {
    json one = oneProcess(clock, 1, {factor[size_t(i)]}, false, "p" + std::to_string(i));
    one[0]["builder"] = "b" + std::to_string(i);
    isolated.push_back(one[0]);
  }
  const json alone = computeFindings(isolated, kNoOrder);
  // interleave = false with each process's own A/A control: within-session bands do not cover a
  // comparison between sessions.
  json isolatedWithControls = isolated;
  for (json& r : isolatedWithControls) r["aa_shared_control_frame_ms_all"] = r["frame_ms_all"];
  const json crossSession = computeFindings(isolatedWithControls, kNoOrder);
  for (const json* f : {&noControl, &alone, &crossSession}) {
    ASSERT_GE((*f)["comparisons"].size(), 3u);
    for (const json& c : (*f)["comparisons"]) {
      EXPECT_EQ(c["verdict"], "not called: no noise band") << c.dump();
      EXPECT_TRUE(c["band"].is_null());
      EXPECT_TRUE(c["p_value"].is_null());
    }
    EXPECT_EQ((*f)["adjustment"]["tests"], 0);
  }
  // The same rows with a control are called (the rule above is not vacuous).
  FakeClock again(7);
  const json withControl = computeFindings(oneProcess(again, 4, factor, true), kNoOrder);
  // b1 slower and b2 faster, each along builder and as builder-best.
  EXPECT_EQ(countVerdict(withControl, "slower"), 2u) << withControl.dump(1);
  EXPECT_EQ(countVerdict(withControl, "faster"), 2u) << withControl.dump(1);
}

TEST(FindingsBands, ReplicatesGiveABandAcrossProcesses) {
  // Six replicates, each its own process without a control, b1 20% slower: pooled across the
  // replicates (band 0, measured across processes), so called.
  json b0 = rowOf("k0", "b0", "r0", {1}), b1 = rowOf("k1", "b1", "r0", {1});
  b0["replicate_rows"] = json::array();
  b1["replicate_rows"] = json::array();
  for (int r = 0; r < 6; ++r) {
    FakeClock clock(50 + uint64_t(r));
    json rows = oneProcess(clock, 2, {1.0, 1.2}, false, "r" + std::to_string(r));
    for (json& x : rows) x["replicate"] = r;
    b0["replicate_rows"].push_back(rows[0]);
    b1["replicate_rows"].push_back(rows[1]);
  }
  b0["frame_ms"] = 20.0;
  b1["frame_ms"] = 24.0;
  const json f = computeFindings(json::array({b0, b1}), kNoOrder);
  ASSERT_EQ(f["comparisons"].size(), 2u);  // along builder, and builder-best
  for (const json& c : f["comparisons"]) {
    EXPECT_EQ(c["interval_over"], "replicates");
    EXPECT_EQ(c["band_source"], "replicates");
    EXPECT_EQ(c["verdict"], "slower") << c.dump();
  }
  // Three replicates (the hull, each replicate's own band): none has a control, so not called.
  for (json* row : {&b0, &b1})
    while ((*row)["replicate_rows"].size() > 3) (*row)["replicate_rows"].erase(3);
  const json hull = computeFindings(json::array({b0, b1}), kNoOrder);
  ASSERT_EQ(hull["comparisons"].size(), 2u) << hull.dump();
  for (const json& c : hull["comparisons"]) {
    EXPECT_EQ(c["interval_over"], "replicates (hull)");
    EXPECT_EQ(c["verdict"], "not called: no noise band") << c.dump();
  }
}

// ---- multiple comparisons ----------------------------------------------------------------------------
TEST(FindingsAdjustment, HolmAndBenjaminiHochbergOnKnownPValues) {
  const std::vector<double> p = {0.01, 0.04, 0.03, 0.005};
  // BH, N = 4, sorted 0.005 0.01 0.03 0.04: N p / rank = 0.02 0.02 0.04 0.04, running minimum from the top.
  const std::vector<double> bh = adjustBenjaminiHochberg(p);
  const std::vector<double> bhExpected = {0.02, 0.04, 0.04, 0.02};
  // Holm: (N - rank + 1) p = 0.02 0.03 0.06 0.04, running maximum from the bottom.
  const std::vector<double> holm = adjustHolm(p);
  const std::vector<double> holmExpected = {0.03, 0.06, 0.06, 0.02};
  for (size_t i = 0; i < p.size(); ++i) {
    EXPECT_NEAR(bh[i], bhExpected[i], 1e-12) << i;
    EXPECT_NEAR(holm[i], holmExpected[i], 1e-12) << i;
  }
  // Capped at 1; NaN counts as 1 and never helps.
  const std::vector<double> odd = adjustBenjaminiHochberg(std::vector<double>{0.6, std::nan(""), 0.001});
  EXPECT_NEAR(odd[0], 0.9, 1e-12);
  EXPECT_EQ(odd[1], 1.0);
  EXPECT_NEAR(odd[2], 0.003, 1e-12);
  EXPECT_EQ(adjustHolm(std::vector<double>{0.6, 0.5})[0], 1.0);
}

TEST(FindingsAdjustment, TheFileCarriesTheAdjustmentAndVerdictsAgreeWithIntervals) {
  FakeClock clock(11);
  std::vector<double> factor(12, 1.0);
  factor[3] = 1.1;
  factor[5] = 0.9;
  const json f = computeFindings(oneProcess(clock, 12, factor, true), kNoOrder);
  EXPECT_EQ(f["format"], 2);
  const json& adj = f["adjustment"];
  EXPECT_EQ(adj["method"], "benjamini-hochberg");
  EXPECT_EQ(adj["alpha"], 0.05);
  size_t tests = 0, directional = 0;
  for (const json& c : f["comparisons"]) {
    ASSERT_TRUE(c.contains("p_value") && c.contains("p_adjusted")) << c.dump();
    if (!c["p_value"].is_number()) continue;
    ++tests;
    EXPECT_GE(c["p_adjusted"].get<double>(), c["p_value"].get<double>());
    const double band = c["band"].get<double>();
    if (c["verdict"] == "slower" || c["verdict"] == "faster") {
      ++directional;
      EXPECT_LE(c["p_adjusted"].get<double>(), 0.05);
      if (c["verdict"] == "slower") EXPECT_GT(c["ci_low"].get<double>(), std::exp(band)) << c.dump();
      else EXPECT_LT(c["ci_high"].get<double>(), std::exp(-band)) << c.dump();
    } else {
      EXPECT_GT(c["p_adjusted"].get<double>(), 0.05) << c.dump();
    }
  }
  EXPECT_EQ(adj["tests"], tests);
  EXPECT_EQ(adj["directional"], directional);
  EXPECT_EQ(directional, 4u) << "b3 slower and b5 faster, each along builder and as builder-best";
  EXPECT_NEAR(adj["expected_by_chance"].get<double>(), 0.05 * double(directional), 1e-12);
  // The noise entry carries the control's lag-1 autocorrelation (AR(1) with phi 0.8 in both series).
  ASSERT_EQ(f["noise"].size(), 1u);
  EXPECT_GT(f["noise"][0]["lag1_autocorrelation"].get<double>(), 0.3) << f["noise"][0].dump();
}

// ---- fixed baselines ---------------------------------------------------------------------------------
TEST(FindingsBaselines, TheBaselineIsTheConfigsFirstValueOrItsChoiceNeverTheFastest) {
  FakeClock clock(3);
  json rows = oneProcess(clock, 3, {1.3, 1.0, 1.1}, true);  // b0 (first in config order) is the slowest
  const json order = {{"builder", {"b0", "b1", "b2"}}};
  const json f = computeFindings(rows, order);
  EXPECT_EQ(f["baselines"]["builder"], "b0");
  size_t axis = 0;
  for (const json& c : f["comparisons"]) {
    EXPECT_EQ(c["b_label"], "b0") << c.dump();
    EXPECT_EQ(c["baseline"], true);
    EXPECT_EQ(c["b_values"], (json{{"builder", "b0"}, {"kernel", "k"}}));
    EXPECT_EQ(c["a_values"]["builder"], c["a_label"]);
    EXPECT_EQ(c["fastest"]["label"], "b1");
    axis += c["kind"] == "axis";
  }
  EXPECT_EQ(axis, 2u);
  // The config's [findings] baseline overrides the order.
  const json chosen = computeFindings(rows, order, json{{"builder", "b2"}});
  EXPECT_EQ(chosen["baselines"]["builder"], "b2");
  for (const json& c : chosen["comparisons"]) EXPECT_EQ(c["b_label"], "b2") << c.dump();
  // Config order, not row order: b1 listed first.
  const json reordered = computeFindings(rows, json{{"builder", {"b1", "b0", "b2"}}});
  for (const json& c : reordered["comparisons"]) EXPECT_EQ(c["b_label"], "b1") << c.dump();
}

// Kernels are nested in layouts: in a layout the kernel baseline does not walk, its kernels are compared
// with its first kernel in config order; and the layout comparison takes each layout at that kernel.
TEST(FindingsBaselines, KernelsOfALayoutWithoutTheBaselineKernelAreComparedWithItsFirstKernel) {
  FakeClock clock(5);
  json rows = oneProcess(clock, 4, {1.0, 1.2, 0.8, 1.1}, true);
  const std::vector<std::pair<std::string, std::string>> runs = {
      {"v1", "ko"}, {"v1", "ku"}, {"w8", "new"}, {"w8", "old"}};
  for (size_t i = 0; i < runs.size(); ++i) {
    rows[i]["builder"] = "b";
    rows[i]["layout"] = runs[i].first;
    rows[i]["kernel"] = runs[i].second;
  }
  const json order = {{"layout", {"v1", "w8"}}, {"kernel", {"ko", "ku", "new", "old"}}};
  const json f = computeFindings(rows, order);
  std::map<std::string, std::string> kernelPairs;  // a_label -> b_label on the kernel axis
  std::vector<std::string> layoutPairs;
  for (const json& c : f["comparisons"]) {
    if (c["kind"] != "axis") continue;
    if (c["axis"] == "kernel") kernelPairs[c["a_label"]] = c["b_label"];
    if (c["axis"] == "layout") layoutPairs.push_back(c["a_values"]["kernel"].get<std::string>() + "/" +
                                                     c["b_values"]["kernel"].get<std::string>());
  }
  EXPECT_EQ(kernelPairs, (std::map<std::string, std::string>{{"ku", "ko"}, {"old", "new"}})) << f.dump();
  EXPECT_EQ(layoutPairs, (std::vector<std::string>{"new/ko"})) << f.dump();
  // Listing the old kernel first makes it w8's reference instead.
  const json reordered = computeFindings(rows, json{{"layout", {"v1", "w8"}}, {"kernel", {"ko", "ku", "old", "new"}}});
  bool found = false;
  for (const json& c : reordered["comparisons"])
    if (c["kind"] == "axis" && c["axis"] == "kernel" && c["a_label"] == "new") found = c["b_label"] == "old";
  EXPECT_TRUE(found) << reordered.dump();
}

TEST_F(Experiments, FindingsBaselineIsValidatedWithFileLineAndKey) {
  writeText(root / "m.off", "OFF\n0 0 0\n");
  const std::string head = "[axes]\nscenes = \"m.off\"\nbuilders = [\"median\", \"sah-binned\"]\n"
                           "kernels = \"stack-ordered\"\n";
  EXPECT_EQ(parse(head + "[findings]\nbaseline = { builder = \"sah-binned\" }\n").findingsBaseline.at("builder"),
            "sah-binned");
  const std::pair<std::string, std::string> bad[] = {
      {"[findings]\nbaseline = { builder = \"sbvh\" }\n", "cfg.toml:6: findings.baseline.builder: 'sbvh' is not a value"},
      {"[findings]\nbaseline = { leaf_size = 8 }\n", "cfg.toml:6: findings.baseline.leaf_size: '8' is not a value of the leaf_size axis"},
      {"[findings]\nbaseline = { colour = \"red\" }\n", "cfg.toml:6: findings.baseline.colour: not an axis"},
      {"[findings]\nbaseline = { scene = \"m\" }\n", "cfg.toml:6: findings.baseline.scene: not an axis"},
      {"[findings]\nbaselines = { builder = \"median\" }\n", "cfg.toml:6: findings.baselines: unknown key"},
      {"[findings]\nbaseline = \"median\"\n", "cfg.toml:6: findings.baseline"},
  };
  for (const auto& [text, expected] : bad) {
    try {
      parse(head + text);
      ADD_FAILURE() << "expected an InputError for " << text;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  }
}

// ---- autocorrelated rounds ---------------------------------------------------------------------------
TEST(FindingsIntervals, BlockBootstrapIsWiderThanIidUnderStrongAr1AndCoversWhereIidDoesNot) {
  constexpr int kSeries = 200, kRounds = 300;
  constexpr double kPhi = 0.9;
  std::mt19937_64 rng(99);
  std::normal_distribution<double> z(0.0, 1.0);
  int coveredBlock = 0, coveredIid = 0, longBlocks = 0;
  double widthRatio = 0.0;
  for (int s = 0; s < kSeries; ++s) {
    // Per-round log ratios: AR(1), true median 0 (the law is symmetric about 0).
    std::vector<double> a, b;
    double x = z(rng) / std::sqrt(1.0 - kPhi * kPhi);
    for (int t = 0; t < kRounds; ++t) {
      x = kPhi * x + z(rng);
      a.push_back(std::exp(0.01 * x));
      b.push_back(1.0);
    }
    const auto block = pairedRatioBlock(a, b, uint64_t(s));
    const auto iid = pairedRatio(a, b);
    ASSERT_TRUE(block && iid);
    coveredBlock += block->low <= 1.0 && 1.0 <= block->high;
    coveredIid += iid->low <= 1.0 && 1.0 <= iid->high;
    widthRatio += std::log(block->high / block->low) / std::log(iid->high / iid->low) / kSeries;
    longBlocks += block->block > 10;
  }
  EXPECT_EQ(longBlocks, kSeries) << "the block length follows the autocorrelation (rho 0.9: about 30 rounds)";
  std::printf("coverage of 95%% intervals over %d AR(1) series (phi %.1f, %d rounds): block %d, iid %d; width block/iid %.2f\n",
              kSeries, kPhi, kRounds, coveredBlock, coveredIid, widthRatio);
  EXPECT_GT(widthRatio, 2.0);
  // Nominal 95%: at phi 0.9 the block bootstrap's interval (se from ~10 blocks of ~30 rounds) covered
  // 169 of 200 here, the i.i.d. one, about a third as wide, 82 (docs/measurement.md).
  EXPECT_GE(coveredBlock, int(0.80 * kSeries)) << coveredBlock;
  EXPECT_LT(coveredIid, int(0.60 * kSeries)) << coveredIid;
}

TEST(FindingsIntervals, BandTestsAgreeWithTheirIntervals) {
  // Normal: the interval logEstimate +- z se lies above the band exactly when p < 0.05.
  for (double est : {0.02, 0.05, 0.07, 0.09, -0.09}) {
    const double se = 0.02, band = 0.03;
    const BandTest t = normalBandTest(est, se, band);
    const bool outside = est - kZ95 * se > band || est + kZ95 * se < -band;
    EXPECT_EQ(t.p() < 0.05, outside) << est;
    if (outside) {
      EXPECT_EQ(t.slowerSide(), est > 0) << est;
    }
  }
  EXPECT_EQ(normalBandTest(std::nan(""), 0.01, 0.0).p(), 1.0);
  // Sign test: the dual of the order-statistic interval (n = 8: [x_(1), x_(8)], coverage 99.2%).
  const std::vector<double> values = {0.05, 0.06, 0.07, 0.08, 0.09, 0.10, 0.11, 0.12};
  const auto interval = medianInterval(values);
  ASSERT_TRUE(interval);
  for (double band : {0.0, 0.04, 0.049, 0.05, 0.08}) {
    const BandTest t = signBandTest(values, band);
    EXPECT_EQ(t.p() < 0.05, interval->low > band) << band;
  }
}

}  // namespace

// `bvhlab findings DIR --check`: the committed result directories under docs/results/ quote ratios,
// intervals and verdicts from their findings.json; each must follow from the per-round times in its
// results.json with the current rules, and a changed round must be caught.
TEST(FindingsCommand, CommittedFindingsFollowFromTheirRoundsAndAChangedRoundIsCaught) {
  const fs::path docs = fs::path(BVHLAB_SOURCE_DIR) / "docs" / "results";
  int checked = 0;
  for (const auto& entry : fs::directory_iterator(docs)) {
    if (!fs::exists(entry.path() / "results.json") || !fs::exists(entry.path() / "findings.json")) continue;
    EXPECT_EQ(findingsCommand(entry.path(), true), 0) << entry.path();
    ++checked;
  }
  EXPECT_GE(checked, 2) << "docs/results/ has fewer result directories with findings than the docs quote";

  const fs::path dir = fs::temp_directory_path() / ("bvhlab_findings_cmd_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  for (const char* f : {"results.json", "findings.json"}) fs::copy_file(docs / "sbvh-knobs" / f, dir / f);
  EXPECT_EQ(findingsCommand(dir, true), 0);
  nlohmann::json results = nlohmann::json::parse(std::ifstream(dir / "results.json"));
  bool changed = false;
  for (auto& row : results["rows"])
    if (row.contains("frame_ms_all") && row["frame_ms_all"].size() >= 6 && !changed) {
      for (auto& v : row["frame_ms_all"]) v = v.get<double>() * 1.01;
      changed = true;
    }
  ASSERT_TRUE(changed);
  std::ofstream(dir / "results.json") << results.dump(1);
  EXPECT_EQ(findingsCommand(dir, true), 1) << "a run 1% slower in every round left findings.json unchanged";
  EXPECT_EQ(findingsCommand(dir, false), 0);  // rewritten from the rows: now it follows
  EXPECT_EQ(findingsCommand(dir, true), 0);
  fs::remove_all(dir);
}

TEST(FindingsCommand, FirstJsonDifferenceNamesThePathAndToleratesOnlyLastBits) {
  using nlohmann::json;
  const json a = {{"comparisons", {{{"ratio", 1.0}, {"verdict", "faster"}}}}};
  EXPECT_FALSE(firstJsonDifference(a, a, 1e-9));
  json b = a;
  b["comparisons"][0]["ratio"] = 1.0 + 1e-12;
  EXPECT_FALSE(firstJsonDifference(a, b, 1e-9));
  b["comparisons"][0]["ratio"] = 1.001;
  const auto d = firstJsonDifference(a, b, 1e-9);
  ASSERT_TRUE(d);
  EXPECT_NE(d->find("comparisons[0].ratio"), std::string::npos) << *d;
  b = a;
  b["comparisons"][0]["verdict"] = "slower";
  EXPECT_TRUE(firstJsonDifference(a, b, 1e-9));
  b = a;
  b["comparisons"][0]["ratio"] = std::nan("");
  EXPECT_TRUE(firstJsonDifference(b, b, 1e-9)) << "a NaN never agrees";
}
