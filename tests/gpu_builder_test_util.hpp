// Checks shared by the GPU builders' tests (test_gpu_builders.cpp, test_gpu_ploc.cpp).
#pragma once
#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "builder_test_util.hpp"
#include "builders/builder.hpp"
#include "builders/bvh.hpp"
#include "builders/test_inputs.hpp"
#include "datasets/scene.hpp"

namespace bvhlab::testing {

// The invariants every builder's tree keeps (as test_builders checks them): every node reached once,
// every primitive in exactly one leaf, leaves of at most maxLeafSize, every box the exact union of
// its primitives' or children's.
inline void expectValidTree(const Bvh& bvh, const BuildInput& input, uint32_t maxLeafSize) {
  const size_t n = input.boxes.size();
  ASSERT_EQ(bvh.primIndices.size(), n);
  ASSERT_LE(bvh.nodes.size(), 2 * n - 1);
  std::vector<int> referenced(n, 0), reached(bvh.nodes.size(), 0);
  std::vector<uint32_t> stack{0};
  while (!stack.empty()) {
    const uint32_t i = stack.back();
    stack.pop_back();
    ASSERT_LT(i, bvh.nodes.size());
    ASSERT_EQ(reached[i]++, 0) << "node " << i << " reached twice";
    const BvhNode& node = bvh.nodes[i];
    Aabb tight;
    if (node.isLeaf()) {
      ASSERT_LE(node.count, maxLeafSize);
      ASSERT_LE(size_t(node.first) + node.count, n);
      for (uint32_t k = node.first; k < node.first + node.count; ++k) {
        ASSERT_LT(bvh.primIndices[k], n);
        ++referenced[bvh.primIndices[k]];
        tight.grow(input.boxes[bvh.primIndices[k]]);
      }
    } else {
      tight = bvh.nodes.at(node.left).bounds;
      tight.grow(bvh.nodes.at(node.right).bounds);
      stack.push_back(node.right);
      stack.push_back(node.left);
    }
    ASSERT_TRUE(sameBox(node.bounds, tight)) << "node " << i << "'s box is not the union below it";
  }
  EXPECT_EQ(std::count(reached.begin(), reached.end(), 0), 0) << "nodes unreachable from the root";
  EXPECT_EQ(std::count(referenced.begin(), referenced.end(), 1), ptrdiff_t(n)) << "a primitive not in one leaf";
}

inline PrimitiveSet fromMesh(const Mesh& mesh) {
  PrimitiveSet set;
  for (const glm::uvec3& t : mesh.triangles) set.addTriangle(mesh.positions[t.x], mesh.positions[t.y], mesh.positions[t.z]);
  return set;
}

inline BuildOptions withRadius(uint32_t radius) {
  BuildOptions o;
  o.plocRadius = radius;
  return o;
}

// ploc and a GPU build of its tree (ploc-gpu, plocpp-gpu) through the registry, validation included:
// the same tree, node for node, and a valid one.
inline void expectSameAsPloc(const std::string& builder, const BuildInput& input, const BuildOptions& options = {}) {
  const Bvh cpu = buildBvh("ploc", input, options);
  const Bvh gpu = buildBvh(builder, input, options);
  expectValidTree(gpu, input, options.maxLeafSize);
  EXPECT_EQ(gpu.nodes.size(), cpu.nodes.size());
  EXPECT_TRUE(identical(gpu, cpu)) << builder << "'s tree differs from ploc's";
  EXPECT_EQ(sahCost(gpu, options.cost), sahCost(cpu, options.cost));
}

}  // namespace bvhlab::testing
