// trace_rays.glsl — `bvhlab trace`: one compute invocation per ray of a buffer, through the chosen
// traversal kernel (closest hit, or any hit with ANY_HIT), no shading. Rays and results live in shader
// storage buffers (layouts: traversal/ray_batch.hpp). C++ side: render/ray_tracer_gl.hpp.
//   result i = (found, original triangle id, floatBits(t), instance id)   [any hit: (found, 0, 0, 0)]
//   (instance id: a two-level tree's (traversal/two_level.glsl), 0 for a flat tree or a miss)
//   counts i = (node visits, triangle tests, stack overflow, box tests)  [COUNT_STATS only]
//   over a two-level tree (TWO_LEVEL) two per ray: counts 2i as above for the BLAS walks, counts 2i+1 =
//   (TLAS node visits, instance tests, 0, TLAS box tests)

layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer RayBuffer { vec4 rays[]; };
layout(std430, binding = 1) writeonly buffer ResultBuffer { uvec4 results[]; };
#ifdef COUNT_STATS
layout(std430, binding = 2) writeonly buffer CountBuffer { uvec4 counts[]; };
#endif
uniform int u_count;

void main() {
  int i = int(gl_GlobalInvocationID.x);
  if (i >= u_count) return;
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
