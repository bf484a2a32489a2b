// render/frame_stats.hpp: the intervals every comparison in the reports rests on, checked against
// distributions whose median is known, and the exact binomial ranks against hand-computed ones.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "experiments/bench/across_processes.hpp"
#include "render/frame_stats.hpp"

using namespace bvhlab;

namespace {

// Lognormal frame times: skewed like llvmpipe's, with median exp(mu) exactly.
std::vector<double> lognormal(std::mt19937_64& rng, size_t n, double median, double sigma) {
  std::normal_distribution<double> normal(0.0, sigma);
  std::vector<double> v(n);
  for (double& x : v) x = median * std::exp(normal(rng));
  return v;
}

}  // namespace

TEST(FrameStats, OrderStatisticRanksAreTheExactBinomialOnes) {
  // n = 5: even [min, max] covers 1 - 2/32 = 0.9375 < 0.95: no interval.
  EXPECT_FALSE(medianIntervalRanks(5).has_value());
  // n = 6: [x1, x6] covers 1 - 2/64 = 0.96875.
  auto r6 = medianIntervalRanks(6);
  ASSERT_TRUE(r6);
  EXPECT_EQ(r6->lower, 1u);
  EXPECT_EQ(r6->upper, 6u);
  EXPECT_NEAR(r6->coverage, 1.0 - 2.0 / 64.0, 1e-12);
  // n = 10: P(B <= 1) = 11/1024, so k = 2 covers 1 - 22/1024 = 0.9785; k = 3 would cover
  // 1 - 2 * 56/1024 = 0.8906.
  auto r10 = medianIntervalRanks(10);
  ASSERT_TRUE(r10);
  EXPECT_EQ(r10->lower, 2u);
  EXPECT_EQ(r10->upper, 9u);
  EXPECT_NEAR(r10->coverage, 1.0 - 22.0 / 1024.0, 1e-12);
  // n = 100: the textbook ranks are 40 and 61 (coverage 0.9648).
  auto r100 = medianIntervalRanks(100);
  ASSERT_TRUE(r100);
  EXPECT_EQ(r100->lower, 40u);
  EXPECT_EQ(r100->upper, 61u);
  EXPECT_GE(r100->coverage, 0.95);
  EXPECT_LT(r100->coverage, 0.97);
}

TEST(FrameStats, MedianIntervalCoversTheTrueMedianAtLeast95PercentOfTheTime) {
  std::mt19937_64 rng(12345);
  for (size_t n : {6u, 10u, 25u, 60u}) {
    int covered = 0, trials = 4000;
    double width = 0.0;
    for (int t = 0; t < trials; ++t) {
      const std::vector<double> v = lognormal(rng, n, 20.0, 0.1);
      const auto ci = medianInterval(v);
      ASSERT_TRUE(ci);
      ASSERT_LE(ci->low, ci->estimate);
      ASSERT_GE(ci->high, ci->estimate);
      covered += ci->low <= 20.0 && 20.0 <= ci->high;
      width += (ci->high - ci->low) / 20.0;
    }
    const double rate = double(covered) / trials;
    // The interval is exact-or-conservative: coverage >= 95% up to sampling error (sd of the rate
    // over 4000 trials is ~0.35%), and not absurdly wide (the exact coverage is below 0.97 for n >= 10).
    EXPECT_GE(rate, 0.94) << "n = " << n;
    EXPECT_LE(rate, 0.99) << "n = " << n;
    // Normal theory: 2 * 1.96 * 1.2533 * 0.1 / sqrt(60) = 6.3% of the median; order statistics are a
    // little wider (conservative ranks).
    if (n == 60) {
      EXPECT_LT(width / trials, 0.08) << "a 60-frame interval of a 10% spread should be ~6-7%";
    }
  }
}

TEST(FrameStats, MedianIntervalIgnoresNonFiniteValuesAndNeedsSix) {
  std::vector<double> v = {1, 2, 3, 4, 5, std::nan(""), INFINITY};
  EXPECT_FALSE(medianInterval(v).has_value()) << "5 finite values are too few";
  v.push_back(6);
  const auto ci = medianInterval(v);
  ASSERT_TRUE(ci);
  EXPECT_EQ(ci->n, 6u);
  EXPECT_DOUBLE_EQ(ci->estimate, 3.5);
  EXPECT_DOUBLE_EQ(ci->low, 1.0);
  EXPECT_DOUBLE_EQ(ci->high, 6.0);
}

