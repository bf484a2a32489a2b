// C++ mirror of the tracer modules. Each function below carries the name of its GLSL twin and the
// same statement order; the GLSL "uniforms" are the members of Tracer.
#include "shaders/tracer.hpp"

#include <chrono>
#include <cmath>
#include <thread>

#include "shaders/common.hpp"
#include "shaders/offset_ulp.hpp"
#include "shaders/primitives.hpp"
#include "shaders/texture_lod.hpp"
#include "shaders/texture_mips.hpp"
#include "traversal/kernels.hpp"

namespace bvhlab {
namespace glsl {

namespace {

// GLSL built-ins that GLM lacks or names differently.
float atan2f_(float y, float x) { return std::atan2(y, x); }

constexpr int KIND_SPHERE = 0, KIND_BOX = 1, KIND_CYLINDER = 2, KIND_CONE = 3, KIND_TORUS = 4, KIND_PLANE = 5;
constexpr float RAY_OFFSET_SCALE = 1e-4f;
constexpr float MIN_BRANCH_WEIGHT = 1.0f / 1024.0f;

struct Hit {
  float t;
  vec3 normal;
  vec3 geomNormal;
  vec2 uv;
  int material;
  int id;
  vec3 dpdu;  // TEXTURE_LOD
  vec3 dpdv;
  float curvature;
};

struct Scatter {
  float kLocal;
  float kr;
  float kt;
  vec3 refracted;
  vec3 n;
  bool entering;
};

struct PathVertex {
  Ray ray;
  vec3 weight;
  int depth;
  vec2 cone;  // TEXTURE_LOD
};

struct Tracer {
  // "uniforms"
  const Scene& scene;
  const SceneData& data;
  const PackedBvh& bvh;
  const ShaderOptions& options;
  const KernelInfo& kernel;
  Storage storage;  // the BVH streams and BVH_STACK_SIZE
  int MAX_DEPTH;
  int NUM_OBJECTS;
  int NUM_LIGHTS;
  bool MESH_PRESENT;
  bool TEXTURE_LOD;        // usesTextureLod(features, options): cones compiled in
  const TextureMips* mips;  // with TEXTURE_LOD
  // "globals"
  Counters counters;
  float g_pixelSpread = 0.0f;
  float g_firstLod = -1.0f;  // LOD_VIEW
  void recordLod(float lod) {
    if (g_firstLod < 0.0f) g_firstLod = clamp(lod, 0.0f, 15.0f);
  }

  // ---- scene.glsl -------------------------------------------------------------------------
  static vec3 objectPoint(const ObjectData& o, vec3 p) {
    vec4 h = vec4(p, 1.0f);
    return vec3(dot(o.worldToObject0, h), dot(o.worldToObject1, h), dot(o.worldToObject2, h));
  }
  static vec3 objectVector(const ObjectData& o, vec3 v) {
    return vec3(dot(vec3(o.worldToObject0), v), dot(vec3(o.worldToObject1), v), dot(vec3(o.worldToObject2), v));
  }
  static vec3 worldNormal(const ObjectData& o, vec3 n) {
    return n.x * vec3(o.worldToObject0) + n.y * vec3(o.worldToObject1) + n.z * vec3(o.worldToObject2);
  }

  static bool intersectObject(const ObjectData& o, Ray r, float tMax, float& t, vec3& n, vec2& uv) {
    int kind = o.info.x;
    t = tMax;
    n = vec3(0.0f, 1.0f, 0.0f);
    uv = vec2(0.0f);
    if (kind == KIND_SPHERE) return intersectSphere(r, 0.0f, tMax, t, n, uv);
    if (kind == KIND_BOX) return intersectBox(r, 0.0f, tMax, t, n, uv);
    if (kind == KIND_CYLINDER) return intersectCylinder(r, 0.0f, tMax, t, n, uv);
    if (kind == KIND_CONE) return intersectCone(r, 0.0f, tMax, t, n, uv);
    if (kind == KIND_TORUS) return intersectTorus(r, vec2(o.params), 0.0f, tMax, t, n, uv);
    if (kind == KIND_PLANE) return intersectPlane(r, o.params.z > 0.5f, 0.0f, tMax, t, n, uv);
    return false;
  }

