// prim_plane.glsl — ray vs the plane y = 0, |x|,|z| <= 1 unless `infinite`. C++ mirror: shaders/primitives.hpp.
// Conventions (t, tMin/tMax, NaN) as in prim_sphere.glsl. The plane is one-sided for the normal: it is +Y
// whichever side the ray comes from (the caller flips it for shading).
// A ray parallel to the plane misses, also one lying in it (it sees no surface to stop at). The hit is
// t = -o.y / d.y, a single rounding, so there is no cancellation to guard against.
bool intersectPlane(Ray ray, bool infinite, float tMin, float tMax, out float t, out vec3 normal, out vec2 uv) {
  t = 0.0;
  normal = vec3(0.0, 1.0, 0.0);
  uv = vec2(0.0);
  if (!(abs(ray.dir.y) > 0.0)) return false;  // parallel (or NaN; note NaN != 0.0 would be true)
  float tHit = -ray.origin.y / ray.dir.y;
  if (!(tHit > tMin && tHit < tMax)) return false;
  vec2 xz = ray.origin.xz + tHit * ray.dir.xz;
  if (!infinite && !(abs(xz.x) <= 1.0 && abs(xz.y) <= 1.0)) return false;
  t = tHit;
  // (x, z) from [-1, 1] to [0, 1]; the infinite plane repeats that tile.
  uv = infinite ? fract(0.5 * xz + 0.5) : clamp(0.5 * xz + 0.5, 0.0, 1.0);
  return true;
}
