// triangles_precomputed.glsl — the `precomputed` triangle format (layout/triangle_formats.hpp): v0,
// the edges e1, e2 and n = cross(e1, e2) stored, so the Moller-Trumbore test skips the two edge
// subtractions and one cross product. Needs a storage module and ray_triangle.glsl (kTriangleMinDet;
// the format is refused with the watertight test). C++ mirror: triangles_precomputed.hpp.

// Hit iff tMin < t < tMax and the hit point is inside the triangle (edges included), as
// ray_triangle.glsl's intersectTriangle; the same 3x3 system solved by Cramer's rule with the stored
// normal: det = -dot(dir, n), s = origin - v0, q = cross(s, dir), u = dot(e2, q) / det,
// v = -dot(e1, q) / det, t = dot(s, n) / det. A NaN anywhere fails every comparison: no hit.
bool testTriangle(Ray ray, int tri, float tMin, float tMax, out float t, out vec2 bary) {
  t = tMax;
  bary = vec2(0.0);
  vec3 v0 = uintBitsToFloat(fetchTriangle(4 * tri + 0).xyz);
  vec3 e1 = uintBitsToFloat(fetchTriangle(4 * tri + 1).xyz);
  vec3 e2 = uintBitsToFloat(fetchTriangle(4 * tri + 2).xyz);
  vec3 n = uintBitsToFloat(fetchTriangle(4 * tri + 3).xyz);
  float det = -dot(ray.dir, n);
  if (!(abs(det) >= kTriangleMinDet)) return false;
  float invDet = 1.0 / det;
  vec3 s = ray.origin - v0;
  vec3 q = cross(s, ray.dir);
  float u = dot(e2, q) * invDet;
  float v = -dot(e1, q) * invDet;
  t = dot(s, n) * invDet;
  bary = vec2(u, v);
  return u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > tMin && t < tMax;
}

// v0, v0 + e1, v0 + e2: the input vertices up to the rounding of the stored edges.
void loadTriangle(int tri, out vec3 v0, out vec3 v1, out vec3 v2) {
  v0 = uintBitsToFloat(fetchTriangle(4 * tri + 0).xyz);
  v1 = v0 + uintBitsToFloat(fetchTriangle(4 * tri + 1).xyz);
  v2 = v0 + uintBitsToFloat(fetchTriangle(4 * tri + 2).xyz);
}

void loadTriangleIds(int tri, out uint primitive, out uint material, out uint mesh) {
  primitive = fetchTriangle(4 * tri + 0).w;
  material = fetchTriangle(4 * tri + 1).w;
  mesh = fetchTriangle(4 * tri + 2).w;
}

// The ATTRIBUTE stream is raw's (see triangles_raw.glsl): the normal is interpolated, not normalised.
void loadAttributes(int tri, vec2 bary, out vec3 normal, out vec2 uv) {
  uvec4 t0 = fetchAttribute(4 * tri + 0);
  uvec4 t1 = fetchAttribute(4 * tri + 1);
  uvec4 t2 = fetchAttribute(4 * tri + 2);
  uvec4 t3 = fetchAttribute(4 * tri + 3);
  vec3 n0 = uintBitsToFloat(t0.xyz);
  vec3 n1 = uintBitsToFloat(t1.xyz);
  vec3 n2 = uintBitsToFloat(t2.xyz);
  vec2 uv0 = uintBitsToFloat(uvec2(t0.w, t1.w));
  vec2 uv1 = uintBitsToFloat(uvec2(t2.w, t3.x));
  vec2 uv2 = uintBitsToFloat(t3.yz);
  float w = 1.0 - bary.x - bary.y;
  normal = w * n0 + bary.x * n1 + bary.y * n2;
  uv = w * uv0 + bary.x * uv1 + bary.y * uv2;
}
