// trace_full.glsl — Whitted ray tracing as an iterative loop with an explicit ray stack: where a
// surface both reflects and refracts, BOTH branches are traced, weighted by Schlick's Fresnel term.
// A path holds at most MAX_DEPTH segments (the primary ray is segment 1). C++ mirror: tracer.hpp.

// Contributions below this weight are dropped: after clamping to [0,1] and 8-bit quantisation a
// branch weighing 1/1024 changes a pixel by at most 1/4 of a step. Bounds the 2^depth blow-up.
#define MIN_BRANCH_WEIGHT (1.0 / 1024.0)

struct PathVertex {
  Ray ray;
  vec3 weight;
  int depth;
};

vec3 radiance(Ray primary) {
  vec3 color = vec3(0.0);
  // Depth-first: each pop pushes at most two rays one level deeper, so at most one pending ray per
  // level plus the current one: MAX_DEPTH + 1 entries can never overflow.
  PathVertex stack[MAX_DEPTH + 1];
  int sp = 0;
  stack[sp++] = PathVertex(primary, vec3(1.0), 1);
  while (sp > 0) {
    PathVertex v = stack[--sp];
    Hit h;
    if (!intersectScene(v.ray, INF, h)) {
      color += v.weight * worldRadiance(v.ray.dir);
      continue;
    }
    MaterialData m = u_materials[h.material];
    vec3 dir = normalize(v.ray.dir);
    vec3 p = v.ray.origin + h.t * v.ray.dir;
    float magnitude = hitMagnitude(v.ray, h.t);
    Scatter s = scatterAt(m, h, dir);
    if (s.kLocal > 0.0) color += v.weight * s.kLocal * shadeLocal(m, surfaceAlbedo(m, h.uv), p, magnitude, s.n, dir);
#if MAX_DEPTH > 1
    if (v.depth >= MAX_DEPTH) continue;
    vec3 wt = v.weight * s.kt;
    if (max(max(wt.r, wt.g), wt.b) > MIN_BRANCH_WEIGHT)
      stack[sp++] = PathVertex(Ray(offsetRayOrigin(p, -s.n, magnitude), s.refracted), wt, v.depth + 1);
    vec3 wr = v.weight * s.kr;
    if (max(max(wr.r, wr.g), wr.b) > MIN_BRANCH_WEIGHT)
      stack[sp++] = PathVertex(Ray(offsetRayOrigin(p, s.n, magnitude), reflect(dir, s.n)), wr, v.depth + 1);
#endif
  }
  return color;
}
