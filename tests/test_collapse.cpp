// The SAH leaf collapse's emission (builders/collapse.hpp) against its definition: a recursive
// depth-first walk that appends a node's two children next to each other when it visits the node,
// left subtree first, and lists a collapsed subtree's primitives left to right. emitCollapsed gets
// there in one pass in index order instead; the two must agree bit for bit, on trees whose indices
// are scattered the way PLOC's are (parents before children, nothing else in order).
#include <algorithm>
#include <cstdint>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "builders/collapse.hpp"
#include "datasets/random_draws.hpp"

namespace bvhlab {
namespace {

// A random full binary tree over n one-primitive leaves: random shapes (top-down splits at a
// random position, so both balanced and degenerate stretches occur), indices given in a random
// order that keeps every parent before its children, random leaf boxes (some flat, some repeated),
// inner boxes the unions of their children's.
std::vector<BvhNode> randomFullTree(uint32_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  struct Shape {
    int32_t left = -1, right = -1;  // shape indices; leaves: -1
    uint32_t prim = 0;
  };
  std::vector<Shape> shapes(1);
  std::vector<std::pair<uint32_t, uint32_t>> work{{0u, n}};  // (shape, primitives below)
  uint32_t nextPrim = 0;
  while (!work.empty()) {
    const auto [s, count] = work.back();
    work.pop_back();
    if (count == 1) {
      shapes[s].prim = nextPrim++;
      continue;
    }
    const uint32_t leftCount = std::uniform_int_distribution<uint32_t>(1, count - 1)(rng);
    shapes[s].left = int32_t(shapes.size());
    shapes[s].right = int32_t(shapes.size() + 1);
    shapes.resize(shapes.size() + 2);
    work.push_back({uint32_t(shapes[s].right), count - leftCount});
    work.push_back({uint32_t(shapes[s].left), leftCount});
  }
  // Indices: a random topological order (pick any node whose parent is placed).
  std::vector<uint32_t> index(shapes.size()), ready{0};
  uint32_t next = 0;
  while (!ready.empty()) {
    const size_t pick = std::uniform_int_distribution<size_t>(0, ready.size() - 1)(rng);
    const uint32_t s = ready[pick];
    ready[pick] = ready.back();
    ready.pop_back();
    index[s] = next++;
    if (shapes[s].left >= 0) ready.push_back(uint32_t(shapes[s].left)), ready.push_back(uint32_t(shapes[s].right));
  }
  std::vector<BvhNode> full(shapes.size());
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  Aabb repeated;
  repeated.grow(glm::vec3(0.25f)), repeated.grow(glm::vec3(0.5f, 0.25f, 0.75f));
  for (size_t s = shapes.size(); s-- > 0;) {  // children were made after their parents: reverse
    BvhNode& node = full[index[s]];
    if (shapes[s].left < 0) {
      const glm::vec3 c = draw3<glm::vec3>(unit, rng);
      // z first (see random_draws.hpp): one box in five is flat in z.
      const float z = unit(rng) < 0.2f ? 0.0f : unit(rng), y = unit(rng), x = unit(rng);
      const glm::vec3 e = 0.05f * glm::vec3(x, y, z);
      node.bounds = unit(rng) < 0.1f ? repeated : Aabb{c - e, c + e};
      node.first = shapes[s].prim;
      node.count = 1;
    } else {
      node.left = index[uint32_t(shapes[s].left)];
      node.right = index[uint32_t(shapes[s].right)];
      node.bounds = full[node.left].bounds;
      node.bounds.grow(full[node.right].bounds);
    }
  }
  return full;
}

// The definition, written out: the entries bottom-up, then a recursive depth-first emission.
Bvh emitByDefinition(const std::vector<BvhNode>& full, const BuildOptions& options) {
  std::vector<detail::CollapseInfo> info(full.size());
  for (size_t i = full.size(); i-- > 0;) {
    const BvhNode& node = full[i];
    info[i] = node.isLeaf() ? detail::collapseLeafInfo(node, options)
                            : detail::collapseInnerInfo(node, info[node.left], info[node.right], options);
  }
  Bvh bvh;
  bvh.nodes.push_back({full[0].bounds});
  std::function<void(uint32_t)> primitives = [&](uint32_t i) {
    if (full[i].isLeaf()) {
      bvh.primIndices.push_back(full[i].first);
      return;
    }
    primitives(full[i].left);
    primitives(full[i].right);
  };
  std::function<void(uint32_t, uint32_t)> visit = [&](uint32_t i, uint32_t slot) {
    if (info[i].collapse()) {
      bvh.nodes[slot].first = uint32_t(bvh.primIndices.size());
      bvh.nodes[slot].count = info[i].count;
      primitives(i);
      return;
    }
    const uint32_t left = uint32_t(bvh.nodes.size());
    bvh.nodes[slot].left = left;
    bvh.nodes[slot].right = left + 1;
    bvh.nodes.push_back({full[full[i].left].bounds});
    bvh.nodes.push_back({full[full[i].right].bounds});
    visit(full[i].left, left);
    visit(full[i].right, left + 1);
  };
  visit(0, 0);
  return bvh;
}

TEST(Collapse, EmissionMatchesTheDepthFirstDefinition) {
  int trees = 0, collapsedSomewhere = 0, keptSomewhere = 0;
  for (uint32_t n : {1u, 2u, 3u, 5u, 17u, 1000u, 30000u}) {
    for (uint32_t leafSize : {1u, 2u, 4u, 8u}) {
      for (float traversalCost : {1.0f, 0.25f, 4.0f}) {
        const uint32_t seed = n * 131 + leafSize * 7 + uint32_t(traversalCost * 4);
        SCOPED_TRACE("n " + std::to_string(n) + " leaf " + std::to_string(leafSize) + " Ct " +
                     std::to_string(traversalCost) + " seed " + std::to_string(seed));
        const std::vector<BvhNode> full = randomFullTree(n, seed);
        BuildOptions options;
        options.maxLeafSize = leafSize;
        options.cost.traversalCost = traversalCost;
        const Bvh expected = emitByDefinition(full, options);
        const Bvh got = detail::collapseLeavesBySah(full, options);
        ASSERT_EQ(got.nodes.size(), expected.nodes.size());
        ASSERT_EQ(got.primIndices, expected.primIndices);
        for (size_t k = 0; k < got.nodes.size(); ++k) {
          const BvhNode &a = got.nodes[k], &b = expected.nodes[k];
          ASSERT_EQ(a.bounds.min, b.bounds.min) << "node " << k;
          ASSERT_EQ(a.bounds.max, b.bounds.max) << "node " << k;
          ASSERT_EQ(a.count, b.count) << "node " << k;
          if (a.isLeaf()) {
            ASSERT_EQ(a.first, b.first) << "node " << k;
          } else {
            ASSERT_EQ(a.left, b.left) << "node " << k;
            ASSERT_EQ(a.right, b.right) << "node " << k;
          }
        }
        ++trees;
        const size_t leaves = std::count_if(got.nodes.begin(), got.nodes.end(), [](const BvhNode& x) { return x.isLeaf(); });
        collapsedSomewhere += leaves < n;  // some leaf holds more than one primitive
        keptSomewhere += n > 1 && std::any_of(got.nodes.begin(), got.nodes.end(),
                                              [](const BvhNode& x) { return x.count == 1; });
      }
    }
  }
  // The cases exercise both outcomes of the collapse, not only one (31 and 60-odd of the 84 trees
  // when written; leaf size 1 never collapses, and a cheap traversal keeps small trees split).
  EXPECT_EQ(trees, 7 * 4 * 3);
  EXPECT_GT(collapsedSomewhere, 25);
  EXPECT_GT(keptSomewhere, 40);
}

}  // namespace
}  // namespace bvhlab
