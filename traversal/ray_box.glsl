// ray_box.glsl — the slab test (Kay & Kajiya 1986; branch-free min/max form as in Williams et al.
// 2005). A replacement box test (e.g. Ize's robust slabs) is a file providing the same two
// functions. C++ mirror: ray_box.hpp.

// Direction components smaller than this in magnitude are treated as exactly 0: the ray is then
// parallel to that slab and inside it for every t or for none. rayInverseDirection replaces them by
// this value (negative ones keep their sign) so that invDir stays finite: an infinite inverse would
// make (plane - origin) = 0 into 0 * inf = NaN. 1e-30 has a finite inverse (anything above
// 1 / FLT_MAX ~ 2.9e-39 does) and lies far below any component of a direction a renderer traces,
// other than an exact (or flushed) zero.
const float kMinDirectionComponent = 1e-30;
// invDir components at least this large come from such a component (or from one below 2e-30, as
// negligible): the factor 0.5 keeps the test independent of how a compiler rounds the constant.
const float kParallelInverse = 0.5 / kMinDirectionComponent;

// The invDir every intersectAabb call of one ray shares: finite, never NaN.
vec3 rayInverseDirection(vec3 dir) {
  vec3 tiny = mix(vec3(kMinDirectionComponent), vec3(-kMinDirectionComponent), lessThan(dir, vec3(0.0)));
  return 1.0 / mix(dir, tiny, lessThan(abs(dir), vec3(kMinDirectionComponent)));
}

// Does origin + t * dir, t in [tMin, tMax], meet the box [bmin, bmax]? tEnter: where the ray enters
// it (clamped to tMin). invDir must come from rayInverseDirection.
bool intersectAabb(vec3 origin, vec3 invDir, vec3 bmin, vec3 bmax, float tMin, float tMax, out float tEnter) {
  vec3 t0 = (bmin - origin) * invDir;
  vec3 t1 = (bmax - origin) * invDir;
  vec3 tNear = min(t0, t1);
  vec3 tFar = max(t0, t1);
  // Parallel to a slab, the products above would turn an origin lying exactly on the slab's far
  // plane into an exit at t = 0; the ray is in the (closed) slab for all t or for none instead.
  bvec3 parallel = greaterThanEqual(abs(invDir), vec3(kParallelInverse));
  bvec3 inSlab = equal(clamp(origin, bmin, bmax), origin);
  tNear = mix(tNear, mix(vec3(INF), vec3(-INF), inSlab), parallel);
  tFar = mix(tFar, mix(vec3(-INF), vec3(INF), inSlab), parallel);
  tEnter = max(max(tNear.x, tNear.y), max(tNear.z, tMin));
  float tExit = min(min(tFar.x, tFar.y), min(tFar.z, tMax));
  return tEnter <= tExit;
}
