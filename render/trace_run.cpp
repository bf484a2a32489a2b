#include "render/trace_run.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <string_view>

#include "render/frame_stats.hpp"
#include "render/gpu_build_timing.hpp"
#include "render/gl_context.hpp"
#include "traversal/kernels.hpp"

namespace bvhlab {

// Two tracers' closest hits on different triangles at the same distance are a tie, not a mismatch:
// rays through a shared edge or vertex, or coplanar overlapping triangles. "Same distance" allows
// the two intersection algorithms' rounding of t, which has two parts:
//  - relative to t: each t is within a few ulps of the exact value along the ray (Woop et al. 2013
//    for the watertight test); 2^-16 relative is far above that and far below any gap between
//    distinct surfaces the scenes have;
//  - absolute, at the magnitude of the coordinates: the tests subtract the ray origin from the
//    vertices (or the vertices from each other), which rounds at ulps of |origin| and |vertex|, so a
//    short ray from a surface next to another (a diffuse ray leaving a room's corner: t = 0.006 at
//    coordinates ~5) carries an error of ulps of 5, not of 0.006. kTieUlps ulps of the larger of
//    the origin's and the hit point's largest coordinate, over |dir|, bound the two tests' rounding
//    with room (each t comes from ~10 float operations on values of that magnitude).
constexpr double kTieRelativeT = 0x1.0p-16;
constexpr double kTieUlps = 16.0;

namespace {

double maxAbs(const glm::vec3& v) { return std::max({std::abs(double(v.x)), std::abs(double(v.y)), std::abs(double(v.z))}); }

}  // namespace

double tieTolerance(const BatchRay& ray, double ta, double tb) {
  const double t = std::max(std::abs(ta), std::abs(tb));
  const double length = glm::length(glm::dvec3(ray.dir));
  const double magnitude = std::max(maxAbs(ray.origin), maxAbs(ray.origin) + t * maxAbs(ray.dir));
  const double absolute = length > 0.0 ? kTieUlps * double(std::numeric_limits<float>::epsilon()) * magnitude / length : 0.0;
  return std::max(kTieRelativeT * t, absolute);
}

HitAgreement compareHits(const std::vector<BatchHit>& a, const std::vector<BatchHit>& b, bool anyHit,
                         const std::vector<BatchRay>& rays) {
  if (rays.size() != a.size() || b.size() != a.size())
    throw std::invalid_argument("compareHits: " + std::to_string(a.size()) + " and " + std::to_string(b.size()) +
                                " answers for " + std::to_string(rays.size()) + " rays");
  HitAgreement r;
  for (size_t i = 0; i < a.size(); ++i) {
    if (a[i].hit != b[i].hit) {
      ++r.mismatches;
      ++r.hitMiss;
    } else if (!anyHit && a[i].hit && a[i].prim != b[i].prim) {
      const double ta = a[i].t, tb = b[i].t;
      // NaN compares false here and counts as a mismatch.
      if (std::abs(ta - tb) <= tieTolerance(rays[i], ta, tb))
        ++r.ties;
      else
        ++r.mismatches;
    }
  }
  return r;
}

BytesFetched mirrorBytesFetched(const PackedBvh& packed, const std::string& kernel, Robustness robust, bool anyHit,
                                const std::vector<BatchRay>& rays, size_t maxRays) {
  const KernelInfo& k = findKernel(packed.layout, kernel);
  const glsl::Storage storage(packed);
  BytesFetched b;
  const size_t n = rays.size();
  b.stride = maxRays > 0 && n > maxRays ? (n + maxRays - 1) / maxRays : 1;
  const TraceClosestFn closest = k.closest(robust);
  const TraceAnyFn any = k.any(robust);
  for (size_t i = 0; i < n; i += b.stride) {
    const BatchRay& r = rays[i];
    glsl::Counters c;
    glsl::MeshHit hit;
    const glsl::Ray ray{r.origin, r.dir};
    if (anyHit)
      any(storage, ray, r.tMin, r.tMax, c);
    else
      closest(storage, ray, r.tMin, r.tMax, hit, c);
    const double v[3] = {double(c.nodeBytes), double(c.triangleBytes), double(c.stackBytes)};
    for (int f = 0; f < 3; ++f) {
      b.sum[f] += v[f];
      b.sumSq[f] += v[f] * v[f];
    }
    ++b.rays;
  }
  return b;
}

TraceSetup setupTrace(const TraceCommand& c, const Scene* loaded,
                      std::map<std::string, std::shared_ptr<const PreparedScene>>* trees) {
  TraceSetup s;
  s.workload = parseWorkload(c.rays);  // bad names fail before anything is loaded
  if (c.render.frames < 1 || c.render.warmup < 0) throw std::invalid_argument("--frames must be >= 1 and --warmup >= 0");
  if (c.maxFrames < 0 || !(c.targetCiPct >= 0.0) || !(c.maxSeconds >= 0.0))
    throw std::invalid_argument("--max-frames, --target-ci-pct and --max-seconds must be >= 0");
  const RenderCommand& rc = c.render;
  s.setup = setupRender(rc, loaded);
  const std::string key = trees ? treeKey(rc) : std::string();
  if (trees)
    if (auto it = trees->find(key); it != trees->end()) s.prepared = it->second;
  if (!s.prepared) {
    s.prepared = prepareScene(std::move(s.setup.scene), rc.builder, s.setup.build, s.setup.shader.layout,
                              s.setup.shader.triangles);
    if (trees) trees->emplace(key, s.prepared);
  }
  if (s.prepared->soup.size() == 0) throw InputError(rc.input + ": no triangles to trace rays against");
  s.tracer.kernel = s.setup.shader.kernel;
  s.tracer.storage = s.setup.shader.storage;
  s.tracer.robust = s.setup.shader.robust;
  s.tracer.anyHit = isAnyHit(s.workload);
  return s;
}

TraceYardstick::TraceYardstick(const TraceCommand& c, const TraceSetup& s)
    : anyHit_(isAnyHit(s.workload)), triangles_(s.prepared->soup.size()), input_(c.render.input) {
  const TriangleSoup& soup = s.prepared->soup;
  generator_ = std::make_unique<EmbreeTracer>(soup, c.embreeThreads);
  if (s.setup.shader.robust.triangle != TriangleTest::Watertight) matching_.emplace(soup, c.embreeThreads, false);
  WorkloadRequest req;
  req.workload = s.workload;
  req.count = c.count;
  req.seed = c.seed;
  req.aoRadius = c.aoRadius;
  req.width = s.prepared->scene.settings.width;
  req.height = s.prepared->scene.settings.height;
  EmbreeTracer& generator = *generator_;
  rays_ = generateWorkload(req, s.prepared->scene, soup, [&generator](const std::vector<BatchRay>& r) {
    std::vector<BatchHit> hits;
    generator.closest(r, hits);
    return hits;
  });
}

std::string TraceYardstick::key(const TraceCommand& c, const TraceSetup& s) {
  const TriangleSoup& soup = s.prepared->soup;
  const Scene& scene = s.prepared->scene;
  const Camera& cam = scene.camera;
  auto bytesHash = [](const auto& v) {
    return std::hash<std::string_view>{}(std::string_view(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(v[0])));
  };
  nlohmann::json k = {
      {"input", c.render.input},
      {"triangles", {soup.size(), bytesHash(soup.v0), bytesHash(soup.v1), bytesHash(soup.v2)}},
      {"camera", {cam.eye.x, cam.eye.y, cam.eye.z, cam.target.x, cam.target.y, cam.target.z, cam.up.x, cam.up.y, cam.up.z,
                  cam.fovDeg, scene.settings.width, scene.settings.height}},
      {"workload", {c.rays, c.count, c.seed, c.aoRadius}},
      {"embree", {c.embreeThreads, s.setup.shader.robust.triangle != TriangleTest::Watertight}},
  };
  for (const Light& l : scene.lights)
    k["lights"].push_back({int(l.kind), l.position.x, l.position.y, l.position.z, l.direction.x, l.direction.y, l.direction.z});
  return k.dump();
}

double TraceYardstick::trace() { return anyHit_ ? embree().occluded(rays_.rays, hits_) : embree().closest(rays_.rays, hits_); }

bool TraceYardstick::sameAs(const TraceYardstick& o) const {
  if (input_ != o.input_ || triangles_ != o.triangles_ || anyHit_ != o.anyHit_ || embree().robust() != o.embree().robust() ||
      embree().threads() != o.embree().threads() || rays_.workload != o.rays_.workload ||
      rays_.aoDistance != o.rays_.aoDistance || rays_.rays.size() != o.rays_.rays.size())
    return false;
  // Bit for bit: the same generator over the same triangles gives the same bits.
  return rays_.rays.empty() || std::memcmp(rays_.rays.data(), o.rays_.rays.data(), rays_.rays.size() * sizeof(BatchRay)) == 0;
}

double resolveMinSampleMs(double requested, const std::string& renderer) {
  if (requested >= 0.0) return requested;
  return isSoftwareRenderer(renderer) ? 0.0 : kAutoMinSampleMs;
}

int dispatchesPerSample(double minSampleMs, double shortestMs) {
  // A zero, negative or NaN time (a timer that did not move) asks for the most, so a sample still
  // has a length to measure; an infinite one (nothing timed) for one. NaN fails every comparison
  // below, so it never picks a branch by accident.
  if (!(minSampleMs > 0.0)) return 1;
  if (shortestMs >= minSampleMs) return 1;
  if (!(shortestMs > 0.0)) return 1000;
  return int(std::min(1000.0, std::ceil(minSampleMs / shortestMs)));
}

nlohmann::json traceResult(const TraceCommand& c, const TraceSetup& s, const TraceYardstick& y, GlRayTracer& gl,
                           const TraceRounds& r, const std::string& renderer, uint64_t& overflows) {
  const std::vector<BatchHit> glHits = gl.results();
  const std::vector<BatchHit>& embreeHits = y.hits();
  const bool anyHit = y.anyHit();
  const HitAgreement agree = compareHits(glHits, embreeHits, anyHit, y.rays().rays);
  const std::vector<glm::uvec4> counts = gl.traceCounted();
  uint64_t visits = 0, tests = 0, boxTests = 0, glFound = 0, embreeFound = 0;
  overflows = 0;
  double visitsSq = 0.0, testsSq = 0.0, boxTestsSq = 0.0;
  for (const glm::uvec4& k : counts) {
    visits += k.x;
    tests += k.y;
    boxTests += k.w;
    visitsSq += double(k.x) * double(k.x);
    testsSq += double(k.y) * double(k.y);
    boxTestsSq += double(k.w) * double(k.w);
    overflows += k.z != 0u;
  }
  for (size_t i = 0; i < glHits.size(); ++i) {
    glFound += glHits[i].hit;
    embreeFound += embreeHits[i].hit;
  }

  const RayWorkload& rays = y.rays();
  const EmbreeTracer& embree = y.embree();
  const RenderCommand& rc = c.render;
  const RenderSetup& setup = s.setup;
  const std::shared_ptr<const PreparedScene>& prepared = s.prepared;
  const Workload workload = s.workload;
  const RayTracerOptions& to = s.tracer;
  const std::vector<double>& glMs = r.glMs;
  const std::vector<double>& embreeMs = r.embreeMs;
  const std::vector<std::vector<double>>& copyMs = r.copyMs;
  const double n = double(rays.rays.size());
  const double ms = medianOf(glMs), eMs = medianOf(embreeMs);
  const auto ci = medianInterval(glMs), eCi = medianInterval(embreeMs);
  // The ratio to Embree: across the copies from 6 of them (per copy its paired ratio, then the median
  // of those with its order-statistic interval), else over the rounds.
  std::vector<double> copyRatios;
  if (copyMs.size() > 1)
    for (const std::vector<double>& m : copyMs)
      if (const auto r = pairedRatio(m, embreeMs)) copyRatios.push_back(r->estimate);
  const std::optional<Interval> acrossCopies =
      copyRatios.size() == copyMs.size() && copyMs.size() > 1 ? medianInterval(copyRatios) : std::nullopt;
  const auto ratio = acrossCopies ? acrossCopies : pairedRatio(glMs, embreeMs);
  const auto orNull = [](const std::optional<Interval>& i, bool high) {
    return i ? nlohmann::json(high ? i->high : i->low) : nlohmann::json();
  };
  const BuildStats& b = prepared->stats;
  const double visitsPerRay = n > 0 ? double(visits) / n : 0.0, testsPerRay = n > 0 ? double(tests) / n : 0.0;
  nlohmann::json j;
  j["input"] = rc.input;
  j["workload"] = workloadName(workload);
  j["any_hit"] = anyHit;
  j["rays"] = rays.rays.size();
  j["seed"] = c.seed;
  j["primary_grid"] = {rays.gridWidth, rays.gridHeight};
  j["primary_hits"] = rays.primaryHits;
  if (workload == Workload::Ao) j["ao_distance"] = rays.aoDistance;
  j["frames"] = glMs.size();
  j["measure_stop"] = r.stop;
  j["ci_target_pct"] = r.targetCiPct > 0.0 ? nlohmann::json(r.targetCiPct) : nlohmann::json();
  j["warmup"] = r.warmup;
  j["min_sample_ms"] = r.minSampleMs;
  j["dispatches_per_sample"] = r.dispatches;
  j["ms"] = ms;
  j["ms_ci_low"] = orNull(ci, false);
  j["ms_ci_high"] = orNull(ci, true);
  j["ms_all"] = glMs;
  // The names the experiment tables share with render: one "frame" is one pass over the batch.
  j["frame_ms"] = ms;
  j["frame_ms_ci_low"] = j["ms_ci_low"];
  j["frame_ms_ci_high"] = j["ms_ci_high"];
  j["ci_pct"] = ci && ci->estimate > 0.0 ? nlohmann::json(50.0 * (ci->high - ci->low) / ci->estimate) : nlohmann::json();
  j["frame_ms_all"] = glMs;
  j["mrays_per_s"] = ms > 0 ? n / (ms * 1e3) : 0.0;
  j["embree_ms"] = eMs;
  j["embree_ms_ci_low"] = orNull(eCi, false);
  j["embree_ms_ci_high"] = orNull(eCi, true);
  j["embree_ms_all"] = embreeMs;
  j["embree_mrays_per_s"] = eMs > 0 ? n / (eMs * 1e3) : 0.0;
  j["embree_threads"] = embree.threads();
  j["embree_build_ms"] = embree.buildMs();
  j["embree_robust"] = embree.robust();
  j["ratio_to_embree"] = ratio ? nlohmann::json(ratio->estimate) : nlohmann::json(eMs > 0 ? ms / eMs : 0.0);
  j["ratio_ci_low"] = orNull(ratio, false);
  j["ratio_ci_high"] = orNull(ratio, true);
  j["ratio_interval_over"] = acrossCopies ? "program copies" : "rounds";
  j["program_copies"] = std::max<size_t>(1, copyMs.size());
  if (copyMs.size() > 1) {
    j["ms_copies"] = copyMs;
    j["ratio_to_embree_copies"] = copyRatios;
  }
  j["node_visits_per_ray"] = visitsPerRay;
  j["triangle_tests_per_ray"] = testsPerRay;
  j["box_tests_per_ray"] = n > 0 ? double(boxTests) / n : 0.0;  // a wide node visit tests several boxes
  // 95% intervals of the per-ray means over this batch (normal approximation: the batch has
  // thousands of rays; the counts are bounded, so the central limit theorem applies). Another builder
  // traced with the same seed gets the same rays: comparing two such means with these intervals as if
  // independent is conservative (the per-ray counts are positively correlated).
  // (The bytes below are over the mirror's sample of the rays, so the count is a parameter.)
  const auto meanIntervalOver = [](double count, double sum, double sumSq, const char* key, nlohmann::json& out) {
    if (count < 2) {
      out[std::string(key) + "_ci_low"] = nullptr;
      out[std::string(key) + "_ci_high"] = nullptr;
      return;
    }
    const double mean = sum / count, var = std::max(0.0, (sumSq - count * mean * mean) / (count - 1.0));
    const double half = 1.959964 * std::sqrt(var / count);  // the normal distribution's 97.5% quantile
    out[std::string(key) + "_ci_low"] = mean - half;
    out[std::string(key) + "_ci_high"] = mean + half;
  };
  const auto meanInterval = [&](double sum, double sumSq, const char* key, nlohmann::json& out) {
    meanIntervalOver(double(n), sum, sumSq, key, out);
  };
  meanInterval(double(visits), visitsSq, "node_visits_per_ray", j);
  meanInterval(double(tests), testsSq, "triangle_tests_per_ray", j);
  meanInterval(double(boxTests), boxTestsSq, "box_tests_per_ray", j);
  // Bytes fetched per ray: the GLSL does not count them, so the kernel's C++ mirror traces every
  // stride-th ray of the same batch again (all of them up to kBytesMirrorRays) and counts them
  // exactly (traversal/kernel_*.hpp). The means and intervals are over those rays (bytes_rays).
  const BytesFetched fetched = mirrorBytesFetched(prepared->packed, to.kernel, to.robust, anyHit, rays.rays, kBytesMirrorRays);
  j["bytes_source"] = "mirror";
  j["bytes_rays"] = fetched.rays;
  j["bytes_ray_stride"] = fetched.stride;
  const char* byteKeys[3] = {"node_bytes_per_ray", "triangle_bytes_per_ray", "stack_bytes_per_ray"};
  for (int f = 0; f < 3; ++f) {
    const double m = double(fetched.rays);
    j[byteKeys[f]] = m > 0 ? fetched.sum[f] / m : 0.0;
    meanIntervalOver(m, fetched.sum[f], fetched.sumSq[f], byteKeys[f], j);
  }
  j["ray_cost"] = prepared->cost.traversalCost * visitsPerRay + prepared->cost.intersectionCost * testsPerRay;
  j["stack_overflow_rays"] = overflows;
  j["hits"] = glFound;
  j["embree_hits"] = embreeFound;
  j["hit_mismatches"] = agree.mismatches;
  j["persistent_threads"] = gl.persistentThreads();
  j["hit_miss_mismatches"] = agree.hitMiss;
  j["hit_ties"] = agree.ties;
  j["builder"] = rc.builder;
  j["layout"] = prepared->packed.layout;
  j["triangle_format"] = prepared->packed.triangleFormat;  // "triangles" is the triangle count
  j["kernel"] = to.kernel;
  j["leaf_size"] = setup.buildReview.leafSize;
  j["warnings"] = setup.buildReview.warnings;
  j["robust"] = robustnessName(to.robust);
  j["storage"] = storageName(to.storage);
  j["triangles"] = prepared->soup.size();
  j["build_ms"] = b.buildMs;
  addGpuBuildTiming(j, *prepared, rc.builder, s.setup.build, rc.gpuBuilds);
  j["sah_cost"] = b.sahCost;
  j["references"] = b.references;
  j["tree_hash"] = prepared->treeHash();
  j["epo"] = prepared->endPointOverlap();
  j["nodes"] = b.nodes;
  j["leaves"] = b.leaves;
  j["bvh_depth"] = b.depth;
  j["bytes"] = b.bytes;
  j["bytes_per_triangle"] = double(b.bytes) / double(prepared->soup.size());
  j["optimize"] = rc.optimize.empty() ? nlohmann::json() : nlohmann::json(rc.optimize);
  j["sah_before_optimize"] = b.sahBeforeOptimize;
  j["optimize_ms"] = b.optimizeMs;
  j["backend"] = backendName(setup.backend);
  j["renderer"] = renderer;
  j["gpu"] = !isSoftwareRenderer(renderer);
  return j;
}

}  // namespace bvhlab