  int triangleId(int tri) const {
    uint primitive, material, mesh;
    loadTriangleIds(storage, tri, primitive, material, mesh);
    return int(primitive);
  }
  int triangleMaterial(int tri) const {
    uint primitive, material, mesh;
    loadTriangleIds(storage, tri, primitive, material, mesh);
    return int(material);
  }

  bool intersectScene(Ray ray, float tMax, Hit& hit) {
    hit.t = tMax;
    hit.normal = vec3(0.0f, 1.0f, 0.0f);
    hit.geomNormal = hit.normal;
    hit.uv = vec2(0.0f);
    hit.material = 0;
    hit.id = -1;
    hit.dpdu = vec3(0.0f);
    hit.dpdv = vec3(0.0f);
    hit.curvature = 0.0f;
    vec3 objectNormal = vec3(0.0f, 1.0f, 0.0f);
    bool found = false;
    for (int i = 0; i < NUM_OBJECTS; ++i) {
      const ObjectData& o = data.objects[size_t(i)];
      Ray r = Ray{objectPoint(o, ray.origin), objectVector(o, ray.dir)};
      float t;
      vec3 n;
      vec2 uv;
      if (intersectObject(o, r, hit.t, t, n, uv)) {
        found = true;
        hit.t = t;
        hit.normal = normalize(worldNormal(o, n));
        hit.geomNormal = hit.normal;
        hit.uv = uv;
        hit.material = o.info.y;
        hit.id = i;
        objectNormal = n;
      }
    }
    if (TEXTURE_LOD && found) {
      const ObjectData& o = data.objects[size_t(hit.id)];
      Ray r = Ray{objectPoint(o, ray.origin), objectVector(o, ray.dir)};
      vec3 q = r.origin + hit.t * r.dir;
      objectSurface(o.info.x, vec2(o.params), q, objectNormal, hit.dpdu, hit.dpdv, hit.curvature);
      mat3 objectToWorld =
          inverse(transpose(mat3(vec3(o.worldToObject0), vec3(o.worldToObject1), vec3(o.worldToObject2))));
      hit.dpdu = objectToWorld * hit.dpdu;
      hit.dpdv = objectToWorld * hit.dpdv;
      hit.curvature *= pow(abs(determinant(objectToWorld)), -1.0f / 3.0f);
    }
    if (MESH_PRESENT) {
      counters.meshRays++;
      MeshHit mh;
      if (kernel.closest(options.robust)(storage, ray, 0.0f, hit.t, mh, counters)) {
        found = true;
        vec3 v0, v1, v2;
        loadTriangle(storage, mh.tri, v0, v1, v2);
        vec3 shadingNormal;
        vec2 uv;
        loadAttributes(storage, mh.tri, mh.bary, shadingNormal, uv);
        vec3 geomNormal = normalize(cross(v1 - v0, v2 - v0));
        hit.t = mh.t;
        hit.geomNormal = geomNormal;
        hit.normal = dot(shadingNormal, geomNormal) > 0.0f ? normalize(shadingNormal) : geomNormal;
        hit.uv = uv;
        hit.material = triangleMaterial(mh.tri);
        hit.id = NUM_OBJECTS + triangleId(mh.tri);
        if (TEXTURE_LOD) meshSurface(storage, mh.tri, v0, v1, v2, hit.dpdu, hit.dpdv, hit.curvature);
      }
    }
    return found;
  }

  bool occluded(Ray ray, float tMax) {
    for (int i = 0; i < NUM_OBJECTS; ++i) {
      const ObjectData& o = data.objects[size_t(i)];
      Ray r = Ray{objectPoint(o, ray.origin), objectVector(o, ray.dir)};
      float t;
      vec3 n;
      vec2 uv;
      if (intersectObject(o, r, tMax, t, n, uv)) return true;
    }
    if (MESH_PRESENT) {
      counters.meshRays++;
      if (kernel.any(options.robust)(storage, ray, 0.0f, tMax, counters)) return true;
    }
    return false;
  }

