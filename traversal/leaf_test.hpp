// leaf_test.hpp — the primitive test a kernel mirror's walk runs at its leaves: the C++ side of the
// GLSL kernels' KERNEL_LEAF_TEST macro (traversal/two_level.glsl explains why it is a parameter). A
// flat tree and a two-level tree's BLASes test triangles (TriangleLeaf); a TLAS tests instances
// (traversal/two_level.hpp, InstanceLeaf). Each leaf test also says what one call fetches, for the
// mirrors' byte counters (Counters::triangleBytes).
#pragma once
#include "traversal/intersectors.hpp"

namespace bvhlab::glsl {

// testTriangle of the tree's triangle format, with the Tests pair's triangle test.
template <class Tests>
struct TriangleLeaf {
  const Storage& s;
  bool test(Ray ray, int tri, float tMin, float tMax, float& t, vec2& bary) const {
    return Tests::testTriangle(s, ray, tri, tMin, tMax, t, bary);
  }
  uint bytes() const { return triangleTestBytes(s); }
};

}  // namespace bvhlab::glsl
