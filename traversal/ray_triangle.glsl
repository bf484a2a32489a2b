// ray_triangle.glsl — Möller & Trumbore (1997), "Fast, minimum storage ray/triangle intersection".
// A replacement (e.g. the watertight test of Woop et al. 2013) is a file with the same function.
// C++ mirror: ray_triangle.hpp.

// The smallest normal float. 1 / det is finite for |det| at or above it; below it the quotients
// would overflow (GPUs flush such dets to 0 anyway). det == 0: the ray is parallel to the plane
// or the triangle has no area, and there is no single hit point.
const float kTriangleMinDet = 1.17549435e-38;

// Hit iff tMin < t < tMax and the hit point is inside the triangle (edges included).
// bary = (u, v): the weights of v1 and v2; v0 weighs 1 - u - v.
bool intersectTriangle(Ray ray, vec3 v0, vec3 v1, vec3 v2, float tMin, float tMax, out float t, out vec2 bary) {
  t = tMax;
  bary = vec2(0.0);
  vec3 e1 = v1 - v0;
  vec3 e2 = v2 - v0;
  vec3 p = cross(ray.dir, e2);
  float det = dot(e1, p);
  if (abs(det) < kTriangleMinDet) return false;
  float invDet = 1.0 / det;
  vec3 s = ray.origin - v0;
  float u = dot(s, p) * invDet;
  vec3 q = cross(s, e1);
  float v = dot(ray.dir, q) * invDet;
  t = dot(e2, q) * invDet;
  bary = vec2(u, v);
  return u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > tMin && t < tMax;
}
