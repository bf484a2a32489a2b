// triangles_raw.glsl — the `raw` triangle format (layout/layout.hpp describes its streams,
// layout/triangle_formats.hpp the formats): three vertices + ids, per-corner normals and uvs. Needs a
// storage module (fetchTriangle/fetchAttribute) and a ray_triangle*.glsl (intersectTriangle).
// C++ mirror: triangles_raw.hpp.

// Vertices of TRIANGLE-stream triangle `tri`.
void loadTriangle(int tri, out vec3 v0, out vec3 v1, out vec3 v2) {
  v0 = uintBitsToFloat(fetchTriangle(3 * tri + 0).xyz);
  v1 = uintBitsToFloat(fetchTriangle(3 * tri + 1).xyz);
  v2 = uintBitsToFloat(fetchTriangle(3 * tri + 2).xyz);
}

// Fetch and test: hit iff tMin < t < tMax, as intersectTriangle.
bool testTriangle(Ray ray, int tri, float tMin, float tMax, out float t, out vec2 bary) {
  vec3 v0, v1, v2;
  loadTriangle(tri, v0, v1, v2);
  return intersectTriangle(ray, v0, v1, v2, tMin, tMax, t, bary);
}

// The ids stored alongside the vertices: input triangle id, material index, mesh index.
void loadTriangleIds(int tri, out uint primitive, out uint material, out uint mesh) {
  primitive = fetchTriangle(3 * tri + 0).w;
  material = fetchTriangle(3 * tri + 1).w;
  mesh = fetchTriangle(3 * tri + 2).w;
}

// Shading normal and uv at barycentrics bary = (u, v) of v1, v2 (as MeshHit::bary). The normal is
// interpolated, NOT normalised: where opposed vertex normals cancel it can be zero, so the caller
// normalises after checking it against the geometric normal.
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
