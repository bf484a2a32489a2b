// Statistics of frame times: the median with a distribution-free 95% interval, the ratio of two
// runs' times with its interval (from paired frames when the runs were measured interleaved), and
// Spearman's rank correlation, and intervals and tests that hold when rounds are autocorrelated (block
// bootstrap, below). Used by `render`/`measure` (per-run intervals, when to stop rendering) and by the
// experiment findings (every ratio the report shows; docs/measurement.md).
//
// Why order statistics: frame times on llvmpipe are skewed (a slow tail from the OS and the JIT), so
// a normal-theory interval would be wrong, and a bootstrap would make every figure depend on a random
// stream. The interval [x_(k), x_(n-k+1)] covers the population median with probability
// 1 - 2 P(B <= k-1), B ~ Binomial(n, 1/2), whatever the distribution (continuous); we take the
// largest k whose coverage is still >= 95%, so the interval is exact-or-conservative.
#pragma once
#include <cstdint>
#include <optional>
#include <random>
#include <span>
#include <utility>
#include <vector>

namespace bvhlab {

// The confidence level every interval in the project uses.
constexpr double kConfidence = 0.95;
// The fewest values for which a 95% order-statistic interval of the median exists:
// with n = 5 even [min, max] covers only 1 - 2/32 = 93.75%.
constexpr size_t kMinValuesForInterval = 6;

double medianOf(std::vector<double> values);  // 0 for an empty list

// The order of one round of interleaved measurements: Fisher-Yates driven by the generator's raw
// output (std::shuffle's use of it is implementation-defined), so a fixed seed gives the same orders
// on every standard library.
template <class T>
void shuffleRound(std::vector<T>& order, std::mt19937_64& rng) {
  for (size_t i = order.size(); i > 1; --i) std::swap(order[i - 1], order[size_t(rng() % i)]);
}

struct Interval {
  double estimate = 0.0;      // the median (or median ratio)
  double low = 0.0, high = 0.0;
  double coverage = 0.0;      // the exact coverage of [low, high] (>= kConfidence)
  size_t n = 0;               // values (pairs) used
  // Block-bootstrap intervals only (below): the standard error of ln(estimate), the block length in
  // rounds and the lag-1 autocorrelation the block length was chosen from. logSe = 0 otherwise.
  double logSe = 0.0;
  size_t block = 0;
  double lag1 = 0.0;
};

// 1-based rank k of the lower order statistic for a 95% interval of the median of n values
// (the upper one is n - k + 1), with its exact coverage; nullopt when n < kMinValuesForInterval.
struct OrderStatisticRanks {
  size_t lower = 0, upper = 0;
  double coverage = 0.0;
};
std::optional<OrderStatisticRanks> medianIntervalRanks(size_t n, double confidence = kConfidence);

// Median of `values` with its order-statistic interval. Non-finite values are dropped first (NaN must
// not decide an ordering). nullopt when fewer than kMinValuesForInterval finite values remain.
std::optional<Interval> medianInterval(std::span<const double> values, double confidence = kConfidence);

// The ratio a/b of two runs' typical frame times with a 95% interval.
// Paired (a[i] and b[i] were drawn in the same round): the median of the per-round log ratios
// ln(a[i]/b[i]) and its order-statistic interval, exponentiated. Pairs with a non-positive or
// non-finite member are dropped. nullopt when fewer than kMinValuesForInterval pairs remain.
std::optional<Interval> pairedRatio(std::span<const double> a, std::span<const double> b,
                                    double confidence = kConfidence);
// Unpaired (different processes): median(a)/median(b) with a percentile-bootstrap interval
// (`resamples` draws from a fixed seed, so the same data always give the same interval).
std::optional<Interval> unpairedRatio(std::span<const double> a, std::span<const double> b, uint64_t seed,
                                      int resamples = 2000, double confidence = kConfidence);

// ---- Intervals that hold when rounds are autocorrelated ------------------------------------------
// The order-statistic intervals above assume independent rounds. On llvmpipe a machine's state lasts
// longer than a round (the frame series flips between two levels in long spells), so consecutive
// per-round ratios are correlated and those intervals are too narrow. The functions below resample
// the rounds in moving blocks (Kuensch 1989): a bootstrap series is made of randomly placed runs of
// `block` consecutive rounds, which keeps the dependence within a block. The estimate stays the
// median; its standard error on the log scale, se, is the standard deviation of the bootstrap
// medians, and the interval is exp(ln(estimate) -+ z se), z = the 97.5% normal quantile. A normal
// interval (not the bootstrap percentiles) is used so that a p-value from the same se (pOutsideBand)
// agrees with the interval exactly. The resampling is seeded: the same data give the same interval.
//
// Block length (blockLength): the plug-in rule of Politis & White (2004, corrected by Patton, Politis
// & White 2009) for the moving-block bootstrap with an AR(1) model fitted to the series:
// b = (6 rho^2 n)^(1/3) / (1 - rho^2)^(2/3), rho = the lag-1 autocorrelation clipped to [0, 0.95]
// (negative dependence needs no blocks; above 0.95 the formula runs away), rounded up, at least 1 and
// at most n / 3 (three blocks or more, so a resample is more than a shifted copy); variance bias-corrected (.cpp).

// Sample lag-1 autocorrelation of a series; nullopt for fewer than 3 finite values or a constant one.
std::optional<double> lag1Autocorrelation(std::span<const double> series);
size_t blockLength(size_t n, double lag1);
constexpr int kBlockResamples = 500;  // se to ~3% (relative error of a bootstrap sd ~ 1/sqrt(2 B))

// The paired ratio a/b (median of per-round log ratios) with a moving-block bootstrap interval.
// nullopt when fewer than kMinValuesForInterval pairs remain.
std::optional<Interval> pairedRatioBlock(std::span<const double> a, std::span<const double> b, uint64_t seed,
                                         int resamples = kBlockResamples);
// median(a)/median(b) for two series from different processes: each series resampled in its own
// blocks. nullopt when either has fewer than kMinValuesForInterval finite positive values.
std::optional<Interval> unpairedRatioBlock(std::span<const double> a, std::span<const double> b, uint64_t seed,
                                           int resamples = kBlockResamples);

// ---- Tests against a noise band --------------------------------------------------------------------
// H0: the true log ratio lies inside [-band, band] (no difference beyond the noise floor). Each side
// is tested one-sidedly (pSlower: H0 ratio <= e^band; pFaster: H0 ratio >= e^-band); the reported
// p-value is two-sided (twice the smaller, capped at 1), so p < 1 - kConfidence exactly when the
// matching 95% interval lies wholly outside the band, on the side of the smaller one-sided p.
struct BandTest {
  double pSlower = 1.0, pFaster = 1.0;
  double p() const;
  bool slowerSide() const { return pSlower < pFaster; }
};
// From a normal interval (block bootstrap): logEstimate +- z logSe. logSe = 0: p = 0 on the side the
// estimate lies beyond the band, else 1. A NaN estimate tests as inside the band.
BandTest normalBandTest(double logEstimate, double logSe, double band);
// From an order-statistic interval over values (the sign test, the dual of medianInterval: that
// interval lies beyond a point exactly when the one-sided sign test rejects it at 2.5%). `logValues`
// are log ratios; non-finite ones are dropped. p = 1 when fewer than kMinValuesForInterval remain.
BandTest signBandTest(std::span<const double> logValues, double band);
double normalCdf(double x);
// The two-sided 95% normal quantile.
constexpr double kZ95 = 1.959963984540054;

// Spearman's rank correlation (average ranks for ties). nullopt for fewer than 3 points, different
// lengths, a non-finite value, or a constant series (no ranking to correlate).
std::optional<double> spearman(std::span<const double> x, std::span<const double> y);

}  // namespace bvhlab
