// common.glsl — types and counters every module uses. C++ mirror: shaders/common.hpp.
struct Ray {
  vec3 origin;
  vec3 dir;  // not necessarily unit length: object-space rays keep world t
};

// Closest mesh hit: `tri` indexes the TRIANGLE stream (packed order), bary = (u, v) of v1, v2.
struct MeshHit {
  float t;
  int tri;
  vec2 bary;
};

// Per-pixel traversal statistics, written to the stats render target.
uint g_nodeVisits = 0u;
uint g_triTests = 0u;
uint g_boxTests = 0u;  // ray-box tests (intersectAabb calls): a wide node visit tests several boxes
uint g_meshRays = 0u;  // rays traced into the mesh BVH (closest + any)
bool g_stackOverflow = false;  // a kernel sets this instead of overflowing silently

const float INF = 1.0 / 0.0;
const float PI = 3.14159265358979;
