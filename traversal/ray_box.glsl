// ray_box.glsl — the slab test (Kay & Kajiya 1986; branch-free min/max form as in Williams et al.
// 2005). A replacement box test (e.g. Ize's robust slabs) is a file providing the same two
// functions. C++ mirror: ray_box.hpp.

// Direction components smaller than this are replaced by it (keeping their sign) before inverting.
// An infinite inverse would turn (plane - origin) = 0 into 0 * inf = NaN, and NaN would decide the
// test. 1e-30 has a finite inverse (anything above 1 / FLT_MAX ~ 2.9e-39 does) and is far below any
// component of a direction a renderer traces, other than an exact (or flushed) zero.
const float kMinDirectionComponent = 1e-30;

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
  tEnter = max(max(tNear.x, tNear.y), max(tNear.z, tMin));
  float tExit = min(min(tFar.x, tFar.y), min(tFar.z, tMax));
  return tEnter <= tExit;
}
