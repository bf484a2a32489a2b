// sbvh's spatial binning (builders/sbvh.cpp; Stich, Friedrich & Dietrich 2009, section 3): the
// reference sbvh moves, the slabs of one axis of a node's spatial-split search, lookups of the slab a
// coordinate lies in, and the part of a reference that straddles slab planes in each slab. Private to
// sbvh.cpp.
#pragma once
#include <algorithm>
#include <cstdint>

#include <glm/glm.hpp>

#include "builders/builder.hpp"
#include "builders/clip.hpp"

namespace bvhlab::sbvh {

// A reference: a primitive id and a box holding the part of the primitive it stands for.
struct Ref {
  Aabb box;
  glm::vec3 centroid;  // the input centroid while whole; the box centre once clipped
  uint32_t id;
};

// The slabs of one axis of a spatial-split search: planes[0..bins] (non-decreasing floats, the outer
// ones the node's faces) and a first guess of the slab holding a coordinate, from the planes' uniform
// spacing. Lookups walk from the guess to the answer, comparing with the planes themselves, so they
// return exactly what a binary search over the planes returns (the guess only decides where the walk
// starts: the planes are clamped and rounded, so it can be off by one); a guess is nearly always
// right, where a binary search over 32 planes costs five hard-to-predict branches, and a node's
// references take up to eight lookups per axis.
struct Slabs {
  const float* planes;
  uint32_t bins;
  double lo, scale;  // scale = bins / (hi - lo), finite: hi > lo are floats, their difference is >= 2^-149

  // floor((x - lo) * scale) clamped to [from, to]. x, lo and scale are finite, so g is never NaN.
  uint32_t guess(float x, uint32_t from, uint32_t to) const {
    const double g = (double(x) - lo) * scale;
    return g <= double(from) ? from : g >= double(to) ? to : uint32_t(g);
  }
  // The largest j in [from, to] with planes[j] <= x, given planes[from] <= x: upper_bound over
  // planes[from..to] minus one.
  uint32_t lastAtMost(float x, uint32_t from, uint32_t to) const {
    uint32_t j = guess(x, from, to);
    while (j > from && planes[j] > x) --j;
    while (j < to && planes[j + 1] <= x) ++j;
    return j;
  }
  // The number of planes among planes[1..bins-1] below x: lower_bound over them.
  uint32_t countBelow(float x) const {
    uint32_t k = guess(x, 0, bins - 1);
    while (k > 0 && !(planes[k] < x)) --k;
    while (k + 1 < bins && planes[k + 1] < x) ++k;
    return k;
  }
};

// Grows boxes[first..last], the bins a reference spans on `axis`, by its part in each (`pieces`:
// scratch for as many boxes): the box's slab for a box-only primitive; for a triangle, the box of its
// vertices in the slab and of its edges' crossings with the slab's planes, intersected with the
// reference's box. These boxes only estimate the SAH of the candidate planes, so the crossings are
// computed plainly (rounded to nearest): the split itself clips with clip.hpp's conservative bounds.
// Each plane's crossings are computed once and grow both slabs they bound.
inline void binStraddler(const Ref& r, int axis, const Slabs& slabs, uint32_t first, uint32_t last, const BuildInput& input,
                         bool triangles, Aabb* boxes, Aabb* pieces) {
  const float* planes = slabs.planes;
  if (!triangles) {
    for (uint32_t b = first; b <= last; ++b) {
      const Aabb part = clip::clipBox(r.box, axis, planes[b], planes[b + 1]);
      if (!part.empty()) boxes[b].grow(part);
    }
    return;
  }
  Aabb* piece = pieces - first;  // piece[b] for b in [first, last]
  for (uint32_t b = first; b <= last; ++b) piece[b] = Aabb{};
  const glm::vec3 v[3] = {input.v0[r.id], input.v1[r.id], input.v2[r.id]};
  for (const glm::vec3& p : v) {
    // The slabs holding the vertex (two when it lies on a plane), within [first, last].
    if (p[axis] < planes[first] || p[axis] > planes[last + 1]) continue;
    const uint32_t b0 = slabs.lastAtMost(p[axis], first, last);
    piece[b0].grow(p);
    if (b0 > first && planes[b0] == p[axis]) piece[b0 - 1].grow(p);
  }
  for (int e = 0; e < 3; ++e) {
    const glm::vec3 &p = v[e], &q = v[(e + 1) % 3];
    if (p[axis] == q[axis]) continue;
    const float lo = std::min(p[axis], q[axis]), hi = std::max(p[axis], q[axis]);
    // Planes strictly between the edge's ends, among the planes first .. last + 1 of the slabs
    // the reference spans.
    uint32_t j = planes[first] > lo ? first : slabs.lastAtMost(lo, first, last + 1) + 1;
    const glm::dvec3 dp(p), slope = (glm::dvec3(q) - dp) / (double(q[axis]) - double(p[axis]));
    for (; j <= last + 1 && planes[j] < hi; ++j) {
      glm::vec3 x(dp + (double(planes[j]) - dp[axis]) * slope);
      x[axis] = planes[j];
      if (j > first) piece[j - 1].grow(x);
      if (j <= last) piece[j].grow(x);
    }
  }
  for (uint32_t b = first; b <= last; ++b) {
    Aabb slab = r.box;
    slab.min[axis] = std::max(slab.min[axis], planes[b]);
    slab.max[axis] = std::min(slab.max[axis], planes[b + 1]);
    const Aabb part = clip::intersect(piece[b], slab);
    if (!part.empty()) boxes[b].grow(part);
  }
}

}  // namespace bvhlab::sbvh
