// The ray-box / ray-triangle pair a kernel mirror is instantiated with: the C++ counterpart of the
// shader assembler choosing ray_box.glsl or ray_box_robust.glsl, and ray_triangle.glsl or
// ray_triangle_watertight.glsl, independently (traversal/robustness.hpp). Kernel mirrors call
// Tests::intersectAabb(...) where their GLSL twin calls intersectAabb(...), and
// Tests::testTriangle(s, ...) where it calls the triangle format's testTriangle(...).
#pragma once
#include "traversal/ray_box.hpp"
#include "traversal/ray_box_robust.hpp"
#include "traversal/ray_triangle.hpp"
#include "traversal/ray_triangle_watertight.hpp"
#include "traversal/robustness.hpp"
#include "traversal/triangles_format.hpp"

namespace bvhlab::glsl {

template <TriangleTest Triangle, BoxTest Box>
struct Tests {
  static vec3 rayInverseDirection(vec3 dir) {
    if constexpr (Box == BoxTest::Robust) return robust::rayInverseDirection(dir);
    else return glsl::rayInverseDirection(dir);
  }
  static bool intersectAabb(vec3 origin, vec3 invDir, vec3 bmin, vec3 bmax, float tMin, float tMax, float& tEnter) {
    if constexpr (Box == BoxTest::Robust) return robust::intersectAabb(origin, invDir, bmin, bmax, tMin, tMax, tEnter);
    else return glsl::intersectAabb(origin, invDir, bmin, bmax, tMin, tMax, tEnter);
  }
  static bool intersectTriangle(Ray ray, vec3 v0, vec3 v1, vec3 v2, float tMin, float tMax, float& t, vec2& bary) {
    if constexpr (Triangle == TriangleTest::Watertight)
      return watertight::intersectTriangle(ray, v0, v1, v2, tMin, tMax, t, bary);
    else return glsl::intersectTriangle(ray, v0, v1, v2, tMin, tMax, t, bary);
  }
  // The triangle format module's testTriangle (traversal/triangles_<format>.glsl): fetch triangle
  // `tri` in the tree's format and test it. precomputed runs only with Moller-Trumbore; the CLI and
  // the assembler refuse the other pairing before this (layout/triangle_formats.hpp).
  static bool testTriangle(const Storage& s, Ray ray, int tri, float tMin, float tMax, float& t, vec2& bary) {
    switch (s.triangles) {
      case TriangleFormat::Precomputed:
        if constexpr (Triangle == TriangleTest::Watertight)
          throw std::invalid_argument("triangle format 'precomputed' cannot run the watertight triangle test");
        else return precomputed::testTriangle(s, ray, tri, tMin, tMax, t, bary);
      case TriangleFormat::Indexed: return indexed::testTriangle<Tests>(s, ray, tri, tMin, tMax, t, bary);
      default: return raw::testTriangle<Tests>(s, ray, tri, tMin, tMax, t, bary);
    }
  }
};

using FastTests = Tests<TriangleTest::MollerTrumbore, BoxTest::Slab>;  // --robust fast
using RobustTests = Tests<TriangleTest::Watertight, BoxTest::Robust>;   // --robust watertight (and tri+box)

}  // namespace bvhlab::glsl
