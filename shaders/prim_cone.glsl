// prim_cone.glsl — ray vs the capped cone with apex (0,1,0) and base of radius 1 at y = -1.
// C++ mirror: shaders/primitives.hpp. Conventions (t, tMin/tMax, outward normal, NaN) as in prim_sphere.glsl.
//
// The solid is convex: {4 (x^2 + z^2) <= (1 - y)^2} ∩ {|y| <= 1}. The first set is the double cone; the slab
// keeps only its lower nappe (the upper one meets the slab in the apex alone), so the ray's interval inside
// the solid is (its interval inside the double cone's nappe) ∩ (its interval inside the slab), and the hit
// is taken from the interval ends as for the cylinder (no cracks at the rim).
// Along the ray, f(s) = 4 |xz|^2 - (1 - y)^2 = A s^2 + 2 B s + C:
//   A > 0 (ray shallower than the cone's slope): f <= 0 on [s0, s1];
//   A < 0 (steeper): f <= 0 on (-inf, s0] and [s1, inf), one half-line per nappe; a ray going down (d.y < 0)
//         ends in the lower nappe, so it keeps [s1, inf), a ray going up keeps (-inf, s0];
//   A == 0 (parallel to a generator): f is linear, one half-line.
// Precision: closest-approach origin (as in prim_sphere.glsl; bounding sphere radius sqrt(2)) and the
// stable quadratic formula. For A < 0 the discriminant is >= 0 in exact arithmetic (such a line crosses
// both nappes), so a slightly negative rounded value near the apex is clamped to 0. Near the apex the two
// roots (one per nappe) nearly coincide, and a near-double root of a float quadratic is good to about
// sqrt(eps): hits within ~0.01 of the apex are placed to ~sqrt(eps) (measured <= 0.2 sqrt(eps)), elsewhere
// to a few eps.
bool intersectCone(Ray ray, float tMin, float tMax, out float t, out vec3 normal, out vec2 uv) {
  t = 0.0;
  normal = vec3(0.0, 1.0, 0.0);
  uv = vec2(0.0);
  float dd = dot(ray.dir, ray.dir);
  if (!(dd > 0.0 && dd < INF)) return false;  // zero, overflowing or NaN direction
  float tc = -dot(ray.origin, ray.dir) / dd;
  vec3 p = ray.origin + tc * ray.dir;
  if (!(dot(p, p) <= 2.0)) return false;  // misses the bounding sphere (or NaN)
  float w = 1.0 - p.y;  // depth below the apex; along the ray it is w - s d.y
  float A = 4.0 * (ray.dir.x * ray.dir.x + ray.dir.z * ray.dir.z) - ray.dir.y * ray.dir.y;
  float B = 4.0 * (p.x * ray.dir.x + p.z * ray.dir.z) + w * ray.dir.y;
  float C = 4.0 * (p.x * p.x + p.z * p.z) - w * w;
  float sideIn = -INF;
  float sideOut = INF;
  if (A != 0.0) {
    float disc = B * B - A * C;
    if (A < 0.0) disc = max(disc, 0.0);
    if (!(disc >= 0.0)) return false;
    float q = -(B + (B >= 0.0 ? sqrt(disc) : -sqrt(disc)));  // B >= 0.0: GLSL's sign(0.0) is 0.0
    float s0 = q / A;
    float s1 = q != 0.0 ? C / q : s0;  // q == 0: double root at s = 0
    float sLo = min(s0, s1);
    float sHi = max(s0, s1);
    if (A > 0.0) {
      sideIn = sLo;
      sideOut = sHi;
    } else if (ray.dir.y < 0.0) {
      sideIn = sHi;
    } else {
      sideOut = sLo;
    }
  } else if (B != 0.0) {
    float s0 = -C / (2.0 * B);  // f = 2 B s + C <= 0
    if (B > 0.0) {
      sideOut = s0;
    } else {
      sideIn = s0;
    }
  } else if (!(C <= 0.0)) {
    return false;  // f is a positive constant: never inside
  }
  float capIn = -INF;
  float capOut = INF;
  if (ray.dir.y != 0.0) {
    float s0 = (-1.0 - p.y) / ray.dir.y;
    float s1 = (1.0 - p.y) / ray.dir.y;
    capIn = min(s0, s1);
    capOut = max(s0, s1);
  } else if (!(abs(p.y) <= 1.0)) {
    return false;  // parallel to the base, above the apex or below the base
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
    onCap = capIn > sideIn;
  } else if (tOut > tMin && tOut < tMax) {
    t = tOut;
    s = sOut;
    onCap = capOut < sideOut;
  } else {
    return false;
  }
  vec3 hit = p + s * ray.dir;
  float r = length(hit.xz);
  if (onCap && hit.y < 0.0) {  // the base
    normal = vec3(0.0, -1.0, 0.0);
    uv = clamp(0.5 * vec2(hit.x, hit.z) + 0.5, 0.0, 1.0);  // planar, oriented like the box's -Y face
  } else {
    // Side, or the slab's top plane, which the solid touches only at the apex. Gradient of 2 r - (1 - y),
    // scaled by r: (2 x / r, 1, 2 z / r); at the apex (r == 0) the normal is undefined and +Y is used.
    normal = r > 0.0 ? vec3(2.0 * hit.x / r, 1.0, 2.0 * hit.z / r) : vec3(0.0, 1.0, 0.0);
    float phi = r > 0.0 ? atan(hit.x, hit.z) : 0.0;  // atan(0, 0) is undefined
    uv = clamp(vec2(0.5 + phi / (2.0 * PI), 0.5 + 0.5 * hit.y), 0.0, 1.0);
  }
  return true;
}
