#include "render/workloads.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include "shaders/common.hpp"
#include "shaders/offset_ulp.hpp"
#include "shaders/scene_data.hpp"

namespace bvhlab {

namespace {

constexpr Workload kAll[] = {Workload::Primary, Workload::Shadow, Workload::Specular, Workload::Diffuse, Workload::Ao};
constexpr const char* kNames[] = {"primary", "shadow", "specular", "diffuse", "ao"};

// A uniform float in [0, 1) from the top 24 bits of a 64-bit draw: the same numbers on every
// platform (std::uniform_real_distribution is implementation-defined).
float unit(std::mt19937_64& rng) { return float(rng() >> 40) * 0x1.0p-24f; }

// An orthonormal basis around unit n (Duff et al. 2017, "Building an Orthonormal Basis, Revisited").
void basis(const glm::vec3& n, glm::vec3& t, glm::vec3& b) {
  const float sign = std::copysign(1.0f, n.z);
  const float a = -1.0f / (sign + n.z);
  const float c = n.x * n.y * a;
  t = glm::vec3(1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x);
  b = glm::vec3(c, sign + n.y * n.y * a, -n.y);
}

// Cosine-weighted direction about unit n (Malley's method: a uniform disc point lifted to the
// hemisphere), pdf cos(theta) / pi.
glm::vec3 cosineDirection(const glm::vec3& n, float u1, float u2) {
  const float r = std::sqrt(u1), phi = 2.0f * glsl::PI * u2;
  glm::vec3 t, b;
  basis(n, t, b);
  return glm::normalize(r * std::cos(phi) * t + r * std::sin(phi) * b + std::sqrt(std::max(0.0f, 1.0f - u1)) * n);
}

struct Grid {
  uint32_t width = 0, height = 0;
  std::vector<BatchRay> rays;
};

// `count` camera rays, row by row through pixel centres of a width x height grid of the request's
// aspect (main.glsl's cameraRay for that grid).
Grid primaryGrid(uint32_t count, const Camera& camera, int aspectW, int aspectH) {
  Grid g;
  const double aspect = double(aspectW) / double(aspectH);
  g.width = uint32_t(std::max(1.0, std::round(std::sqrt(double(count) * aspect))));
  g.height = (count + g.width - 1) / g.width;
  const CameraBasis cam = cameraBasis(camera, int(g.width), int(g.height));
  g.rays.resize(count);
  for (uint32_t k = 0; k < count; ++k) {
    const glm::vec2 pixel(float(k % g.width) + 0.5f, float(k / g.width) + 0.5f);
    const glm::vec2 ndc = 2.0f * pixel / glm::vec2(float(g.width), float(g.height)) - 1.0f;
    g.rays[k] = {cam.eye, 0.0f, glm::normalize(cam.forward + ndc.x * cam.right + ndc.y * cam.up), glsl::INF};
  }
  return g;
}

}  // namespace

Workload parseWorkload(const std::string& name) {
  for (size_t i = 0; i < std::size(kAll); ++i)
    if (name == kNames[i]) return kAll[i];
  throw std::invalid_argument("unknown ray workload '" + name + "' (valid: primary, shadow, specular, diffuse, ao)");
}

const char* workloadName(Workload w) { return kNames[int(w)]; }

const std::vector<std::string>& workloadNames() {
  static const std::vector<std::string> names(std::begin(kNames), std::end(kNames));
  return names;
}

RayWorkload generateWorkload(const WorkloadRequest& req, const Scene& scene, const TriangleSoup& soup,
                             const ClosestHitFn& closest) {
  if (req.count < 1 || req.count > kMaxTraceRays)
    throw std::invalid_argument("--count must be in 1.." + std::to_string(kMaxTraceRays));
  if (!(req.aoRadius > 0.0f && req.aoRadius <= 1.0f))
    throw std::invalid_argument("--ao-radius must be in (0, 1] (a fraction of the scene's diagonal)");
  if (req.width < 1 || req.height < 1) throw std::invalid_argument("workload aspect needs a positive width and height");
  if (soup.size() == 0) throw InputError("the scene has no triangles to trace rays against");
  RayWorkload w;
  w.workload = req.workload;
  Grid grid = primaryGrid(req.count, scene.camera, req.width, req.height);
  w.gridWidth = grid.width;
  w.gridHeight = grid.height;
  if (req.workload == Workload::Primary) {
    w.rays = std::move(grid.rays);
    return w;
  }
  if (req.workload == Workload::Shadow && scene.lights.empty())
    throw InputError("shadow rays need a light, and the scene has none");

  std::vector<BatchHit> hits = closest(grid.rays);
  auto hitIndices = [&hits]() {
    std::vector<uint32_t> idx;
    for (uint32_t i = 0; i < hits.size(); ++i)
      if (hits[i].hit) idx.push_back(i);
    return idx;
  };
  std::vector<uint32_t> hitIdx = hitIndices();
  w.primaryHits = uint32_t(hitIdx.size());
  if (hitIdx.empty()) throw InputError("no camera ray hits a triangle: the camera does not see the mesh");
  // Too few hits for `count` secondary rays: a denser grid over the same view (at most 16x the rays,
  // so a mesh that covers a sliver of the image still ends in bounded work).
  if (hitIdx.size() < req.count) {
    const double scale = std::min(16.0, double(req.count) / double(hitIdx.size()) * 1.1);
    const uint64_t denser = std::min<uint64_t>(kMaxTraceRays, uint64_t(std::ceil(double(req.count) * scale)));
    grid = primaryGrid(uint32_t(denser), scene.camera, req.width, req.height);
    hits = closest(grid.rays);
    hitIdx = hitIndices();
    w.gridWidth = grid.width;
    w.gridHeight = grid.height;
    w.primaryHits = uint32_t(hitIdx.size());
  }
  // `count` hits spread evenly over the grid's hits (repeats only if the denser grid still has fewer).
  glm::vec3 lo(glsl::INF), hi(-glsl::INF);
  for (size_t i = 0; i < soup.size(); ++i)
    for (const glm::vec3& v : {soup.v0[i], soup.v1[i], soup.v2[i]}) {
      lo = glm::min(lo, v);
      hi = glm::max(hi, v);
    }
  w.aoDistance = req.aoRadius * glm::length(hi - lo);
  std::mt19937_64 rng(req.seed);
  w.rays.reserve(req.count);
  for (uint32_t k = 0; k < req.count; ++k) {
    const uint32_t i = hitIdx[size_t((uint64_t(k) * hitIdx.size()) / req.count)];
    const BatchRay& in = grid.rays[i];
    const BatchHit& h = hits[i];
    const glm::vec3 p = in.origin + h.t * in.dir;
    const uint32_t tri = h.prim;
    glm::vec3 n = glm::cross(soup.v1[tri] - soup.v0[tri], soup.v2[tri] - soup.v0[tri]);
    const float len = glm::length(n);
    // A degenerate triangle (it can be hit edge-on by a watertight test) has no normal: face the ray.
    n = len > 0.0f && std::isfinite(len) ? n / len : -in.dir;
    if (glm::dot(n, in.dir) > 0.0f) n = -n;  // the side the ray arrived on
    // The magnitude the hit point's rounding error scales with (shade.glsl's hitMagnitude).
    const float magnitude = glm::max(glm::max(std::abs(in.origin.x), std::abs(in.origin.y)), std::abs(in.origin.z)) +
                            h.t * glm::length(in.dir);
    glm::vec3 dir;
    float tMax = glsl::INF;
    size_t lightIndex = 0;
    switch (req.workload) {
      case Workload::Shadow: {
        lightIndex = size_t(rng() % scene.lights.size());
        const Light& light = scene.lights[lightIndex];
        if (light.kind == LightKind::Directional) {
          dir = -glm::normalize(light.direction);
        } else {
          dir = light.position - p;
          tMax = glm::length(dir);
          dir = tMax > 0.0f ? dir / tMax : n;
        }
        break;
      }
      case Workload::Specular:
        dir = glm::reflect(in.dir, n);
        break;
      case Workload::Diffuse:
      case Workload::Ao: {
        const float u1 = unit(rng), u2 = unit(rng);
        dir = cosineDirection(n, u1, u2);
        if (req.workload == Workload::Ao) tMax = w.aoDistance;
        break;
      }
      case Workload::Primary:
        break;
    }
    // Leave on the side the new ray goes to (a light behind the surface: through it).
    const glm::vec3 side = glm::dot(dir, n) >= 0.0f ? n : -n;
    const glm::vec3 origin = glsl::offsetRayOriginUlp(p, side, magnitude);
    if (req.workload == Workload::Shadow && std::isfinite(tMax)) {
      // A point light: the ray ends at the light, measured from where it actually starts.
      const Light& light = scene.lights[lightIndex];
      dir = light.position - origin;
      tMax = glm::length(dir);
      dir = tMax > 0.0f ? dir / tMax : side;
    }
    w.rays.push_back({origin, 0.0f, dir, tMax});
  }
  return w;
}

}  // namespace bvhlab
