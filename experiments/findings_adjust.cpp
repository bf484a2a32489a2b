#include "experiments/findings_adjust.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace bvhlab {

namespace {

// Indices of p in ascending order of p (NaN as 1), ties kept in input order.
std::vector<size_t> ascending(std::span<const double> p, std::vector<double>& clean) {
  clean.assign(p.begin(), p.end());
  for (double& x : clean) x = std::isnan(x) ? 1.0 : std::clamp(x, 0.0, 1.0);
  std::vector<size_t> order(p.size());
  std::iota(order.begin(), order.end(), size_t(0));
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return clean[a] < clean[b]; });
  return order;
}

}  // namespace

std::vector<double> adjustBenjaminiHochberg(std::span<const double> p) {
  std::vector<double> clean;
  const std::vector<size_t> order = ascending(p, clean);
  const double n = double(p.size());
  std::vector<double> out(p.size());
  double running = 1.0;
  for (size_t r = p.size(); r-- > 0;) {  // from the largest p down: the running minimum over j >= i
    running = std::min(running, n * clean[order[r]] / double(r + 1));
    out[order[r]] = running;
  }
  return out;
}

std::vector<double> adjustHolm(std::span<const double> p) {
  std::vector<double> clean;
  const std::vector<size_t> order = ascending(p, clean);
  const double n = double(p.size());
  std::vector<double> out(p.size());
  double running = 0.0;
  for (size_t r = 0; r < p.size(); ++r) {  // the running maximum over j <= i
    running = std::max(running, std::min(1.0, (n - double(r)) * clean[order[r]]));
    out[order[r]] = running;
  }
  return out;
}

}  // namespace bvhlab
