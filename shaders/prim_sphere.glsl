// prim_sphere.glsl — ray vs the unit sphere at the origin. C++ mirror: shaders/primitives.hpp.
//
// Conventions shared by every prim_*.glsl (object space, see datasets/scene.hpp):
// - `ray.dir` is not unit length; t is the parameter of ray.origin + t * ray.dir (the world t).
// - Returns the nearest hit with tMin < t < tMax. A ray starting inside a closed primitive hits the inside
//   of its surface; `normal` is always the OUTWARD geometric normal (length > 0, not normalised).
// - Every comparison that decides a hit is written so that a NaN makes it fail (a miss).
//
// Precision: the origin is first moved to the ray's closest approach to the centre, p = o + tc * d
// (Hearn & Baker; Haines et al., "Precision Improvements for Ray/Sphere Intersection", Ray Tracing Gems
// ch. 7). The discriminant then comes from 1 - |p|^2, two O(1) numbers, instead of b^2 - a c of two numbers
// of size |o|^2 that cancel for far origins. The roots s (t = tc + s) use the stable quadratic formula
// q = -(b + sign(b) sqrt(disc)), s0 = q / a, s1 = c / q, which never subtracts nearly equal numbers.
bool intersectSphere(Ray ray, float tMin, float tMax, out float t, out vec3 normal, out vec2 uv) {
  t = 0.0;
  normal = vec3(0.0, 1.0, 0.0);
  uv = vec2(0.0);
  float a = dot(ray.dir, ray.dir);
  if (!(a > 0.0 && a < INF)) return false;  // zero, overflowing or NaN direction
  float tc = -dot(ray.origin, ray.dir) / a;
  vec3 p = ray.origin + tc * ray.dir;
  // (a s^2 + 2 b s + c = 0 with the half-coefficient b.) b is ~0 by construction; keeping it absorbs
  // the rounding of p, so the roots stay those of the computed p.
  float b = dot(p, ray.dir);
  float c = dot(p, p) - 1.0;
  float disc = b * b - a * c;
  if (!(disc >= 0.0)) return false;  // the line misses the sphere (or NaN)
  // b >= 0.0 rather than sign(b): GLSL's sign(0.0) is 0.0, which would make q = 0 for b == 0.
  float q = -(b + (b >= 0.0 ? sqrt(disc) : -sqrt(disc)));
  float s0 = q / a;
  float s1 = q != 0.0 ? c / q : s0;  // q == 0 only for b == 0 and disc == 0: a double root at s = 0
  float sNear = min(s0, s1);
  float sFar = max(s0, s1);
  float tNear = tc + sNear;
  float tFar = tc + sFar;
  float s;
  if (tNear > tMin && tNear < tMax) {
    t = tNear;
    s = sNear;
  } else if (tFar > tMin && tFar < tMax) {  // the origin (or tMin) is inside: the far side
    t = tFar;
    s = sFar;
  } else {
    return false;
  }
  vec3 hit = p + s * ray.dir;  // from p, not from a far-away origin
  normal = hit;
  // Longitude from +Z towards +X (u grows to the right seen from outside, seam at -Z), latitude from -Y.
  // atan(0, 0) is undefined in GLSL: guard the poles.
  float phi = (hit.x != 0.0 || hit.z != 0.0) ? atan(hit.x, hit.z) : 0.0;
  // Latitude as atan(y, rho), not asin(y): better conditioned near the poles and more accurate on GPUs
  // (llvmpipe's asin put v off by up to 1.2e-4, its atan by 1e-5). rho and y are never both 0 here.
  float theta = atan(hit.y, length(hit.xz));
  uv = clamp(vec2(0.5 + phi / (2.0 * PI), 0.5 + theta / PI), 0.0, 1.0);
  return true;
}
