#include "render/frame_stats.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

namespace bvhlab {

namespace {

std::vector<double> finiteValues(std::span<const double> values) {
  std::vector<double> out;
  out.reserve(values.size());
  for (double v : values)
    if (std::isfinite(v)) out.push_back(v);
  return out;
}

// P(B <= j) for B ~ Binomial(n, 1/2), summed in log space (n may be in the thousands).
double binomialHalfCdf(size_t n, size_t j) {
  double sum = 0.0;
  const double logHalfN = double(n) * std::log(0.5);
  for (size_t i = 0; i <= j && i <= n; ++i)
    sum += std::exp(std::lgamma(double(n) + 1.0) - std::lgamma(double(i) + 1.0) - std::lgamma(double(n - i) + 1.0) +
                    logHalfN);
  return sum;
}

// The value at 1-based rank k of a sorted list.
double rank(const std::vector<double>& sorted, size_t k) { return sorted[k - 1]; }

}  // namespace

double medianOf(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::optional<OrderStatisticRanks> medianIntervalRanks(size_t n, double confidence) {
  if (n < kMinValuesForInterval) return std::nullopt;
  // The interval [x_(k), x_(n-k+1)] misses the median when at most k-1 values lie below it or at
  // most k-1 above: probability 2 P(B <= k-1). Grow k while the coverage stays >= confidence.
  OrderStatisticRanks best;
  for (size_t k = 1; k <= (n + 1) / 2; ++k) {
    const double coverage = 1.0 - 2.0 * binomialHalfCdf(n, k - 1);
    if (coverage < confidence) break;
    best = {k, n - k + 1, coverage};
  }
  if (best.lower == 0) return std::nullopt;
  return best;
}

std::optional<Interval> medianInterval(std::span<const double> values, double confidence) {
  std::vector<double> v = finiteValues(values);
  const auto ranks = medianIntervalRanks(v.size(), confidence);
  if (!ranks) return std::nullopt;
  std::sort(v.begin(), v.end());
  Interval out;
  out.estimate = medianOf(v);
  out.low = rank(v, ranks->lower);
  out.high = rank(v, ranks->upper);
  out.coverage = ranks->coverage;
  out.n = v.size();
  return out;
}

std::optional<Interval> pairedRatio(std::span<const double> a, std::span<const double> b, double confidence) {
  std::vector<double> logRatios;
  const size_t n = std::min(a.size(), b.size());
  for (size_t i = 0; i < n; ++i)
    if (a[i] > 0.0 && b[i] > 0.0 && std::isfinite(a[i]) && std::isfinite(b[i]))
      logRatios.push_back(std::log(a[i]) - std::log(b[i]));
  const auto m = medianInterval(logRatios, confidence);
  if (!m) return std::nullopt;
  return Interval{std::exp(m->estimate), std::exp(m->low), std::exp(m->high), m->coverage, m->n};
}

std::optional<Interval> unpairedRatio(std::span<const double> a, std::span<const double> b, uint64_t seed,
                                      int resamples, double confidence) {
  std::vector<double> x = finiteValues(a), y = finiteValues(b);
  if (x.size() < kMinValuesForInterval || y.size() < kMinValuesForInterval || resamples < 100) return std::nullopt;
  const double mx = medianOf(x), my = medianOf(y);
  if (!(mx > 0.0 && my > 0.0)) return std::nullopt;
  std::mt19937_64 rng(seed);
  std::vector<double> ratios, rx(x.size()), ry(y.size());
  ratios.reserve(size_t(resamples));
  for (int r = 0; r < resamples; ++r) {
    // Index by the top bits of the generator's output (std::uniform_int_distribution's algorithm is
    // implementation-defined; this keeps the interval identical across standard libraries).
    for (double& v : rx) v = x[size_t((rng() >> 11) % x.size())];
    for (double& v : ry) v = y[size_t((rng() >> 11) % y.size())];
    const double dx = medianOf(rx), dy = medianOf(ry);
    if (dx > 0.0 && dy > 0.0) ratios.push_back(dx / dy);
  }
  if (ratios.size() < 100) return std::nullopt;
  std::sort(ratios.begin(), ratios.end());
  const double tail = 0.5 * (1.0 - confidence);
  const auto at = [&](double q) { return ratios[std::min(ratios.size() - 1, size_t(q * double(ratios.size())))]; };
  return Interval{mx / my, at(tail), at(1.0 - tail), confidence, std::min(x.size(), y.size())};
}

namespace {

// The median of v (reordered in place); v non-empty.
double medianInPlace(std::vector<double>& v) {
  const size_t n = v.size(), mid = n / 2;
  std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(mid), v.end());
  const double upper = v[mid];
  if (n % 2) return upper;
  return 0.5 * (*std::max_element(v.begin(), v.begin() + std::ptrdiff_t(mid)) + upper);
}

// One moving-block resample of x (n values from randomly started runs of `block` consecutive ones,
// the last run cut to length n) into `out`.
void blockResample(const std::vector<double>& x, size_t block, std::mt19937_64& rng, std::vector<double>& out) {
  out.clear();
  const size_t starts = x.size() - block + 1;
  while (out.size() < x.size()) {
    // Top bits of the raw output: identical on every standard library (see unpairedRatio).
    const size_t s = size_t((rng() >> 11) % starts);
    for (size_t i = 0; i < block && out.size() < x.size(); ++i) out.push_back(x[s + i]);
  }
}

double standardDeviation(const std::vector<double>& v) {
  if (v.size() < 2) return 0.0;
  const double mean = std::accumulate(v.begin(), v.end(), 0.0) / double(v.size());
  double ss = 0.0;
  for (double x : v) ss += (x - mean) * (x - mean);
  return std::sqrt(ss / double(v.size() - 1));
}

struct BlockPlan {
  size_t block = 1;
  double lag1 = 0.0;
  // The moving-block variance misses the covariance between neighbouring blocks: for an AR(1) series
  // its expected relative bias is -2 rho / (b (1 - rho^2)) (Kuensch 1989; the AR(1) sums of
  // Politis & White 2004). The bootstrap variance is divided by 1 minus that, at most doubled.
  double varianceFactor() const {
    const double rho = !(lag1 > 0.0) ? 0.0 : std::min(lag1, 0.95);
    const double bias = 2.0 * rho / (double(block) * (1.0 - rho * rho));
    return 1.0 / std::max(0.5, 1.0 - bias);
  }
};
BlockPlan planBlocks(const std::vector<double>& x) {
  const double rho = lag1Autocorrelation(x).value_or(0.0);
  return {blockLength(x.size(), rho), rho};
}

std::vector<double> positiveFinite(std::span<const double> values) {
  std::vector<double> out;
  for (double v : values)
    if (std::isfinite(v) && v > 0.0) out.push_back(v);
  return out;
}

Interval normalInterval(double logEstimate, double logSe, size_t n, size_t block, double lag1) {
  Interval out;
  out.estimate = std::exp(logEstimate);
  out.low = std::exp(logEstimate - kZ95 * logSe);
  out.high = std::exp(logEstimate + kZ95 * logSe);
  out.coverage = kConfidence;
  out.n = n;
  out.logSe = logSe;
  out.block = block;
  out.lag1 = lag1;
  return out;
}

}  // namespace

std::optional<double> lag1Autocorrelation(std::span<const double> series) {
  const std::vector<double> x = finiteValues(series);
  if (x.size() < 3) return std::nullopt;
  const double mean = std::accumulate(x.begin(), x.end(), 0.0) / double(x.size());
  double c0 = 0.0, c1 = 0.0;
  for (size_t i = 0; i < x.size(); ++i) {
    c0 += (x[i] - mean) * (x[i] - mean);
    if (i + 1 < x.size()) c1 += (x[i] - mean) * (x[i + 1] - mean);
  }
  if (!(c0 > 0.0)) return std::nullopt;
  return c1 / c0;
}

size_t blockLength(size_t n, double lag1) {
  if (n < 3) return 1;
  // Clipped as the header says; !(x > 0) also maps NaN to 0 (independent rounds).
  const double rho = !(lag1 > 0.0) ? 0.0 : std::min(lag1, 0.95);
  const double b = std::cbrt(6.0 * rho * rho * double(n)) / std::pow(1.0 - rho * rho, 2.0 / 3.0);
  return std::clamp(size_t(std::ceil(b)), size_t(1), n / 3);
}

std::optional<Interval> pairedRatioBlock(std::span<const double> a, std::span<const double> b, uint64_t seed,
                                         int resamples) {
  std::vector<double> d;
  const size_t n = std::min(a.size(), b.size());
  for (size_t i = 0; i < n; ++i)
    if (a[i] > 0.0 && b[i] > 0.0 && std::isfinite(a[i]) && std::isfinite(b[i]))
      d.push_back(std::log(a[i]) - std::log(b[i]));
  if (d.size() < kMinValuesForInterval || resamples < 2) return std::nullopt;
  const BlockPlan plan = planBlocks(d);
  std::vector<double> work = d;
  const double estimate = medianInPlace(work);
  std::mt19937_64 rng(seed);
  std::vector<double> medians;
  medians.reserve(size_t(resamples));
  for (int r = 0; r < resamples; ++r) {
    blockResample(d, plan.block, rng, work);
    medians.push_back(medianInPlace(work));
  }
  return normalInterval(estimate, standardDeviation(medians) * std::sqrt(plan.varianceFactor()), d.size(), plan.block,
                        plan.lag1);
}

std::optional<Interval> unpairedRatioBlock(std::span<const double> a, std::span<const double> b, uint64_t seed,
                                           int resamples) {
  const std::vector<double> x = positiveFinite(a), y = positiveFinite(b);
  if (x.size() < kMinValuesForInterval || y.size() < kMinValuesForInterval || resamples < 2) return std::nullopt;
  const BlockPlan px = planBlocks(x), py = planBlocks(y);
  std::vector<double> wx = x, wy = y;
  const double estimate = std::log(medianInPlace(wx)) - std::log(medianInPlace(wy));
  std::mt19937_64 rng(seed);
  std::vector<double> logRatios;
  logRatios.reserve(size_t(resamples));
  for (int r = 0; r < resamples; ++r) {
    blockResample(x, px.block, rng, wx);
    blockResample(y, py.block, rng, wy);
    logRatios.push_back(std::log(medianInPlace(wx)) - std::log(medianInPlace(wy)));
  }
  // The two series are independent: each one's bias correction applies to its share of the variance;
  // the larger of the two factors bounds both.
  const double factor = std::max(px.varianceFactor(), py.varianceFactor());
  return normalInterval(estimate, standardDeviation(logRatios) * std::sqrt(factor), std::min(x.size(), y.size()),
                        std::max(px.block, py.block), std::max(px.lag1, py.lag1));
}

double normalCdf(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }

double BandTest::p() const { return std::min(1.0, 2.0 * std::min(pSlower, pFaster)); }

BandTest normalBandTest(double logEstimate, double logSe, double band) {
  BandTest t;
  if (!(logSe > 0.0)) {  // no spread: the estimate alone decides (NaN falls through to p = 1)
    if (logEstimate > band) t.pSlower = 0.0;
    if (logEstimate < -band) t.pFaster = 0.0;
    return t;
  }
  // One-sided: P(estimate >= observed | true log ratio = band), and its mirror at -band.
  const double slower = normalCdf((band - logEstimate) / logSe), faster = normalCdf((logEstimate + band) / logSe);
  if (std::isfinite(slower)) t.pSlower = slower;
  if (std::isfinite(faster)) t.pFaster = faster;
  return t;
}

BandTest signBandTest(std::span<const double> logValues, double band) {
  const std::vector<double> v = finiteValues(logValues);
  BandTest t;
  if (v.size() < kMinValuesForInterval) return t;
  // Slower: the values at or below +band are the sign test's count; P(B <= count), B ~ Bin(n, 1/2).
  const size_t notAbove = size_t(std::count_if(v.begin(), v.end(), [&](double x) { return x <= band; }));
  const size_t notBelow = size_t(std::count_if(v.begin(), v.end(), [&](double x) { return x >= -band; }));
  t.pSlower = std::min(1.0, binomialHalfCdf(v.size(), notAbove));
  t.pFaster = std::min(1.0, binomialHalfCdf(v.size(), notBelow));
  return t;
}

std::optional<double> spearman(std::span<const double> x, std::span<const double> y) {
  const size_t n = x.size();
  if (n < 3 || y.size() != n) return std::nullopt;
  for (size_t i = 0; i < n; ++i)
    if (!std::isfinite(x[i]) || !std::isfinite(y[i])) return std::nullopt;
  auto ranks = [n](std::span<const double> v) {
    std::vector<size_t> order(n);
    std::iota(order.begin(), order.end(), size_t(0));
    std::sort(order.begin(), order.end(), [&](size_t i, size_t j) { return v[i] < v[j]; });
    std::vector<double> r(n);
    for (size_t i = 0; i < n;) {
      size_t j = i;
      while (j + 1 < n && v[order[j + 1]] == v[order[i]]) ++j;
      const double average = 0.5 * double(i + j) + 1.0;  // ties share their mean rank
      for (size_t k = i; k <= j; ++k) r[order[k]] = average;
      i = j + 1;
    }
    return r;
  };
  const std::vector<double> rx = ranks(x), ry = ranks(y);
  const double mean = 0.5 * double(n + 1);
  double sxy = 0.0, sxx = 0.0, syy = 0.0;
  for (size_t i = 0; i < n; ++i) {
    sxy += (rx[i] - mean) * (ry[i] - mean);
    sxx += (rx[i] - mean) * (rx[i] - mean);
    syy += (ry[i] - mean) * (ry[i] - mean);
  }
  if (sxx == 0.0 || syy == 0.0) return std::nullopt;
  return sxy / std::sqrt(sxx * syy);
}

}  // namespace bvhlab
