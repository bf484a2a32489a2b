// triangles_indexed.glsl — the `indexed` triangle format (layout/triangle_formats.hpp): one TRIANGLE
// texel of vertex indices, welded vertices with exact positions and oct-encoded normals (VERTEX),
// half-float uvs and ids (ATTRIBUTE, 2 vertices a texel). Needs a storage module
// (fetchTriangle/fetchVertex/fetchAttribute) and a ray_triangle*.glsl (intersectTriangle).
// C++ mirror: triangles_indexed.hpp.
const uint kFlatNormal = 0x80008000u;  // = bvhlab::kFlatNormal: the corner takes the geometric normal

// Vertices of TRIANGLE-stream triangle `tri`: the input's, exactly (the watertight test works).
void loadTriangle(int tri, out vec3 v0, out vec3 v1, out vec3 v2) {
  uvec4 index = fetchTriangle(tri);
  v0 = uintBitsToFloat(fetchVertex(int(index.x)).xyz);
  v1 = uintBitsToFloat(fetchVertex(int(index.y)).xyz);
  v2 = uintBitsToFloat(fetchVertex(int(index.z)).xyz);
}

bool testTriangle(Ray ray, int tri, float tMin, float tMax, out float t, out vec2 bary) {
  vec3 v0, v1, v2;
  loadTriangle(tri, v0, v1, v2);
  return intersectTriangle(ray, v0, v1, v2, tMin, tMax, t, bary);
}

// Vertex k's two ATTRIBUTE words: (packHalf2x16(uv), material | mesh << 16).
uvec2 vertexWords(uint k) {
  uvec4 texel = fetchAttribute(int(k >> 1));
  return (k & 1u) == 0u ? texel.xy : texel.zw;
}

void loadTriangleIds(int tri, out uint primitive, out uint material, out uint mesh) {
  uvec4 index = fetchTriangle(tri);
  uint ids = vertexWords(index.x).y;
  primitive = index.w;
  material = ids & 0xFFFFu;
  mesh = ids >> 16;
}

// Cigolle et al. 2014's octahedral decoding (signNotZero: a coordinate of 0 folds to +).
vec3 decodeOctNormal(uint code) {
  vec2 e = unpackSnorm2x16(code);
  vec3 v = vec3(e.x, e.y, 1.0 - abs(e.x) - abs(e.y));
  if (v.z < 0.0) {
    vec2 folded = vec2((1.0 - abs(v.y)) * (v.x >= 0.0 ? 1.0 : -1.0), (1.0 - abs(v.x)) * (v.y >= 0.0 ? 1.0 : -1.0));
    v.x = folded.x;
    v.y = folded.y;
  }
  return normalize(v);
}

// As layout/soup.cpp's geometricNormal: +Z where the triangle has no plane.
vec3 flatNormal(vec3 v0, vec3 v1, vec3 v2) {
  vec3 n = cross(v1 - v0, v2 - v0);
  float len = length(n);
  return len > 0.0 && !isinf(len) ? n / len : vec3(0.0, 0.0, 1.0);
}

// Interpolated normal (not normalised, see triangles_raw.glsl) and uv at bary.
void loadAttributes(int tri, vec2 bary, out vec3 normal, out vec2 uv) {
  uvec4 index = fetchTriangle(tri);
  uvec4 p0 = fetchVertex(int(index.x));
  uvec4 p1 = fetchVertex(int(index.y));
  uvec4 p2 = fetchVertex(int(index.z));
  vec3 geometric = vec3(0.0);
  if (p0.w == kFlatNormal || p1.w == kFlatNormal || p2.w == kFlatNormal)
    geometric = flatNormal(uintBitsToFloat(p0.xyz), uintBitsToFloat(p1.xyz), uintBitsToFloat(p2.xyz));
  vec3 n0 = p0.w == kFlatNormal ? geometric : decodeOctNormal(p0.w);
  vec3 n1 = p1.w == kFlatNormal ? geometric : decodeOctNormal(p1.w);
  vec3 n2 = p2.w == kFlatNormal ? geometric : decodeOctNormal(p2.w);
  vec2 uv0 = unpackHalf2x16(vertexWords(index.x).x);
  vec2 uv1 = unpackHalf2x16(vertexWords(index.y).x);
  vec2 uv2 = unpackHalf2x16(vertexWords(index.z).x);
  float w = 1.0 - bary.x - bary.y;
  normal = w * n0 + bary.x * n1 + bary.y * n2;
  uv = w * uv0 + bary.x * uv1 + bary.y * uv2;
}