  // ---- world*.glsl ------------------------------------------------------------------------
  vec3 worldColor(vec3) const { return scene.world.color; }
  vec3 worldSky(vec3 dir) const {
    const World& w = scene.world;
    float y = dir.y / length(dir);
    return y < 0.0f ? mix(w.horizon, w.ground, min(-y * 4.0f, 1.0f)) : mix(w.horizon, w.zenith, sqrt(y));
  }
  vec2 equirectUv(vec3 dir) const {
    vec3 d = normalize(dir);
    float phi = atan2f_(d.z, d.x) + radians(scene.world.rotationDeg);
    float theta = asin(clamp(d.y, -1.0f, 1.0f));
    return vec2(phi / (2.0f * PI) + 0.5f, theta / PI + 0.5f);
  }
  vec3 worldMap(vec3 dir) const {
    const Image* m = data.worldMap;
    if (!m) return vec3(0.0f);
    return vec3(bilinear(m->texels.data(), m->width, m->height, equirectUv(dir), false));
  }
  vec3 worldRadiance(vec3 dir) const {
    WorldKind k = scene.world.kind;
    vec3 c = k == WorldKind::Color ? worldColor(dir) : (k == WorldKind::Sky ? worldSky(dir) : worldMap(dir));
    return c * scene.world.intensity;
  }
  // world_map.glsl's worldMapCone
  vec3 worldMapCone(vec3 dir, float spread) {
    const Image* m = data.worldMap;
    if (!m) return vec3(0.0f);
    vec2 size = vec2(float(m->width), float(m->height));
    float cosLat = max(sqrt(max(1.0f - dir.y * dir.y / dot(dir, dir), 0.0f)), PI / size.y);
    vec2 uv = equirectUv(dir);
    if (options.textureLod == TextureLod::ConesAniso) {
      AnisoTaps taps = anisoTaps(vec2(abs(spread) / (2.0f * PI * cosLat), 0.0f), vec2(0.0f, abs(spread) / PI), size);
      recordLod(taps.lod);
      vec3 sum = vec3(0.0f);
      for (int i = 0; i < taps.count; ++i)
        sum += vec3(trilinear(mips->world, 0, uv + ((float(i) + 0.5f) / float(taps.count) - 0.5f) * taps.major,
                              taps.lod, false));
      return sum / float(taps.count);
    }
    float texel = sqrt(2.0f * PI * cosLat / size.x * PI / size.y);
    float lod = abs(spread) > 0.0f ? log2(abs(spread) / texel) : 0.0f;
    recordLod(lod);
    return vec3(trilinear(mips->world, 0, uv, lod, false));
  }
  // world.glsl's worldRadianceCone
  vec3 worldRadianceCone(vec3 dir, float spread) {
    WorldKind k = scene.world.kind;
    if (k != WorldKind::Map) return worldRadiance(dir);
    return worldMapCone(dir, spread) * scene.world.intensity;
  }

  // ---- shade.glsl -------------------------------------------------------------------------
  static float hitMagnitude(const Ray& ray, float t) {
    return max(max(abs(ray.origin.x), abs(ray.origin.y)), abs(ray.origin.z)) + t * length(ray.dir);
  }

  vec3 offsetRayOrigin(vec3 p, vec3 towards, float magnitude) const {
    return bvhlab::offsetRayOrigin(p, towards, magnitude, options.robust.offset);
  }

  vec3 surfaceAlbedo(const MaterialData& m, vec2 uv) const {
    vec3 albedo = vec3(m.color);
    if (m.color.w >= 0.0f) {
      const TextureArray& ta = data.textures;
      const vec4* layer = ta.texels.data() + size_t(m.color.w) * size_t(ta.width) * size_t(ta.height);
      albedo *= vec3(bilinear(layer, ta.width, ta.height, uv * vec2(m.uvScale), true));
    }
    return albedo;
  }

  vec3 surfaceAlbedoCone(const MaterialData& m, const Hit& h, vec3 dir, float w) {
    vec3 albedo = vec3(m.color);
    if (m.color.w >= 0.0f) {
      const TextureArray& ta = data.textures;
      const int layer = int(m.color.w);
      vec2 uvScale = vec2(m.uvScale);
      vec2 at = h.uv * uvScale;
      if (options.textureLod == TextureLod::ConesAniso) {
        vec2 g1, g2;
        coneEllipse(w, dir, h.normal, h.dpdu, h.dpdv, g1, g2);
        AnisoTaps taps = anisoTaps(g1 * uvScale, g2 * uvScale, vec2(float(ta.width), float(ta.height)));
        recordLod(taps.lod);
        vec3 sum = vec3(0.0f);
        for (int i = 0; i < taps.count; ++i) {
          vec2 offset = ((float(i) + 0.5f) / float(taps.count) - 0.5f) * taps.major;
          sum += vec3(trilinear(mips->textures, layer, at + offset, taps.lod, true));
        }
        albedo *= sum / float(taps.count);
      } else {
        vec2 texSize = vec2(float(ta.width), float(ta.height)) * uvScale;
        float lod = coneLodIsotropic(w, dot(dir, h.normal), h.dpdu, h.dpdv, texSize);
        recordLod(lod);
        albedo *= vec3(trilinear(mips->textures, layer, at, lod, true));
      }
    }
    return albedo;
  }

