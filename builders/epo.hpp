// End-Point Overlap (EPO): a tree-quality measure that, unlike a frame time, needs no clock.
//
// Aila, Karras & Laine, "On Quality Metrics of Bounding Volume Hierarchies", HPG 2013, section
// "End-point overlap":
//
//   EPO = sum over nodes n of  C_n * A((S \ Q(n)) ∩ n) / A(S)
//
//   S      every surface of the scene: here, the triangles given;  A(.) surface area (full triangle
//          area, in numerator and denominator alike, so the ratio has no unit)
//   Q(n)   the surfaces in the subtree of n: the SET of triangles its leaves reference. A builder that
//          splits primitives (sbvh) references a triangle from several leaves; it is in Q(n) when any
//          of them lies in n's subtree, and counts at most once in A((S \ Q(n)) ∩ n) otherwise.
//   ∩ n    clipped to n's bounding box: (S \ Q(n)) ∩ n is every triangle NOT in n's subtree, clipped
//          to n's box
//   C_n    the cost of visiting n, the per-node cost of the paper's SAH (their Eq. 1):
//          Ct (CostModel::traversalCost) for an inner node, Ci * (its triangle count)
//          (CostModel::intersectionCost) for a leaf, so EPO and sahCost() weigh nodes alike.
//
// Why: the SAH prices the chance that an endless random ray enters a node, but real rays end on a
// surface. A ray whose end point lies inside n's box enters n; if that surface is in n's subtree the
// visit was needed, otherwise it is pure overhead that even a perfectly ordered traversal pays, and
// the more surface of other subtrees a box holds, the more often this happens. Entering a leaf means
// testing all its triangles, which is why a leaf weighs Ci times its count, as in the SAH; an inner
// node costs one traversal step, Ct.
//
// Boxes are closed: a triangle lying in a face of a box (a floor in a flat box) is inside it, as a
// ray ending on that floor does enter the box. Clipping is exact up to double rounding:
// Sutherland-Hodgman against the six planes, then the area of the clipped polygon.
#pragma once
#include <span>

#include <glm/glm.hpp>

#include "builders/bvh.hpp"

namespace bvhlab {

// Area of the triangle (a, b, c).
double triangleArea(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c);

// Area of the part of triangle (a, b, c) inside the closed box (0 for an empty box).
double clippedTriangleArea(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, const Aabb& box);

// EPO of a tree over triangle i = (v0[i], v1[i], v2[i]); leaves index triangles through
// Bvh::primIndices. Sums over the nodes reachable from the root.
//
// Degenerate inputs give a defined, finite value: zero-area triangles contribute no area; when the
// total area A(S) is 0 (every triangle degenerate) the EPO is 0, as there is no surface for a ray to
// end on, hence no end-point overlap; a tree of one leaf has EPO 0 (its subtree holds everything).
//
// `threads` workers (0 = hardware concurrency) share the nodes; each node's overlap is summed alone
// and the total is reduced in a fixed node order, so the result is bit-identical for any thread count.
//
// Throws std::invalid_argument when the three spans differ in length, a vertex or a node box is not
// finite, the tree has no nodes, is not a tree (a cycle, a child out of range), or its leaves do not
// reference every triangle at least once (several references to one triangle are fine: see Q(n)).
double endPointOverlap(const Bvh& bvh, std::span<const glm::vec3> v0, std::span<const glm::vec3> v1,
                       std::span<const glm::vec3> v2, const CostModel& cost, unsigned threads = 0);

}  // namespace bvhlab
