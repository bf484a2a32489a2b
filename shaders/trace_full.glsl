// trace_full.glsl — Whitted ray tracing as an iterative loop with an explicit ray stack: where a
// surface both reflects and refracts, BOTH branches are traced, weighted by Schlick's Fresnel term.
// A path holds at most MAX_DEPTH segments (the primary ray is segment 1). C++ mirror: tracer.hpp.

// Contributions below this weight are dropped: after clamping to [0,1] and 8-bit quantisation a
// branch weighing 1/1024 changes a pixel by at most 1/4 of a step. Bounds the 2^depth blow-up.
#define MIN_BRANCH_WEIGHT (1.0 / 1024.0)

// With TEXTURE_LOD each ray carries its cone (width at its origin, spread angle: texture_lod.glsl).
#ifdef TEXTURE_LOD
#define CONE_ARG(c) , c
#else
#define CONE_ARG(c)
#endif

struct PathVertex {
  Ray ray;
  vec3 weight;
  int depth;
#ifdef TEXTURE_LOD
  vec2 cone;
#endif
};

vec3 radiance(Ray primary) {
  vec3 color = vec3(0.0);
  // Depth-first: each pop pushes at most two rays one level deeper, so at most one pending ray per
  // level plus the current one: MAX_DEPTH + 1 entries can never overflow.
  PathVertex stack[MAX_DEPTH + 1];
  int sp = 0;
  stack[sp++] = PathVertex(primary, vec3(1.0), 1 CONE_ARG(vec2(0.0, g_pixelSpread)));
  while (sp > 0) {
    PathVertex v = stack[--sp];
    Hit h;
    const bool found = intersectScene(v.ray, INF, h);
#ifdef PRIMARY_ID_OUT
    if (v.depth == 1) g_primaryId = found ? h.id : -1;
#endif
    if (!found) {
#ifdef TEXTURE_LOD
      color += v.weight * worldRadianceCone(v.ray.dir, v.cone.y);
#else
      color += v.weight * worldRadiance(v.ray.dir);
#endif
      continue;
    }
    MaterialData m = u_materials[h.material];
    vec3 dir = normalize(v.ray.dir);
    vec3 p = v.ray.origin + h.t * v.ray.dir;
    float magnitude = hitMagnitude(v.ray, h.t);
    Scatter s = scatterAt(m, h, dir);
#ifdef TEXTURE_LOD
    vec2 cone = coneAt(v.cone, h.t * length(v.ray.dir));
    if (s.kLocal > 0.0)
      color += v.weight * s.kLocal * shadeLocal(m, surfaceAlbedoCone(m, h, dir, cone.x), p, magnitude, s.n, dir);
#else
    if (s.kLocal > 0.0) color += v.weight * s.kLocal * shadeLocal(m, surfaceAlbedo(m, h.uv), p, magnitude, s.n, dir);
#endif
#if MAX_DEPTH > 1
    if (v.depth >= MAX_DEPTH) continue;
    vec3 wt = v.weight * s.kt;
    if (max(max(wt.r, wt.g), wt.b) > MIN_BRANCH_WEIGHT)
      stack[sp++] = PathVertex(Ray(offsetRayOrigin(p, -s.n, magnitude), s.refracted), wt, v.depth + 1
                                 CONE_ARG(refractedCone(m, h, s, dir, cone)));
    vec3 wr = v.weight * s.kr;
    if (max(max(wr.r, wr.g), wr.b) > MIN_BRANCH_WEIGHT)
      stack[sp++] = PathVertex(Ray(offsetRayOrigin(p, s.n, magnitude), reflect(dir, s.n)), wr, v.depth + 1
                                 CONE_ARG(reflectedCone(h, s, cone)));
#endif
  }
  return color;
}
