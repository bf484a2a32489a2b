// trace_report.glsl — the report's Algorithm 1 compromise: one ray continues per pixel. Where a
// surface both reflects and refracts, the reflection is followed for ONE bounce only (its hit is
// shaded locally, or the world is seen) and the path continues along the refracted ray.
// C++ mirror: shaders/tracer.hpp.

#define MIN_BRANCH_WEIGHT (1.0 / 1024.0)

// One-bounce reflection: local shading of whatever the reflected ray sees ("getReflectedColor").
// With TEXTURE_LOD, `cone` is the ray's cone (width at its origin, spread: texture_lod.glsl).
#ifdef TEXTURE_LOD
vec3 reflectedColor(Ray ray, vec2 cone) {
  Hit h;
  if (!intersectScene(ray, INF, h)) return worldRadianceCone(ray.dir, cone.y);
  MaterialData m = u_materials[h.material];
  vec3 dir = normalize(ray.dir);
  Scatter s = scatterAt(m, h, dir);
  vec3 albedo = surfaceAlbedoCone(m, h, dir, coneAt(cone, h.t * length(ray.dir)).x);
  return shadeLocal(m, albedo, ray.origin + h.t * ray.dir, hitMagnitude(ray, h.t), s.n, dir);
}
#else
vec3 reflectedColor(Ray ray) {
  Hit h;
  if (!intersectScene(ray, INF, h)) return worldRadiance(ray.dir);
  MaterialData m = u_materials[h.material];
  vec3 dir = normalize(ray.dir);
  Scatter s = scatterAt(m, h, dir);
  return shadeLocal(m, surfaceAlbedo(m, h.uv), ray.origin + h.t * ray.dir, hitMagnitude(ray, h.t), s.n, dir);
}
#endif

vec3 radiance(Ray primary) {
  vec3 color = vec3(0.0);
  Ray ray = primary;
  vec3 weight = vec3(1.0);
#ifdef TEXTURE_LOD
  vec2 cone = vec2(0.0, g_pixelSpread);
#endif
  for (int depth = 1; depth <= MAX_DEPTH; ++depth) {
    Hit h;
    const bool found = intersectScene(ray, INF, h);
#ifdef PRIMARY_ID_OUT
    if (depth == 1) g_primaryId = found ? h.id : -1;
#endif
    if (!found) {
#ifdef TEXTURE_LOD
      color += weight * worldRadianceCone(ray.dir, cone.y);
#else
      color += weight * worldRadiance(ray.dir);
#endif
      break;
    }
    MaterialData m = u_materials[h.material];
    vec3 dir = normalize(ray.dir);
    vec3 p = ray.origin + h.t * ray.dir;
    float magnitude = hitMagnitude(ray, h.t);
    Scatter s = scatterAt(m, h, dir);
#ifdef TEXTURE_LOD
    vec2 hitCone = coneAt(cone, h.t * length(ray.dir));
    if (s.kLocal > 0.0)
      color += weight * s.kLocal * shadeLocal(m, surfaceAlbedoCone(m, h, dir, hitCone.x), p, magnitude, s.n, dir);
#else
    if (s.kLocal > 0.0) color += weight * s.kLocal * shadeLocal(m, surfaceAlbedo(m, h.uv), p, magnitude, s.n, dir);
#endif
    if (depth == MAX_DEPTH) break;
    Ray reflected = Ray(offsetRayOrigin(p, s.n, magnitude), reflect(dir, s.n));
    if (s.kr > 0.0 && s.kt > 0.0) {
#ifdef TEXTURE_LOD
      color += weight * s.kr * reflectedColor(reflected, reflectedCone(h, s, hitCone));
      cone = refractedCone(m, h, s, dir, hitCone);
#else
      color += weight * s.kr * reflectedColor(reflected);
#endif
      weight *= s.kt;
      ray = Ray(offsetRayOrigin(p, -s.n, magnitude), s.refracted);
    } else if (s.kt > 0.0) {
#ifdef TEXTURE_LOD
      cone = refractedCone(m, h, s, dir, hitCone);
#endif
      weight *= s.kt;
      ray = Ray(offsetRayOrigin(p, -s.n, magnitude), s.refracted);
    } else if (s.kr > 0.0) {
#ifdef TEXTURE_LOD
      cone = reflectedCone(h, s, hitCone);
#endif
      weight *= s.kr;
      ray = reflected;
    } else {
      break;
    }
    if (max(max(weight.r, weight.g), weight.b) <= MIN_BRANCH_WEIGHT) break;
  }
  return color;
}