  vec3 shadeLocal(const MaterialData& m, vec3 albedo, vec3 p, float magnitude, vec3 n, vec3 viewDir) {
    vec3 color = vec3(m.emission) + albedo * m.lighting.y * vec3(data.ambient);
    for (int i = 0; i < NUM_LIGHTS; ++i) {
      const LightData& light = data.lights[size_t(i)];
      vec3 toLight;
      float distance;
      if (light.position.w > 0.5f) {
        toLight = -vec3(light.position);
        distance = INF;
      } else {
        vec3 d = vec3(light.position) - p;
        distance = length(d);
        toLight = d / distance;
      }
      float nDotL = dot(n, toLight);
      if (nDotL > 0.0f) {
        vec3 origin = offsetRayOrigin(p, n, magnitude);
        float tLight = light.position.w > 0.5f ? INF : length(vec3(light.position) - origin);
        if (occluded(Ray{origin, toLight}, tLight)) continue;
        vec3 h = normalize(toLight - viewDir);
        float spec = m.lighting.z > 0.0f ? m.lighting.z * pow(max(dot(n, h), 0.0f), m.lighting.w) : 0.0f;
        color += vec3(light.radiance) * (albedo * m.lighting.x * nDotL + vec3(spec));
      }
    }
    return color;
  }

  static float schlickFresnel(float cosTheta, float ior) {
    float r0 = (ior - 1.0f) / (ior + 1.0f);
    r0 = r0 * r0;
    float m = clamp(1.0f - cosTheta, 0.0f, 1.0f);
    return r0 + (1.0f - r0) * m * m * m * m * m;
  }

  static Scatter scatterAt(const MaterialData& m, const Hit& h, vec3 dir) {
    Scatter s;
    s.entering = dot(dir, h.geomNormal) < 0.0f;
    s.n = s.entering ? h.normal : -h.normal;
    float reflectivity = m.optics.x;
    float transparency = m.optics.y;
    float opaque = 1.0f - transparency;
    s.kLocal = opaque * (1.0f - reflectivity);
    s.kr = opaque * reflectivity;
    s.kt = 0.0f;
    s.refracted = vec3(0.0f);
    if (transparency > 0.0f) {
      float ior = m.optics.z;
      float eta = s.entering ? 1.0f / ior : ior;
      float cosI = min(-dot(dir, s.n), 1.0f);
      float sin2T = eta * eta * max(1.0f - cosI * cosI, 0.0f);
      float fresnel = 1.0f;
      if (sin2T < 1.0f) {
        float cosT = sqrt(1.0f - sin2T);
        s.refracted = eta * dir + (eta * cosI - cosT) * s.n;
        fresnel = schlickFresnel(s.entering ? cosI : cosT, ior);
      }
      s.kr += transparency * fresnel;
      s.kt = transparency * (1.0f - fresnel);
    }
    return s;
  }

  // shade.glsl's reflectedCone / refractedCone
  vec2 reflectedCone(const Hit& h, const Scatter& s, vec2 cone) const {
    float kappa = s.entering ? h.curvature : -h.curvature;
    return vec2(cone.x, coneSpreadAfter(cone.y, cone.x, kappa, true, 1.0f, 1.0f, 1.0f, options.coneCurvature));
  }
  vec2 refractedCone(const MaterialData& m, const Hit& h, const Scatter& s, vec3 dir, vec2 cone) const {
    float kappa = s.entering ? h.curvature : -h.curvature;
    float eta = s.entering ? 1.0f / m.optics.z : m.optics.z;
    float cosI = min(-dot(dir, s.n), 1.0f);
    float cosT = -dot(s.refracted, s.n);
    return vec2(cone.x, coneSpreadAfter(cone.y, cone.x, kappa, false, eta, cosI, cosT, options.coneCurvature));
  }

