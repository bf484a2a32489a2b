// trace_report.glsl — the report's Algorithm 1 compromise: one ray continues per pixel. Where a
// surface both reflects and refracts, the reflection is followed for ONE bounce only (its hit is
// shaded locally, or the world is seen) and the path continues along the refracted ray.
// C++ mirror: shaders/tracer.hpp.

#define MIN_BRANCH_WEIGHT (1.0 / 1024.0)

// One-bounce reflection: local shading of whatever the reflected ray sees ("getReflectedColor").
vec3 reflectedColor(Ray ray) {
  Hit h;
  if (!intersectScene(ray, INF, h)) return worldRadiance(ray.dir);
  MaterialData m = u_materials[h.material];
  vec3 dir = normalize(ray.dir);
  Scatter s = scatterAt(m, h, dir);
  return shadeLocal(m, surfaceAlbedo(m, h.uv), ray.origin + h.t * ray.dir, hitMagnitude(ray, h.t), s.n, dir);
}

vec3 radiance(Ray primary) {
  vec3 color = vec3(0.0);
  Ray ray = primary;
  vec3 weight = vec3(1.0);
  for (int depth = 1; depth <= MAX_DEPTH; ++depth) {
    Hit h;
    if (!intersectScene(ray, INF, h)) {
      color += weight * worldRadiance(ray.dir);
      break;
    }
    MaterialData m = u_materials[h.material];
    vec3 dir = normalize(ray.dir);
    vec3 p = ray.origin + h.t * ray.dir;
    float magnitude = hitMagnitude(ray, h.t);
    Scatter s = scatterAt(m, h, dir);
    if (s.kLocal > 0.0) color += weight * s.kLocal * shadeLocal(m, surfaceAlbedo(m, h.uv), p, magnitude, s.n, dir);
    if (depth == MAX_DEPTH) break;
    Ray reflected = Ray(offsetRayOrigin(p, s.n, magnitude), reflect(dir, s.n));
    if (s.kr > 0.0 && s.kt > 0.0) {
      color += weight * s.kr * reflectedColor(reflected);
      weight *= s.kt;
      ray = Ray(offsetRayOrigin(p, -s.n, magnitude), s.refracted);
    } else if (s.kt > 0.0) {
      weight *= s.kt;
      ray = Ray(offsetRayOrigin(p, -s.n, magnitude), s.refracted);
    } else if (s.kr > 0.0) {
      weight *= s.kr;
      ray = reflected;
    } else {
      break;
    }
    if (max(max(weight.r, weight.g), weight.b) <= MIN_BRANCH_WEIGHT) break;
  }
  return color;
}
