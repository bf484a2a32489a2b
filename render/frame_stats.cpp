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