TEST(FrameStats, PairedRatioRecoversAKnownEffectUnderSharedDrift) {
  // B takes 1.10x A's time; both ride the same drifting machine (a slow ramp plus per-round load)
  // and each adds its own 1% jitter. Pairing cancels the drift: the interval must cover 1.10 and be
  // narrow, while the unpaired interval of the same frames is wide.
  std::mt19937_64 rng(7);
  std::normal_distribution<double> jitter(0.0, 0.01), load(0.0, 0.15);
  int covered = 0;
  const int trials = 1000;
  double pairedWidth = 0.0, unpairedWidth = 0.0;
  for (int t = 0; t < trials; ++t) {
    std::vector<double> a, b;
    for (int i = 0; i < 40; ++i) {
      const double machine = (1.0 + 0.01 * i) * std::exp(load(rng));
      a.push_back(10.0 * machine * std::exp(jitter(rng)));
      b.push_back(11.0 * machine * std::exp(jitter(rng)));
    }
    const auto p = pairedRatio(b, a);
    ASSERT_TRUE(p);
    covered += p->low <= 1.1 && 1.1 <= p->high;
    pairedWidth += p->high - p->low;
    if (t < 50) {
      const auto u = unpairedRatio(b, a, uint64_t(t));
      ASSERT_TRUE(u);
      unpairedWidth += u->high - u->low;
    }
  }
  EXPECT_GE(double(covered) / trials, 0.94);
  EXPECT_LT(pairedWidth / trials, 0.02) << "paired frames should give a ~1% interval";
  EXPECT_GT(unpairedWidth / 50, 3.0 * pairedWidth / trials) << "the drift should widen the unpaired interval";
}

TEST(FrameStats, UnpairedRatioIsDeterministicAndCoversItsEstimate) {
  std::mt19937_64 rng(3);
  const std::vector<double> a = lognormal(rng, 30, 12.0, 0.05), b = lognormal(rng, 30, 10.0, 0.05);
  const auto x = unpairedRatio(a, b, 99), y = unpairedRatio(a, b, 99);
  ASSERT_TRUE(x && y);
  EXPECT_EQ(x->low, y->low);
  EXPECT_EQ(x->high, y->high);
  EXPECT_LE(x->low, x->estimate);
  EXPECT_GE(x->high, x->estimate);
  EXPECT_GT(x->low, 1.1) << "a 20% difference with 5% spread and 30 frames is resolved";
  EXPECT_FALSE(unpairedRatio(std::vector<double>{1, 2, 3}, b, 1).has_value());
}

TEST(FrameStats, PairedRatioDropsPairsItCannotUse) {
  std::vector<double> a = {2, 2, 2, 2, 2, 2, 0, -1, std::nan("")};
  std::vector<double> b = {1, 1, 1, 1, 1, 1, 1, 1, 1};
  const auto r = pairedRatio(a, b);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->n, 6u);
  EXPECT_DOUBLE_EQ(r->estimate, 2.0);
  a.resize(5);
  EXPECT_FALSE(pairedRatio(a, b).has_value());
}

TEST(FrameStats, SpearmanRanksWithTiesAndRefusesWhatItCannotRank) {
  const std::vector<double> x = {1, 2, 3, 4, 5}, y = {10, 20, 30, 40, 50}, z = {50, 40, 30, 20, 10};
  EXPECT_DOUBLE_EQ(*spearman(x, y), 1.0);
  EXPECT_DOUBLE_EQ(*spearman(x, z), -1.0);
  // Monotone but not linear: still 1.
  const std::vector<double> cube = {1, 8, 27, 64, 125};
  EXPECT_DOUBLE_EQ(*spearman(x, cube), 1.0);
  // Ties get their mean rank: x ranks 1, 2.5, 2.5, 4; y ranks 1..4 -> rho = 4.5 / sqrt(4.5 * 5).
  const std::vector<double> tx = {1, 2, 2, 3}, ty = {1, 2, 3, 4};
  EXPECT_NEAR(*spearman(tx, ty), 4.5 / std::sqrt(4.5 * 5.0), 1e-12);
  EXPECT_FALSE(spearman(std::vector<double>{1, 2}, std::vector<double>{1, 2}).has_value());
  EXPECT_FALSE(spearman(std::vector<double>{1, 1, 1}, std::vector<double>{1, 2, 3}).has_value());
  EXPECT_FALSE(spearman(std::vector<double>{1, std::nan(""), 3}, std::vector<double>{1, 2, 3}).has_value());
}

