// Helpers the builder test suites share (test_builders, test_reinsert, test_reinsert_leaves): the
// registered builders' names and bitwise equality of two trees.
#pragma once
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

}  // namespace bvhlab::testing
