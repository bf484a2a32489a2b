// Statistics of frame times: the median with a distribution-free 95% interval, the ratio of two
// runs' times with its interval (from paired frames when the runs were measured interleaved), and
// Spearman's rank correlation. Used by `render`/`measure` (per-run intervals, when to stop rendering)
// and by the experiment findings (every ratio the report shows).
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

// Spearman's rank correlation (average ranks for ties). nullopt for fewer than 3 points, different
// lengths, a non-finite value, or a constant series (no ranking to correlate).
std::optional<double> spearman(std::span<const double> x, std::span<const double> y);

}  // namespace bvhlab