// bench_builders --processes: a paired-ratio line survives the round trip exactly, malformed ones are
// refused, and the processes' estimates combine into the median with its order-statistic interval.
TEST(AcrossProcesses, LinesRoundTripAndBadOnesAreRefused) {
  const bench::PairedLine p{"bunny", "ploc[top-down=4] t(1)", "sah-binned t(1)", 1.0123456789012345, 0.9, 1.1};
  const std::optional<bench::PairedLine> q = bench::parsePairedLine(bench::formatPairedLine(p));
  ASSERT_TRUE(q.has_value());
  EXPECT_EQ(q->mesh, p.mesh);
  EXPECT_EQ(q->row, p.row);
  EXPECT_EQ(q->versus, p.versus);
  EXPECT_EQ(q->estimate, p.estimate);
  EXPECT_EQ(q->low, p.low);
  EXPECT_EQ(q->high, p.high);
  for (const char* bad : {"", "bunny\tploc t(1)\tsah-binned t(1)\t1.0\t0.9", "bunny\tploc\tsah\t1.0\t0.9\t1.1\t2",
                          "bunny\tploc\tsah\tnan\t0.9\t1.1", "bunny\tploc\tsah\t1.0\t-1\t1.1",
                          "bunny\tploc\tsah\t1.0x\t0.9\t1.1", "\tploc\tsah\t1.0\t0.9\t1.1", "bunny\tploc\tsah\tinf\t0.9\t1.1"})
    EXPECT_FALSE(bench::parsePairedLine(bad).has_value()) << bad;
}

TEST(AcrossProcesses, MedianOfTheProcessesWithItsIntervalAndVerdict) {
  auto line = [](const char* row, double e) { return bench::PairedLine{"bunny", row, "sah-binned t(1)", e, e * 0.95, e * 1.05}; };
  // Six processes: the interval is [min, max] (coverage 1 - 2/64), the estimate the median.
  const double faster[6] = {0.90, 0.93, 0.85, 0.97, 0.91, 0.88};
  const double mixed[6] = {0.990, 1.092, 1.012, 1.124, 0.978, 1.050};
  std::vector<std::vector<bench::PairedLine>> processes(6);
  for (int k = 0; k < 6; ++k) processes[k] = {line("fast t(1)", faster[k]), line("mixed t(1)", mixed[k])};
  processes[0].push_back(line("once t(1)", 0.5));  // a comparison only one process made
  const std::vector<bench::AcrossProcesses> all = bench::combineProcesses(processes);
  ASSERT_EQ(all.size(), 3u);
  const bench::AcrossProcesses& fast = all[0];
  EXPECT_EQ(fast.row, "fast t(1)");
  ASSERT_TRUE(fast.interval.has_value());
  EXPECT_DOUBLE_EQ(fast.interval->estimate, (0.90 + 0.91) / 2);
  EXPECT_DOUBLE_EQ(fast.interval->low, 0.85);
  EXPECT_DOUBLE_EQ(fast.interval->high, 0.97);
  EXPECT_EQ(fast.verdict, "below 1");
  EXPECT_EQ(fast.estimates, std::vector<double>(faster, faster + 6));
  const bench::AcrossProcesses& mixedRow = all[1];
  EXPECT_EQ(mixedRow.row, "mixed t(1)");
  ASSERT_TRUE(mixedRow.interval.has_value());
  EXPECT_EQ(mixedRow.verdict, "no detectable difference");
  const bench::AcrossProcesses& once = all[2];
  EXPECT_FALSE(once.interval.has_value());
  EXPECT_EQ(once.verdict, "< 6 processes: no interval");
  // All six above 1.
  for (auto& lines : processes)
    for (bench::PairedLine& p : lines) p.estimate += 1.0;
  EXPECT_EQ(bench::combineProcesses(processes)[0].verdict, "above 1");
}
