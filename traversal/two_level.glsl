// two_level.glsl — traceClosest / traceAny over a two-level tree (layout/pack_two_level.hpp: a TLAS
// over instance records, each naming a BLAS and its transform, all in one NODE stream). C++ mirror:
// two_level.hpp.
//
// One module for every kernel that has a two-level walk: the assembler (shaders/assemble.cpp,
// appendKernel) puts the kernel's file in twice, once before this module as
//   #define KERNEL_WALK blasWalk    #define KERNEL_LEAF_TEST testTriangle
// and once after it as
//   #define KERNEL_WALK tlasWalk    #define KERNEL_LEAF_TEST testInstance
// with the TLAS copy's counters renamed (g_nodeVisits -> g_tlasNodeVisits, g_boxTests ->
// g_tlasBoxTests, g_triTests -> g_instanceTests). GLSL has no recursion and no function pointers, so
// the kernel's walk exists as two functions, both compiled from the one file; each walk starts at
// the `root` it is given. The flat kernels assemble the file once, as before (no TWO_LEVEL).
//
// Counters: g_nodeVisits, g_boxTests, g_triTests count the BLAS walks (summed over the instances a
// ray enters), g_tlasNodeVisits, g_tlasBoxTests, g_instanceTests the TLAS walk, each by the kernel's
// own definitions (its file's header); an instance test = one testInstance call.

uint g_tlasNodeVisits = 0u;
uint g_tlasBoxTests = 0u;
uint g_instanceTests = 0u;
// After traceClosest: the record (layout/pack_two_level.hpp) of the closest hit's instance, -1 when
// nothing was hit. instanceNormalToWorld and instanceId take it.
int g_instance = -1;

const int kInstanceTexels = 8;  // = bvhlab::kInstanceTexels
int g_blasTri = -1;               // the triangle of the last hit a BLAS walk returned
bool g_twoLevelAnyHit = false;    // the walk the entry point runs: the BLAS walks stop at a first hit too

bool tlasWalk(Ray ray, int root, float tMin, float tMax, bool anyHit, out MeshHit hit);

// The ray in instance `record`'s object space: o' = L^-1 (o - T), d' = L^-1 d. The translation is
// taken off first: o - T is exact when o and T are within a factor 2 of each other (Sterbenz), and
// otherwise rounded at the magnitude of |o - T|, where the world->object map's own translation
// (-L^-1 T, of the magnitude of T) would cancel against L^-1 o at the magnitude of |o| (measured in
// tests/test_two_level.cpp). d' is not renormalised: t along it is world t.
Ray instanceRay(Ray ray, int record, out int root) {
  int base = kInstanceTexels * record;
  vec3 r0 = uintBitsToFloat(fetchNode(base + 0).xyz);
  vec3 r1 = uintBitsToFloat(fetchNode(base + 1).xyz);
  vec3 r2 = uintBitsToFloat(fetchNode(base + 2).xyz);
  uvec4 place = fetchNode(base + 6);
  root = int(place.w);
  precise vec3 p = ray.origin - uintBitsToFloat(place.xyz);
  precise vec3 o = vec3(r0.x * p.x + r0.y * p.y + r0.z * p.z, r1.x * p.x + r1.y * p.y + r1.z * p.z,
                        r2.x * p.x + r2.y * p.y + r2.z * p.z);
  vec3 d = ray.dir;
  precise vec3 od = vec3(r0.x * d.x + r0.y * d.y + r0.z * d.z, r1.x * d.x + r1.y * d.y + r1.z * d.z,
                         r2.x * d.x + r2.y * d.y + r2.z * d.z);
  return Ray(o, od);
}

// The TLAS walk's leaf test: the instance's BLAS walked with the ray in object space, over (tMin,
// tMax). On a hit, t and bary are the BLAS hit's and g_blasTri its triangle.
bool testInstance(Ray ray, int record, float tMin, float tMax, out float t, out vec2 bary) {
  int root;
  Ray objectRay = instanceRay(ray, record, root);
  MeshHit hit;
  bool found = blasWalk(objectRay, root, tMin, tMax, g_twoLevelAnyHit, hit);
  t = hit.t;
  bary = hit.bary;
  if (found) g_blasTri = hit.tri;
  return found;
}

// Closest hit with tMin < t < tMax: hit.tri is the TRIANGLE-stream triangle (loadTriangleIds gives the
// mesh's own triangle id), g_instance its instance's record; hit.tri = -1, hit.t = tMax on a miss.
bool traceClosest(Ray ray, float tMin, float tMax, out MeshHit hit) {
  g_twoLevelAnyHit = false;
  int root = int(fetchNode(0).x);
  bool found = tlasWalk(ray, root, tMin, tMax, false, hit);
  g_instance = found ? hit.tri : -1;  // the TLAS walk's "triangle" is the record
  hit.tri = found ? g_blasTri : -1;
  return found;
}

// Any hit with tMin < t < tMax (shadow rays).
bool traceAny(Ray ray, float tMin, float tMax) {
  g_twoLevelAnyHit = true;
  MeshHit hit;
  return tlasWalk(ray, int(fetchNode(0).x), tMin, tMax, true, hit);
}

// An object-space normal of instance `record` in world space: by the inverse transpose of L, i.e.
// transpose(L^-1) n (not normalised).
vec3 instanceNormalToWorld(int record, vec3 n) {
  int base = kInstanceTexels * record;
  vec3 r0 = uintBitsToFloat(fetchNode(base + 0).xyz);
  vec3 r1 = uintBitsToFloat(fetchNode(base + 1).xyz);
  vec3 r2 = uintBitsToFloat(fetchNode(base + 2).xyz);
  return r0 * n.x + r1 * n.y + r2 * n.z;
}

// The caller's instance id of a record (its index in the instance list packTwoLevel was given).
uint instanceId(int record) { return fetchNode(kInstanceTexels * record + 7).x; }

// The scene material the instance's triangles are shaded with (a shared BLAS's triangles hold one
// instance's).
uint instanceMaterial(int record) { return fetchNode(kInstanceTexels * record + 7).w; }

// An object-space point of instance `record` in world space: L p + T (texels 3..5: row i of L, T_i).
vec3 instancePointToWorld(int record, vec3 p) {
  int base = kInstanceTexels * record;
  vec4 r0 = uintBitsToFloat(fetchNode(base + 3));
  vec4 r1 = uintBitsToFloat(fetchNode(base + 4));
  vec4 r2 = uintBitsToFloat(fetchNode(base + 5));
  return vec3(dot(r0.xyz, p) + r0.w, dot(r1.xyz, p) + r1.w, dot(r2.xyz, p) + r2.w);
}