  // ---- trace_full.glsl --------------------------------------------------------------------
  vec3 radianceFull(Ray primary) {
    vec3 color = vec3(0.0f);
    std::vector<PathVertex> stack(size_t(MAX_DEPTH + 1));
    int sp = 0;
    stack[size_t(sp++)] = PathVertex{primary, vec3(1.0f), 1, vec2(0.0f, g_pixelSpread)};
    while (sp > 0) {
      PathVertex v = stack[size_t(--sp)];
      Hit h;
      if (!intersectScene(v.ray, INF, h)) {
        if (TEXTURE_LOD)
          color += v.weight * worldRadianceCone(v.ray.dir, v.cone.y);
        else
          color += v.weight * worldRadiance(v.ray.dir);
        continue;
      }
      const MaterialData& m = data.materials[size_t(h.material)];
      vec3 dir = normalize(v.ray.dir);
      vec3 p = v.ray.origin + h.t * v.ray.dir;
      float magnitude = hitMagnitude(v.ray, h.t);
      Scatter s = scatterAt(m, h, dir);
      vec2 cone = coneAt(v.cone, h.t * length(v.ray.dir));  // TEXTURE_LOD
      if (TEXTURE_LOD) {
        if (s.kLocal > 0.0f)
          color += v.weight * s.kLocal * shadeLocal(m, surfaceAlbedoCone(m, h, dir, cone.x), p, magnitude, s.n, dir);
      } else {
        if (s.kLocal > 0.0f)
          color += v.weight * s.kLocal * shadeLocal(m, surfaceAlbedo(m, h.uv), p, magnitude, s.n, dir);
      }
      if (MAX_DEPTH > 1) {
        if (v.depth >= MAX_DEPTH) continue;
        vec3 wt = v.weight * s.kt;
        if (max(max(wt.r, wt.g), wt.b) > MIN_BRANCH_WEIGHT)
          stack[size_t(sp++)] = PathVertex{Ray{offsetRayOrigin(p, -s.n, magnitude), s.refracted}, wt, v.depth + 1,
                                           TEXTURE_LOD ? refractedCone(m, h, s, dir, cone) : vec2(0.0f)};
        vec3 wr = v.weight * s.kr;
        if (max(max(wr.r, wr.g), wr.b) > MIN_BRANCH_WEIGHT)
          stack[size_t(sp++)] = PathVertex{Ray{offsetRayOrigin(p, s.n, magnitude), reflect(dir, s.n)}, wr, v.depth + 1,
                                           TEXTURE_LOD ? reflectedCone(h, s, cone) : vec2(0.0f)};
      }
    }
    return color;
  }

  // ---- trace_report.glsl ------------------------------------------------------------------
  vec3 reflectedColor(Ray ray, vec2 cone) {
    Hit h;
    if (!intersectScene(ray, INF, h)) return TEXTURE_LOD ? worldRadianceCone(ray.dir, cone.y) : worldRadiance(ray.dir);
    const MaterialData& m = data.materials[size_t(h.material)];
    vec3 dir = normalize(ray.dir);
    Scatter s = scatterAt(m, h, dir);
    vec3 albedo = TEXTURE_LOD ? surfaceAlbedoCone(m, h, dir, coneAt(cone, h.t * length(ray.dir)).x)
                              : surfaceAlbedo(m, h.uv);
    return shadeLocal(m, albedo, ray.origin + h.t * ray.dir, hitMagnitude(ray, h.t), s.n, dir);
  }

