// trace_rays.glsl — `bvhlab trace`: one compute invocation per ray of a buffer, through the chosen
// traversal kernel (closest hit, or any hit with ANY_HIT), no shading. Rays and results live in shader
// storage buffers (layouts: traversal/ray_batch.hpp). C++ side: render/ray_tracer_gl.hpp.
//   result i = (found, original triangle id, floatBits(t), instance id)   [any hit: (found, 0, 0, 0)]
//   (instance id: a two-level tree's (traversal/two_level.glsl), 0 for a flat tree or a miss)
//   counts i = (node visits, triangle tests, stack overflow, box tests)  [COUNT_STATS only]
//   over a two-level tree (TWO_LEVEL) two per ray: counts 2i as above for the BLAS walks, counts 2i+1 =
//   (TLAS node visits, instance tests, 0, TLAS box tests)
//
// PERSISTENT_THREADS (traversal/kernels.hpp persistentThreadsOn: which kernels, and why not on
// llvmpipe): Aila & Laine's persistent threads. The host launches a fixed number of workgroups
// (render/ray_tracer_gl.cpp) and every invocation loops, taking its next ray from the atomic counter
// `nextRay` until the rays run out. Where
// GL_KHR_shader_subgroup_ballot is available the subgroup's active invocations take one batch of
// consecutive rays with one atomicAdd (the paper's per-warp fetch), ray base + rank among the active
// lanes; elsewhere each invocation takes one ray per atomicAdd. Either way each ray is traced by exactly
// one invocation with the per-ray counters reset, so results and counts are those of one invocation per
// ray.

layout(local_size_x = COMPUTE_LANES) in;  // COMPUTE_LANES: assembleRayTracer (render/ray_tracer_gl.cpp's kLocalSize)
layout(std430, binding = 0) readonly buffer RayBuffer { vec4 rays[]; };
layout(std430, binding = 1) writeonly buffer ResultBuffer { uvec4 results[]; };
#ifdef COUNT_STATS
layout(std430, binding = 2) writeonly buffer CountBuffer { uvec4 counts[]; };
#endif
#ifdef PERSISTENT_THREADS
layout(std430, binding = 3) coherent buffer RayCounter { uint nextRay; };  // zeroed before each dispatch
#endif
uniform int u_count;

void traceRay(int i) {
#ifdef PERSISTENT_THREADS
  // One invocation traces many rays: the counters are per ray.
  g_nodeVisits = 0u;
  g_triTests = 0u;
  g_boxTests = 0u;
  g_stackOverflow = false;
#ifdef TWO_LEVEL
  g_tlasNodeVisits = 0u;
  g_tlasBoxTests = 0u;
  g_instanceTests = 0u;
#endif
#endif
  Ray ray = Ray(rays[2 * i].xyz, rays[2 * i + 1].xyz);
  float tMin = rays[2 * i].w, tMax = rays[2 * i + 1].w;
#ifdef ANY_HIT
  bool found = traceAny(ray, tMin, tMax);
  results[i] = uvec4(found ? 1u : 0u, 0u, 0u, 0u);
#else
  MeshHit hit;
  bool found = traceClosest(ray, tMin, tMax, hit);
  uint primitive = 0u, material, mesh;
  if (found) loadTriangleIds(hit.tri, primitive, material, mesh);
  uint instance = 0u;
#ifdef TWO_LEVEL
  if (found) instance = instanceId(g_instance);
#endif
  results[i] = uvec4(found ? 1u : 0u, primitive, floatBitsToUint(found ? hit.t : tMax), instance);
#endif
#ifdef COUNT_STATS
#ifdef TWO_LEVEL
  counts[2 * i] = uvec4(g_nodeVisits, g_triTests, g_stackOverflow ? 1u : 0u, g_boxTests);
  counts[2 * i + 1] = uvec4(g_tlasNodeVisits, g_instanceTests, 0u, g_tlasBoxTests);
#else
  counts[i] = uvec4(g_nodeVisits, g_triTests, g_stackOverflow ? 1u : 0u, g_boxTests);
#endif
#endif
}

void main() {
#ifdef PERSISTENT_THREADS
  while (true) {
#ifdef GL_KHR_shader_subgroup_ballot
    uvec4 active = subgroupBallot(true);
    uint base = 0u;
    if (subgroupElect()) base = atomicAdd(nextRay, subgroupBallotBitCount(active));
    uint next = subgroupBroadcastFirst(base) + subgroupBallotExclusiveBitCount(active);
#else
    uint next = atomicAdd(nextRay, 1u);
#endif
    if (next >= uint(u_count)) break;
    traceRay(int(next));
  }
#else
  int i = int(gl_GlobalInvocationID.x);
  if (i < u_count) traceRay(i);
#endif
}
