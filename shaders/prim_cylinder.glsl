// prim_cylinder.glsl — ray vs the capped cylinder x^2 + z^2 <= 1, |y| <= 1. C++ mirror: shaders/primitives.hpp.
// Conventions (t, tMin/tMax, outward normal, NaN) as in prim_sphere.glsl.
//
// The solid is convex: the ray's interval inside it is [sIn, sOut] = (interval inside the infinite
// cylinder) ∩ (interval inside the slab |y| <= 1). Taking the hit from the interval ends (instead of
// testing each side root and cap hit separately) leaves no crack along the rims.
// Precision: the origin is moved to the closest approach to the centre (as in prim_sphere.glsl), which
// rejects lines missing the bounding sphere (radius sqrt(2)) and leaves O(1) coefficients; the side
// quadratic uses the stable formula. A ray parallel to the axis (a == 0) is decided by c alone, so no
// 0/0 or x/0 ever reaches a comparison.
bool intersectCylinder(Ray ray, float tMin, float tMax, out float t, out vec3 normal, out vec2 uv) {
  t = 0.0;
  normal = vec3(0.0, 1.0, 0.0);
  uv = vec2(0.0);
  float dd = dot(ray.dir, ray.dir);
  if (!(dd > 0.0 && dd < INF)) return false;  // zero, overflowing or NaN direction
  float tc = -dot(ray.origin, ray.dir) / dd;
  vec3 p = ray.origin + tc * ray.dir;
  if (!(dot(p, p) <= 2.0)) return false;  // misses the bounding sphere (or NaN)
  // Side: (p + s d).xz inside the unit circle <=> a s^2 + 2 b s + c <= 0.
  float a = ray.dir.x * ray.dir.x + ray.dir.z * ray.dir.z;
  float b = p.x * ray.dir.x + p.z * ray.dir.z;
  float c = p.x * p.x + p.z * p.z - 1.0;
  float sideIn = -INF;
  float sideOut = INF;
  if (a > 0.0) {
    float disc = b * b - a * c;
    if (!(disc >= 0.0)) return false;
    float q = -(b + (b >= 0.0 ? sqrt(disc) : -sqrt(disc)));  // b >= 0.0: GLSL's sign(0.0) is 0.0
    float s0 = q / a;
    float s1 = q != 0.0 ? c / q : s0;  // q == 0: double root at s = 0
    sideIn = min(s0, s1);
    sideOut = max(s0, s1);
  } else if (!(c <= 0.0)) {
    return false;  // parallel to the axis, outside the side wall
  }
  // Caps: the slab |y| <= 1.
  float capIn = -INF;
  float capOut = INF;
  if (ray.dir.y != 0.0) {
    float s0 = (-1.0 - p.y) / ray.dir.y;
    float s1 = (1.0 - p.y) / ray.dir.y;
    capIn = min(s0, s1);
    capOut = max(s0, s1);
  } else if (!(abs(p.y) <= 1.0)) {
    return false;  // parallel to the caps, above or below the cylinder
  }
  float sIn = max(sideIn, capIn);
  float sOut = min(sideOut, capOut);
  if (!(sIn <= sOut)) return false;
  float tIn = tc + sIn;
  float tOut = tc + sOut;
  float s;
  bool onCap;
  if (tIn > tMin && tIn < tMax) {
    t = tIn;
    s = sIn;
    onCap = capIn >= sideIn;
  } else if (tOut > tMin && tOut < tMax) {
    t = tOut;
    s = sOut;
    onCap = capOut <= sideOut;
  } else {
    return false;
  }
  vec3 hit = p + s * ray.dir;
  if (onCap) {
    float side = hit.y >= 0.0 ? 1.0 : -1.0;
    normal = vec3(0.0, side, 0.0);
    uv = vec2(hit.x, -side * hit.z);  // planar, oriented like the box's Y faces
    uv = clamp(0.5 * uv + 0.5, 0.0, 1.0);
  } else {
    normal = vec3(hit.x, 0.0, hit.z);  // |hit.xz| ~ 1 on the side
    float phi = (hit.x != 0.0 || hit.z != 0.0) ? atan(hit.x, hit.z) : 0.0;  // atan(0, 0) is undefined
    uv = clamp(vec2(0.5 + phi / (2.0 * PI), 0.5 + 0.5 * hit.y), 0.0, 1.0);
  }
  return true;
}