  vec3 radianceReport(Ray primary) {
    vec3 color = vec3(0.0f);
    Ray ray = primary;
    vec3 weight = vec3(1.0f);
    vec2 cone = vec2(0.0f, g_pixelSpread);  // TEXTURE_LOD
    for (int depth = 1; depth <= MAX_DEPTH; ++depth) {
      Hit h;
      if (!intersectScene(ray, INF, h)) {
        color += weight * (TEXTURE_LOD ? worldRadianceCone(ray.dir, cone.y) : worldRadiance(ray.dir));
        break;
      }
      const MaterialData& m = data.materials[size_t(h.material)];
      vec3 dir = normalize(ray.dir);
      vec3 p = ray.origin + h.t * ray.dir;
      float magnitude = hitMagnitude(ray, h.t);
      Scatter s = scatterAt(m, h, dir);
      vec2 hitCone = coneAt(cone, h.t * length(ray.dir));
      if (s.kLocal > 0.0f)
        color += weight * s.kLocal *
                 shadeLocal(m, TEXTURE_LOD ? surfaceAlbedoCone(m, h, dir, hitCone.x) : surfaceAlbedo(m, h.uv), p,
                            magnitude, s.n, dir);
      if (depth == MAX_DEPTH) break;
      Ray reflected = Ray{offsetRayOrigin(p, s.n, magnitude), reflect(dir, s.n)};
      if (s.kr > 0.0f && s.kt > 0.0f) {
        color += weight * s.kr * reflectedColor(reflected, TEXTURE_LOD ? reflectedCone(h, s, hitCone) : vec2(0.0f));
        if (TEXTURE_LOD) cone = refractedCone(m, h, s, dir, hitCone);
        weight *= s.kt;
        ray = Ray{offsetRayOrigin(p, -s.n, magnitude), s.refracted};
      } else if (s.kt > 0.0f) {
        if (TEXTURE_LOD) cone = refractedCone(m, h, s, dir, hitCone);
        weight *= s.kt;
        ray = Ray{offsetRayOrigin(p, -s.n, magnitude), s.refracted};
      } else if (s.kr > 0.0f) {
        if (TEXTURE_LOD) cone = reflectedCone(h, s, hitCone);
        weight *= s.kr;
        ray = reflected;
      } else {
        break;
      }
      if (max(max(weight.r, weight.g), weight.b) <= MIN_BRANCH_WEIGHT) break;
    }
    return color;
  }

  // ---- main.glsl --------------------------------------------------------------------------
  static float srgbEncode(float c) { return c <= 0.0031308f ? 12.92f * c : 1.055f * pow(c, 1.0f / 2.4f) - 0.055f; }
  vec3 toneMap(vec3 c, float exposure) const {
    c *= exposure;
    if (options.reinhard) c = c / (1.0f + c);
    return clamp(c, 0.0f, 1.0f);
  }
  static vec3 srgbEncode(vec3 c) { return vec3(srgbEncode(c.r), srgbEncode(c.g), srgbEncode(c.b)); }
  static bool nonFinite(vec3 c) {
    return any(equal(floatBitsToUint(c) & uvec3(0x7F800000u), uvec3(0x7F800000u)));
  }
  static vec3 idColor(int id) {
    uint32_t h = uint32_t(id) * 2654435761u;
    h ^= h >> 15;
    return vec3(0.2f) + 0.8f * vec3(float(h & 255u), float((h >> 8) & 255u), float((h >> 16) & 255u)) / 255.0f;
  }

  vec3 radiance(Ray ray) { return options.branching == Branching::Full ? radianceFull(ray) : radianceReport(ray); }

  // main.glsl's cameraRay
  Ray cameraRay(const CameraBasis& cam, vec2 resolution, vec2 pixel) const {
    vec2 ndc = 2.0f * pixel / resolution - 1.0f;
    return Ray{cam.eye, normalize(cam.forward + ndc.x * cam.right + ndc.y * cam.up)};
  }

