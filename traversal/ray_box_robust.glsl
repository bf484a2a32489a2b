// ray_box_robust.glsl — the slab test made conservative: Ize (2013), "Robust BVH Ray Traversal",
// JCGT 2(2). Drop-in for ray_box.glsl (same rayInverseDirection and intersectAabb). C++ mirror:
// ray_box_robust.hpp.
//
// Conservative: every slab distance (plane - origin) * invDir is computed with at most three
// roundings (the subtraction, the reciprocal in invDir, the product), so it lies within a relative
// gamma(3) = 3u / (1 - 3u) of the exact distance, u = 2^-24. Enlarging each box's exit distance by
// the factor 1 + 2 gamma(3) covers the error of both the exit and the entry distance (Ize, section 3),
// so a ray that meets the box in exact arithmetic is never culled; the price is a few more node
// visits. (A negative exit, a box behind the origin, moves further behind; with tMin >= 0 that
// matters only for an exit within gamma(3) of 0, which a rounded subtraction cannot produce: it is
// exactly 0 or at least one float spacing of the coordinates away.)
//
// NaN never decides anything, for finite origin and direction: invDir is finite (below), a finite
// difference times a finite invDir is never NaN (it may overflow to +-inf, which min/max and the
// comparisons order correctly), and the exit scale is a finite positive factor. A ray parallel to a
// slab (|dir| below kRobustMinDirection) with its origin exactly on a slab plane takes the closed-slab
// branch instead of relying on 0 * inf. `precise` keeps the compiler from rewriting
// (plane - origin) * invDir into plane * invDir - origin * invDir (a fused multiply-add), which would
// change the error the bound above accounts for.

// Direction components smaller than this in magnitude are treated as exactly 0 (the ray is parallel to
// that slab); rayInverseDirection replaces them by this value with their sign so that invDir stays
// finite. 1e-30 has a finite inverse (anything above 1 / FLT_MAX ~ 2.9e-39 has) and lies far below any
// component of a direction a renderer traces, other than an exact (or flushed) zero.
const float kRobustMinDirection = 1e-30;
// invDir components at least this large come from such a component: the factor 0.5 keeps the test
// independent of how a compiler rounds the constant.
const float kRobustParallelInverse = 0.5 / kRobustMinDirection;
// At least 1 + 2 gamma(3), gamma(n) = n u / (1 - n u), u = 2^-24 (Ize 2013; pbrt-v3 section 3.9.2).
// 1 + 2 gamma(3) = 1.00000035762793 lies just above the float 1 + 6u, so the next float up, 1 + 8u, is
// used: the spare u (more than half an ulp of the product) also covers the rounding of the product
// tFar * kRobustExitScale itself. The literal 1.0000004768371582 is exactly 1 + 8u.
const float kRobustExitScale = 1.0000004768371582;

// The invDir every intersectAabb call of one ray shares: finite, never NaN.
vec3 rayInverseDirection(vec3 dir) {
  vec3 tiny = mix(vec3(kRobustMinDirection), vec3(-kRobustMinDirection), lessThan(dir, vec3(0.0)));
  return 1.0 / mix(dir, tiny, lessThan(abs(dir), vec3(kRobustMinDirection)));
}

// Does origin + t * dir, t in [tMin, tMax], meet the box [bmin, bmax], conservatively (never a false
// miss; a near miss may count as a hit)? tEnter: where the ray enters it (clamped to tMin), a lower
// bound of the exact entry. invDir must come from rayInverseDirection.
bool intersectAabb(vec3 origin, vec3 invDir, vec3 bmin, vec3 bmax, float tMin, float tMax, out float tEnter) {
  precise vec3 t0 = (bmin - origin) * invDir;
  precise vec3 t1 = (bmax - origin) * invDir;
  vec3 tNear = min(t0, t1);
  precise vec3 tFar = max(t0, t1) * kRobustExitScale;
  // Parallel to a slab: inside the closed slab for every t or for none.
  bvec3 parallel = greaterThanEqual(abs(invDir), vec3(kRobustParallelInverse));
  bvec3 inSlab = equal(clamp(origin, bmin, bmax), origin);
  tNear = mix(tNear, mix(vec3(INF), vec3(-INF), inSlab), parallel);
  tFar = mix(tFar, mix(vec3(-INF), vec3(INF), inSlab), parallel);
  tEnter = max(max(tNear.x, tNear.y), max(tNear.z, tMin));
  float tExit = min(min(tFar.x, tFar.y), min(tFar.z, tMax));
  return tEnter <= tExit;
}
