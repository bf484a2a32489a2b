// Multiple-comparison adjustment of a findings file's tests (docs/measurement.md, "Many comparisons").
// Both take p-values in any order and return the adjusted ones in the same order, each in [0, 1];
// a NaN p-value is treated as 1 (it never supports a verdict).
#pragma once
#include <span>
#include <vector>

namespace bvhlab {

// Benjamini & Hochberg (1995): controls the expected share of false directional verdicts among the
// directional verdicts (false discovery rate) at alpha when adjusted p <= alpha is called. Adjusted
// p_(i) = min over j >= i of N p_(j) / j (p sorted ascending), capped at 1.
std::vector<double> adjustBenjaminiHochberg(std::span<const double> p);
// Holm (1979): controls the chance of any false verdict (family-wise error). Adjusted p_(i) = max over
// j <= i of (N - j + 1) p_(j), capped at 1.
std::vector<double> adjustHolm(std::span<const double> p);

}  // namespace bvhlab
