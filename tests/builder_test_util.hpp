// Helpers the builder test suites share (test_builders, test_reinsert, test_reinsert_leaves, test_ploc,
// test_hploc): the registered builders' names, bitwise equality of two trees, and PLOC's clustering
// pass written out plainly.
#pragma once
#include <algorithm>
#include <bit>
#include <cstdint>
#include <string>
#include <vector>

#include "builders/builder.hpp"
#include "builders/bvh.hpp"

namespace bvhlab::testing {

inline std::vector<std::string> builderNames() {
  std::vector<std::string> names;
  for (const BuilderInfo& info : builders()) names.push_back(info.name);
  return names;
}

inline bool sameBox(const Aabb& a, const Aabb& b) { return a.min == b.min && a.max == b.max; }

// The same nodes (boxes bit for bit, links, counts) and the same primitive order.
inline bool identical(const Bvh& a, const Bvh& b) {
  if (a.nodes.size() != b.nodes.size() || a.primIndices != b.primIndices) return false;
  for (size_t i = 0; i < a.nodes.size(); ++i) {
    const BvhNode &x = a.nodes[i], &y = b.nodes[i];
    if (!sameBox(x.bounds, y.bounds) || x.count != y.count ||
        (x.isLeaf() ? x.first != y.first : (x.left != y.left || x.right != y.right)))
      return false;
  }
  return true;
}

// One PLOC pass as Meister & Bittner define it, with the keys builders/ploc_keys.hpp states (written
// out here, not shared): every cluster's nearest neighbour within +-radius by merged half area (-0 as
// +0), ties by (distance, lower position's parity, side); mutual pairs merged at the lower position by
// merge(left, right) -> new node; the order kept.
template <class Merge>
void referencePlocPass(const std::vector<BvhNode>& full, std::vector<uint32_t>& clusters, uint32_t radius,
                       Merge&& merge) {
  const uint32_t m = uint32_t(clusters.size());
  std::vector<uint32_t> nn(m);
  for (uint32_t x = 0; x < m; ++x) {
    uint64_t best = ~uint64_t(0);
    for (uint32_t j = x > radius ? x - radius : 0; j <= std::min(m - 1, x + radius); ++j) {
      if (j == x) continue;
      Aabb merged = full[clusters[x]].bounds;
      merged.grow(full[clusters[j]].bounds);
      const glm::vec3 e = merged.extent();
      const float area = (e.x * e.y + e.y * e.z) + e.z * e.x + 0.0f;  // -0 counts as +0
      const uint32_t d = x > j ? x - j : j - x, lower = std::min(x, j);
      const uint64_t key = uint64_t(std::bit_cast<uint32_t>(area)) << 32 | (4 * d + 2 * (lower & 1) + (j > x));
      if (key < best) best = key, nn[x] = j;
    }
  }
  std::vector<uint32_t> kept;
  for (uint32_t x = 0; x < m; ++x) {
    if (nn[nn[x]] != x)
      kept.push_back(clusters[x]);
    else if (x < nn[x])
      kept.push_back(merge(clusters[x], clusters[nn[x]]));
  }
  clusters = kept;
}

}  // namespace bvhlab::testing