  // One pixel (main.glsl's main): the colour written to o_color; fills `stats` like o_stats and
  // `boxTests` like o_boxTests.
  vec3 renderPixel(const CameraBasis& cam, vec2 resolution, vec2 fragCoord, float exposure, float sceneRadius,
                   uvec4& stats, uint32_t& boxTests) {
    counters = Counters{};
    g_firstLod = -1.0f;
    // main.glsl: the primary cone's spread, one pixel's angle per sub-sample (cam.up carries tan(fov/2))
    if (TEXTURE_LOD) g_pixelSpread = atan(2.0f * length(cam.up) / resolution.y) / float(options.ssaaGrid);
    Ray ray = cameraRay(cam, resolution, fragCoord);
    int primaryId = -1;
    bool nonFiniteValue = false;
    vec3 color;
    if (options.view == View::Shaded) {
      const int SSAA_GRID = options.ssaaGrid;
      if (SSAA_GRID > 1) {
        vec3 sum = vec3(0.0f);
        for (int j = 0; j < SSAA_GRID; ++j)
          for (int i = 0; i < SSAA_GRID; ++i) {
            vec2 offset = (vec2(float(i), float(j)) + 0.5f) / float(SSAA_GRID) - 0.5f;
            vec3 L = radiance(cameraRay(cam, resolution, fragCoord + offset));
            nonFiniteValue = nonFiniteValue || nonFinite(L);
            sum += toneMap(L, exposure);
          }
        color = srgbEncode(sum / float(SSAA_GRID * SSAA_GRID));
      } else {
        vec3 L = radiance(ray);
        nonFiniteValue = nonFinite(L);
        color = srgbEncode(toneMap(L, exposure));
      }
    } else {
      Hit h;
      bool found = intersectScene(ray, INF, h);
      color = vec3(0.0f);
      if (found) {
        primaryId = h.id;
        if (options.view == View::Normal) color = abs(h.normal);
        if (options.view == View::Depth) color = vec3(max(sceneRadius / (sceneRadius + h.t), 1.0f / 255.0f));
        if (options.view == View::PrimId) color = idColor(h.id);
      }
      nonFiniteValue = nonFinite(color);
    }
    if (TEXTURE_LOD && options.lodView)  // LOD_VIEW
      color = vec3(g_firstLod < 0.0f ? 0.0f : (g_firstLod * 16.0f + 1.0f) / 255.0f);
    stats = uvec4(counters.nodeVisits, counters.triTests,
                  counters.meshRays | (counters.stackOverflow ? 0x80000000u : 0u),
                  uint32_t(primaryId + 1) | (nonFiniteValue ? 0x80000000u : 0u));
    boxTests = counters.boxTests;
    return color;
  }
};

}  // namespace
}  // namespace glsl

glm::vec3 offsetRayOrigin(glm::vec3 p, glm::vec3 towards, float magnitude, OriginOffset offset) {
  using namespace glsl;
  if (offset == OriginOffset::Ulp) return offsetRayOriginUlp(p, towards, magnitude);  // #ifdef RAY_OFFSET_ULP
  return p + towards * (RAY_OFFSET_SCALE * magnitude);
}

ReferenceImage renderReference(const Scene& scene, const SceneData& data, const PackedBvh& bvh,
                               const ShaderOptions& options, const FrameOptions& frame) {
  using namespace glsl;
  const auto start = std::chrono::steady_clock::now();
  SceneFeatures features = analyzeScene(scene);
  ReferenceImage img;
  img.width = frame.width;
  img.height = frame.height;
  img.rgba.resize(size_t(frame.width) * frame.height * 4);
  img.stats.resize(size_t(frame.width) * frame.height);
  img.boxTests.resize(size_t(frame.width) * frame.height);
  CameraBasis cam = cameraBasis(frame.camera, frame.width, frame.height);
  const KernelInfo& kernel = findKernel(options.kernel);
  const bool cones = usesTextureLod(features, options);
  const TextureMips mips = cones ? buildTextureMips(data) : TextureMips{};  // the levels GpuRenderer uploads

  auto worker = [&](int first, int step) {
    Tracer tr{scene, data, bvh, options, kernel, glsl::Storage(bvh, std::max(1, options.bvhStackSize)), effectiveDepth(features, options.maxDepth, options.uber),
              features.numObjects, features.numLights, !bvh.triangles.empty(), cones, &mips, {}};
    const vec2 resolution(float(frame.width), float(frame.height));
    for (int y = first; y < frame.height; y += step)
      for (int x = 0; x < frame.width; ++x) {
        // gl_FragCoord.xy: pixel centres at +0.5
        vec2 fragCoord(float(x) + 0.5f, float(y) + 0.5f);
        size_t i = size_t(y) * frame.width + x;
        vec3 c = tr.renderPixel(cam, resolution, fragCoord, frame.exposure, data.sceneRadius, img.stats[i],
                                 img.boxTests[i]);
        // Float -> UNORM8 conversion as GL specifies it: round(clamp(c) * 255).
        for (int k = 0; k < 3; ++k) img.rgba[4 * i + k] = uint8_t(std::lround(clamp(c[k], 0.0f, 1.0f) * 255.0f));
        img.rgba[4 * i + 3] = 255;
      }
  };
  unsigned threads = std::max(1u, std::thread::hardware_concurrency());
  std::vector<std::thread> pool;
  for (unsigned t = 0; t < threads; ++t) pool.emplace_back(worker, int(t), int(threads));
  for (std::thread& t : pool) t.join();
  img.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return img;
}

}  // namespace bvhlab
