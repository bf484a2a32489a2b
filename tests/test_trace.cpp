// `bvhlab trace`'s pieces: the ray workloads (deterministic, and what each claims: shadow rays end at
// the light, diffuse directions are cosine-distributed), the GLSL ray tracer against its C++ mirror
// per ray (answer and counters), Embree's answers against ours, and the command's JSON.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_run.hpp"
#include "datasets/procedural.hpp"
#include "datasets/scene_io.hpp"
#include "render/frame_stats.hpp"
#include "render/gl_context.hpp"
#include "render/prepared_scene.hpp"
#include "render/ray_tracer_gl.hpp"
#include "render/trace_run.hpp"
#include "render/workloads.hpp"
#include "traversal/embree_tracer.hpp"
#include "traversal/kernels.hpp"
#include "require.hpp"

namespace bvhlab {
namespace {

namespace fs = std::filesystem;

[[maybe_unused]] ::testing::Environment* const kRemoveTestDir =
    ::testing::AddGlobalTestEnvironment(new clitest::RemoveTestDir);

std::unique_ptr<PreparedScene> prepared(Mesh mesh, const std::string& builder = "sah-binned") {
  MeshSceneOptions mo;
  mo.groundPlane = false;
  return prepareScene(makeMeshScene(std::move(mesh), mo), builder, BuildOptions{});
}

RayWorkload workload(const PreparedScene& p, Workload w, uint32_t count, uint64_t seed, const EmbreeTracer& embree) {
  WorkloadRequest r;
  r.workload = w;
  r.count = count;
  r.seed = seed;
  r.width = p.scene.settings.width;
  r.height = p.scene.settings.height;
  return generateWorkload(r, p.scene, p.soup, [&embree](const std::vector<BatchRay>& rays) {
    std::vector<BatchHit> hits;
    embree.closest(rays, hits);
    return hits;
  });
}

bool sameRays(const std::vector<BatchRay>& a, const std::vector<BatchRay>& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i)
    if (a[i].origin != b[i].origin || a[i].dir != b[i].dir || a[i].tMin != b[i].tMin ||
        !(a[i].tMax == b[i].tMax))
      return false;
  return true;
}

TEST(TraceWorkloads, AreDeterministicFromTheSeed) {
  auto p = prepared(makeUvSphere(32, 16));
  EmbreeTracer embree(p->soup, 2);
  for (Workload w : {Workload::Primary, Workload::Shadow, Workload::Specular, Workload::Diffuse, Workload::Ao}) {
    SCOPED_TRACE(workloadName(w));
    const RayWorkload a = workload(*p, w, 2000, 7, embree), b = workload(*p, w, 2000, 7, embree);
    EXPECT_EQ(a.rays.size(), 2000u);
    EXPECT_TRUE(sameRays(a.rays, b.rays));
    for (const BatchRay& r : a.rays) {
      ASSERT_TRUE(std::isfinite(r.origin.x) && std::isfinite(r.dir.x) && std::isfinite(r.dir.y) && std::isfinite(r.dir.z));
      ASSERT_NEAR(glm::length(r.dir), 1.0f, 1e-5f);
    }
    // Only the random workloads depend on the seed.
    const RayWorkload c = workload(*p, w, 2000, 8, embree);
    const bool random = w == Workload::Diffuse || w == Workload::Ao || (w == Workload::Shadow && p->scene.lights.size() > 1);
    if (random) {
      EXPECT_FALSE(sameRays(a.rays, c.rays));
    } else if (w != Workload::Shadow) {
      EXPECT_TRUE(sameRays(a.rays, c.rays));
    }
  }
}

TEST(TraceWorkloads, ShadowRaysEndAtALight) {
  MeshSceneOptions mo;
  mo.groundPlane = false;
  Scene scene = makeMeshScene(makeUvSphere(32, 16), mo);
  Light point;  // beside the directional key and fill of a mesh scene
  point.position = scene.camera.eye + glm::vec3(0.0f, 2.0f, 0.0f);
  scene.lights.push_back(point);
  auto p = prepareScene(std::move(scene), "sah-binned", BuildOptions{});
  size_t toPoint = 0;
  EmbreeTracer embree(p->soup, 2);
  const RayWorkload w = workload(*p, Workload::Shadow, 1000, 3, embree);
  ASSERT_EQ(w.rays.size(), 1000u);
  for (const BatchRay& r : w.rays) {
    float best = INFINITY;
    for (const Light& l : p->scene.lights) {
      if (l.kind == LightKind::Directional) {
        if (std::isinf(r.tMax)) best = std::min(best, glm::length(r.dir + glm::normalize(l.direction)));
      } else {
        // The end point, relative to the light's distance: float rounding of o + t d (a few ulps).
        const float miss = glm::length(r.origin + r.tMax * r.dir - l.position) / std::max(1.0f, glm::length(l.position));
        toPoint += std::isfinite(r.tMax) && miss < 1e-5f;
        best = std::min(best, miss);
      }
    }
    ASSERT_LT(best, 1e-5f) << "a shadow ray that ends at no light";
  }
  EXPECT_GT(toPoint, w.rays.size() / 5);  // one light in three is the point light
}

// With Malley's method cos^2(theta) = 1 - u1 is uniform on [0, 1] for a cosine-weighted direction;
// uniform hemisphere sampling would give cos(theta) uniform instead (KS distance 0.25 from this).
TEST(TraceWorkloads, DiffuseDirectionsAreCosineDistributed) {
  auto p = prepared(makeGridPlane(8, 8));  // every hit's normal is +-Y
  EmbreeTracer embree(p->soup, 2);
  const uint32_t n = 20000;
  for (Workload kind : {Workload::Diffuse, Workload::Ao}) {
    const RayWorkload w = workload(*p, kind, n, 11, embree);
    ASSERT_EQ(w.rays.size(), n);
    std::vector<double> cos2, phi;
    for (const BatchRay& r : w.rays) {
      cos2.push_back(double(r.dir.y) * double(r.dir.y));
      phi.push_back((std::atan2(double(r.dir.z), double(r.dir.x)) + M_PI) / (2.0 * M_PI));
    }
    // All on the side the camera sees (the camera is above the plane: +Y).
    EXPECT_TRUE(std::all_of(w.rays.begin(), w.rays.end(), [](const BatchRay& r) { return r.dir.y >= 0.0f; }));
    // Kolmogorov-Smirnov against U(0, 1): the critical value at alpha = 0.001 is 1.95 / sqrt(n).
    auto ks = [](std::vector<double> v) {
      std::sort(v.begin(), v.end());
      double d = 0.0;
      for (size_t i = 0; i < v.size(); ++i)
        d = std::max({d, double(i + 1) / double(v.size()) - v[i], v[i] - double(i) / double(v.size())});
      return d;
    };
    const double critical = 1.95 / std::sqrt(double(n));
    EXPECT_LT(ks(cos2), critical) << workloadName(kind) << ": cos^2(theta) is not uniform";
    EXPECT_LT(ks(phi), critical) << workloadName(kind) << ": the azimuth is not uniform";
    if (kind == Workload::Ao) {
      for (const BatchRay& r : w.rays) ASSERT_EQ(r.tMax, w.aoDistance);
    }
  }
}

TEST(TraceWorkloads, BadRequestsAreRefused) {
  auto p = prepared(makeUvSphere(8, 4));
  EmbreeTracer embree(p->soup, 1);
  EXPECT_THROW(workload(*p, Workload::Primary, 0, 1, embree), std::invalid_argument);
  EXPECT_THROW(parseWorkload("difuse"), std::invalid_argument);
  // A camera that sees no triangle: no secondary rays can start anywhere.
  Scene s = p->scene;
  s.camera.target = s.camera.eye + (s.camera.eye - s.camera.target);
  WorkloadRequest r;
  r.workload = Workload::Diffuse;
  r.count = 100;
  EXPECT_THROW(generateWorkload(r, s, p->soup, [&](const std::vector<BatchRay>& rays) {
                 std::vector<BatchHit> h;
                 embree.closest(rays, h);
                 return h;
               }),
               InputError);
}

// Embree's threads share the rays in chunks (traversal/embree_tracer.cpp): every ray answered, the
// same answers for any thread count, also when the count is not a multiple of the chunk or is
// smaller than one chunk per thread.
TEST(TraceWorkloads, EmbreeAnswersEveryRayWhateverItsThreads) {
  auto p = prepared(makeUvSphere(32, 16));
  const glm::vec3 centre(0.0f);
  for (size_t count : {size_t(1), size_t(65), size_t(1000)}) {
    std::vector<BatchRay> rays(count);
    for (size_t i = 0; i < count; ++i) {  // from a ring outside the sphere, through its centre: all hit
      const float a = 6.2831853f * float(i) / float(count);
      rays[i].origin = glm::vec3(5.0f * std::cos(a), 0.3f, 5.0f * std::sin(a));
      rays[i].dir = glm::normalize(centre - rays[i].origin);
      rays[i].tMin = 0.0f;
      rays[i].tMax = 100.0f;
    }
    std::vector<BatchHit> one;
    EmbreeTracer(p->soup, 1).closest(rays, one);
    ASSERT_EQ(one.size(), count);
    for (size_t i = 0; i < count; ++i) ASSERT_TRUE(one[i].hit) << "ray " << i << " of " << count;
    for (unsigned threads : {2u, 3u}) {
      std::vector<BatchHit> many;
      EmbreeTracer(p->soup, threads).closest(rays, many);
      ASSERT_EQ(many.size(), count);
      for (size_t i = 0; i < count; ++i) {
        EXPECT_EQ(many[i].hit, one[i].hit) << threads << " threads, ray " << i << " of " << count;
        EXPECT_EQ(many[i].prim, one[i].prim) << threads << " threads, ray " << i << " of " << count;
        EXPECT_EQ(many[i].t, one[i].t) << threads << " threads, ray " << i << " of " << count;
      }
    }
  }
}

// Rays answered differently: hit vs miss, or (closest hit) different triangles at different distances;
// different triangles at the same distance (through a shared edge) are a tie, not a mismatch. 1e-5
// relative: far above both tracers' rounding of t (a few ulps), far below any gap between surfaces here.
// The product's comparison (render/trace_run.hpp compareHits): ties within the rounding of t aside.
size_t mismatches(const std::vector<BatchHit>& ours, const std::vector<BatchHit>& theirs, bool anyHit,
                  const std::vector<BatchRay>& rays) {
  return compareHits(ours, theirs, anyHit, rays).mismatches;
}

// Ties: two closest hits on different triangles whose distances differ by the rounding of t, which
// is relative to t for long rays and absolute, at the coordinates' magnitude, for short ones.
TEST(CompareHits, TiesAllowTheRoundingOfTAtTheCoordinatesMagnitude) {
  auto hit = [](uint32_t prim, float t) { BatchHit h; h.hit = true; h.prim = prim; h.t = t; return h; };
  const BatchRay corner{glm::vec3(5.0f, 2.0f, -4.0f), 0.0f, glm::vec3(0.0f, 0.0f, 1.0f), 1e30f};
  const BatchRay origin{glm::vec3(0.0f), 0.0f, glm::vec3(0.0f, 0.0f, 1.0f), 1e30f};
  // A short ray at coordinates ~5: 3.7e-7 apart is ~3 ulps of 5 (a tie); 1e-4 apart is not.
  HitAgreement a = compareHits({hit(3, 0.0061351f)}, {hit(9, 0.0061355f)}, false, {corner});
  EXPECT_EQ(a.ties, 1u);
  EXPECT_EQ(a.mismatches, 0u);
  a = compareHits({hit(3, 0.0061f)}, {hit(9, 0.0062f)}, false, {corner});
  EXPECT_EQ(a.mismatches, 1u);
  // From the origin: relative to t (2^-16).
  a = compareHits({hit(3, 100.0f)}, {hit(9, 100.001f)}, false, {origin});
  EXPECT_EQ(a.ties, 1u);
  a = compareHits({hit(3, 100.0f)}, {hit(9, 100.01f)}, false, {origin});
  EXPECT_EQ(a.mismatches, 1u);
  // Hit against miss, any-hit answers, NaN, and lengths that differ.
  BatchHit miss;
  a = compareHits({hit(3, 1.0f)}, {miss}, false, {origin});
  EXPECT_EQ(a.hitMiss, 1u);
  EXPECT_EQ(compareHits({hit(3, 1.0f)}, {hit(9, 5.0f)}, true, {origin}).mismatches, 0u);
  EXPECT_EQ(compareHits({hit(3, std::nanf(""))}, {hit(9, 1.0f)}, false, {origin}).mismatches, 1u);
  EXPECT_THROW(compareHits({hit(3, 1.0f)}, {hit(9, 1.0f)}, false, {}), std::invalid_argument);
}

std::unique_ptr<GlContext> contextOrSkip() {
  try {
    const char* backend = std::getenv("BVHLAB_GL_BACKEND");
    return createContext(backend && *backend ? parseBackend(backend) : Backend::OSMesa);
  } catch (const std::exception& e) {
    return nullptr;
  }
}

// Every kernel's GLSL run over a ray batch gives its C++ mirror's answer and counters, per ray, for
// closest and any hit, on a random triangle soup (overlapping triangles: deep, messy trees).
TEST(TraceGlsl, EqualsTheMirrorPerRay) {
  auto ctx = contextOrSkip();
  if (!ctx) BVHLAB_SKIP_OR_FAIL("no OpenGL 4.5 context");
  auto p = prepared(makeTriangleSoup(3000, 5, 0.01f, 0.1f));
  EmbreeTracer embree(p->soup, 2);
  for (Workload w : {Workload::Primary, Workload::Diffuse, Workload::Shadow}) {
    const RayWorkload rays = workload(*p, w, 1500, 2, embree);
    const bool anyHit = isAnyHit(w);
    for (const KernelInfo& k : kernels())
      for (Robustness robust : {Robustness::Watertight, Robustness{}}) {
        SCOPED_TRACE(std::string(workloadName(w)) + " / " + k.name + " / " + robustnessName(robust));
        RayTracerOptions o;
        o.kernel = k.name;
        o.robust = robust;
        o.anyHit = anyHit;
        GlRayTracer gl(p->packed, o);
        gl.setRays(rays.rays);
        std::vector<BatchHit> hits;
        const std::vector<glm::uvec4> counts = gl.traceCounted(&hits);
        gl.trace(3);  // a sample of three dispatches back to back (--min-sample-ms): the same answers
        const std::vector<BatchHit> timed = gl.results();
        const glsl::Storage storage(p->packed, stackSizeFor(p->packed.depth));
        int failures = 0;
        size_t found = 0;
        for (size_t i = 0; i < rays.rays.size() && failures < 3; ++i) {
          found += hits[i].hit;
          const BatchRay& r = rays.rays[i];
          glsl::Counters c;
          glsl::MeshHit mh{};
          bool found;
          uint32_t prim = BatchHit::kNoPrim;
          if (anyHit) {
            found = k.any(robust)(storage, glsl::Ray{r.origin, r.dir}, r.tMin, r.tMax, c);
          } else {
            found = k.closest(robust)(storage, glsl::Ray{r.origin, r.dir}, r.tMin, r.tMax, mh, c);
            uint material, mesh;
            if (found) glsl::loadTriangleIds(storage, mh.tri, prim, material, mesh);
          }
          const bool same = hits[i].hit == found && counts[i].x == c.nodeVisits && counts[i].y == c.triTests &&
                            counts[i].z == 0u && (anyHit || !found || hits[i].prim == prim) &&
                            timed[i].hit == hits[i].hit && timed[i].prim == hits[i].prim;
          if (!same) {
            ++failures;
            ADD_FAILURE() << "ray " << i << ": GLSL " << hits[i].hit << " prim " << hits[i].prim << " visits "
                          << counts[i].x << " tests " << counts[i].y << "; mirror " << found << " prim " << prim
                          << " visits " << c.nodeVisits << " tests " << c.triTests;
          }
        }
        EXPECT_GT(found, rays.rays.size() / 20) << "too few hits for the comparison to mean much";
      }
  }
}

// Embree and the watertight GLSL kernels agree on every ray (closest-hit ties on shared edges aside).
TEST(TraceGlsl, AgreesWithEmbree) {
  auto ctx = contextOrSkip();
  if (!ctx) BVHLAB_SKIP_OR_FAIL("no OpenGL 4.5 context");
  std::vector<std::pair<std::string, std::unique_ptr<PreparedScene>>> scenes;
  scenes.emplace_back("sphere", prepared(makeUvSphere(64, 32)));
  scenes.emplace_back("cube", prepared(makeCube(6), "median"));
  scenes.emplace_back("soup", prepared(makeTriangleSoup(5000, 9), "sbvh"));
  const fs::path bunny = fs::path(BVHLAB_SOURCE_DIR) / "datasets/cache/meshes/bunny00.off";
  if (fs::exists(bunny)) {
    MeshSceneOptions mo;
    mo.groundPlane = false;
    scenes.emplace_back("bunny", prepareScene(loadMeshScene(bunny, mo), "ploc", BuildOptions{}));
  }
  // Rays that hit, per workload over all scenes (secondary rays off the convex sphere and cube hit nothing).
  std::map<std::string, size_t> hitsPerWorkload;
  for (const auto& [name, p] : scenes) {
    EmbreeTracer embree(p->soup, 2);
    for (Workload w : {Workload::Primary, Workload::Shadow, Workload::Specular, Workload::Diffuse, Workload::Ao}) {
      SCOPED_TRACE(name + " / " + workloadName(w));
      const RayWorkload rays = workload(*p, w, 4000, 1, embree);
      RayTracerOptions o;
      o.anyHit = isAnyHit(w);
      GlRayTracer gl(p->packed, o);
      gl.setRays(rays.rays);
      gl.trace();
      const std::vector<BatchHit> ours = gl.results();
      std::vector<BatchHit> theirs;
      o.anyHit ? embree.occluded(rays.rays, theirs) : embree.closest(rays.rays, theirs);
      size_t hits = 0;
      for (const BatchHit& h : ours) hits += h.hit;
      EXPECT_EQ(mismatches(ours, theirs, o.anyHit, rays.rays), 0u);
      hitsPerWorkload[workloadName(w)] += hits;
    }
  }
  for (const std::string& w : workloadNames()) EXPECT_GT(hitsPerWorkload[w], 0u) << w << ": no ray hit anything";
}

// Every bench scene (datasets/scenes/bench/, but the 1M and 10M scaling scenes: too large for a unit
// test), a small batch per workload: the watertight GLSL kernel over a SAH tree and Embree give the same
// answers (closest-hit ties at equal distance aside).
class BenchSceneTrace : public ::testing::TestWithParam<std::string> {};

TEST_P(BenchSceneTrace, GlslAgreesWithEmbree) {
  auto ctx = contextOrSkip();
  if (!ctx) BVHLAB_SKIP_OR_FAIL("no OpenGL 4.5 context");
  const fs::path file = fs::path(BVHLAB_SOURCE_DIR) / "datasets/scenes/bench" / GetParam();
  Scene scene;
  try {
    scene = loadScene(file);
  } catch (const InputError& e) {
    // Fetched data missing: datasets/fetch.sh (CI fetches it and sets BVHLAB_REQUIRE_ALL=1: a failure there).
    BVHLAB_SKIP_OR_FAIL(e.what());
  }
  auto p = prepareScene(std::move(scene), "sah-binned", BuildOptions{});
  EmbreeTracer embree(p->soup, 2);
  for (Workload w : {Workload::Primary, Workload::Shadow, Workload::Diffuse, Workload::Ao}) {
    SCOPED_TRACE(workloadName(w));
    const RayWorkload rays = workload(*p, w, 2000, 4, embree);
    RayTracerOptions o;
    o.anyHit = isAnyHit(w);
    GlRayTracer gl(p->packed, o);
    gl.setRays(rays.rays);
    gl.trace();
    const std::vector<BatchHit> ours = gl.results();
    std::vector<BatchHit> theirs;
    o.anyHit ? embree.occluded(rays.rays, theirs) : embree.closest(rays.rays, theirs);
    EXPECT_EQ(mismatches(ours, theirs, o.anyHit, rays.rays), 0u);
  }
}

std::vector<std::string> benchScenes() {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(fs::path(BVHLAB_SOURCE_DIR) / "datasets/scenes/bench"))
    if (e.path().extension() == ".toml" && e.path().filename() != "scaling_1M.toml" &&
        e.path().filename() != "scaling_10M.toml")
      out.push_back(e.path().filename().string());
  std::sort(out.begin(), out.end());
  return out;
}

INSTANTIATE_TEST_SUITE_P(Bench, BenchSceneTrace, ::testing::ValuesIn(benchScenes()),
                         [](const ::testing::TestParamInfo<std::string>& i) {
                           std::string name = i.param.substr(0, i.param.size() - 5);
                           std::replace(name.begin(), name.end(), '-', '_');  // gtest names: [A-Za-z0-9_]
                           return name;
                         });

TEST(TraceCli, JsonHasTheExpectedKeys) {
  const fs::path bunny = fs::path(BVHLAB_SOURCE_DIR) / "datasets/cache/meshes/bunny00.off";
  const std::string input = fs::exists(bunny) ? bunny.string() : clitest::scene("mesh.toml").string();
  if (!fs::exists(input)) BVHLAB_SKIP_OR_FAIL("no mesh input");
  clitest::Result r = clitest::run("trace " + input + " --rays diffuse --json --count 3000 --frames 6 --warmup 1");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  for (const char* key : {"rays", "workload", "ms", "mrays_per_s", "embree_ms", "embree_mrays_per_s", "ratio_to_embree",
                          "node_visits_per_ray", "triangle_tests_per_ray", "hit_mismatches"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["workload"], "diffuse");
  EXPECT_EQ(j["rays"], 3000);
  EXPECT_EQ(j["hit_mismatches"], 0);
  EXPECT_GT(j["node_visits_per_ray"].get<double>(), 1.0);
  EXPECT_GT(j["ms"].get<double>(), 0.0);
  EXPECT_GT(j["embree_ms"].get<double>(), 0.0);
  EXPECT_FALSE(j["ratio_ci_low"].is_null());  // 6 rounds: an interval exists
  EXPECT_EQ(j["embree_robust"], true);         // watertight triangles (the default): Embree's robust mode

  // The fast triangle test is timed against Embree's default (non-robust) mode, on the same rays.
  r = clitest::run("trace " + input + " --rays diffuse --json --count 3000 --frames 1 --warmup 0 --robust fast");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json fast = nlohmann::json::parse(r.out);
  EXPECT_EQ(fast["embree_robust"], false);
  EXPECT_EQ(fast["robust"], "fast");
  EXPECT_EQ(fast["rays"], 3000);
  EXPECT_GT(fast["embree_ms"].get<double>(), 0.0);

  r = clitest::run("trace " + input + " --rays sideways");
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.err.find("primary, shadow, specular, diffuse, ao"), std::string::npos) << r.err;
}

// How many dispatches make a timed sample: enough for --min-sample-ms after the warm-up's shortest;
// one when none is asked for or a dispatch is long enough; bounded; a NaN or zero time never picks
// the count by accident. The default length is the renderer's: none on llvmpipe, 10 ms on a GPU.
TEST(TraceTiming, DispatchesPerSampleCoverTheSampleLength) {
  EXPECT_EQ(dispatchesPerSample(0.0, 0.4), 1);
  EXPECT_EQ(dispatchesPerSample(10.0, 0.4), 25);
  EXPECT_EQ(dispatchesPerSample(10.0, 0.3), 34);  // ceil: a sample at least 10 ms long
  EXPECT_EQ(dispatchesPerSample(10.0, 10.0), 1);
  EXPECT_EQ(dispatchesPerSample(10.0, 250.0), 1);
  EXPECT_EQ(dispatchesPerSample(10.0, 1e-6), 1000);
  EXPECT_EQ(dispatchesPerSample(10.0, 0.0), 1000);
  EXPECT_EQ(dispatchesPerSample(10.0, std::nan("")), 1000);
  EXPECT_EQ(dispatchesPerSample(std::nan(""), 0.4), 1);
  EXPECT_EQ(dispatchesPerSample(10.0, std::numeric_limits<double>::infinity()), 1);
  EXPECT_EQ(resolveMinSampleMs(-1.0, "llvmpipe (LLVM 15.0.6, 256 bits)"), 0.0);
  EXPECT_EQ(resolveMinSampleMs(-1.0, "NVIDIA H200/PCIe/SSE2"), kAutoMinSampleMs);
  EXPECT_EQ(resolveMinSampleMs(3.0, "llvmpipe (LLVM 15.0.6, 256 bits)"), 3.0);
  EXPECT_EQ(resolveMinSampleMs(0.0, "NVIDIA H200/PCIe/SSE2"), 0.0);
}

// --min-sample-ms: on llvmpipe the default is one dispatch a sample; asked for a sample much longer
// than a dispatch of 2,000 rays, each timed round repeats the dispatch and reports its mean, with the
// same answers (no mismatch against Embree) and the same counts.
TEST(TraceCli, MinSampleMsRepeatsShortDispatches) {
  const std::string input = clitest::scene("mesh.toml").string();
  if (!fs::exists(input)) BVHLAB_SKIP_OR_FAIL("no mesh input");
  const std::string base = "trace " + input + " --rays primary --json --count 2000 --frames 6 --warmup 1";
  clitest::Result r = clitest::run(base);
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json one = nlohmann::json::parse(r.out);
  EXPECT_EQ(one["min_sample_ms"], 0.0);
  EXPECT_EQ(one["dispatches_per_sample"], 1);
  r = clitest::run(base + " --min-sample-ms 40");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json many = nlohmann::json::parse(r.out);
  EXPECT_EQ(many["min_sample_ms"], 40.0);
  EXPECT_GT(many["dispatches_per_sample"].get<int>(), 1);  // 2,000 rays: well under 40 ms on llvmpipe
  EXPECT_LE(many["dispatches_per_sample"].get<int>(), 1000);
  EXPECT_EQ(many["ms_all"].size(), 6u);
  EXPECT_GT(many["ms"].get<double>(), 0.0);
  EXPECT_EQ(many["hit_mismatches"], 0);
  EXPECT_EQ(many["node_visits_per_ray"], one["node_visits_per_ray"]);
  EXPECT_EQ(many["triangle_tests_per_ray"], one["triangle_tests_per_ray"]);
  r = clitest::run(base + " --min-sample-ms -5");
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.err.find("min-sample-ms"), std::string::npos) << r.err;
}

// --program-copies 6: six compiled copies of the kernel traced every round; the round's GLSL time is
// their median, and the ratio to Embree's interval is [min, max] of the six copies' paired ratios
// (the order-statistic interval of six values). Out-of-range counts are refused.
TEST(TraceCli, ProgramCopiesGiveTheRatioAnIntervalAcrossCopies) {
  const std::string input = clitest::scene("mesh.toml").string();
  if (!fs::exists(input)) BVHLAB_SKIP_OR_FAIL("no mesh input");
  clitest::Result r = clitest::run("trace " + input + " --rays primary --json --count 2000 --frames 6 --warmup 1 --program-copies 6");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["program_copies"], 6);
  EXPECT_EQ(j["ratio_interval_over"], "program copies");
  ASSERT_EQ(j["ms_copies"].size(), 6u);
  const std::vector<double> all = j["ms_all"];
  ASSERT_EQ(all.size(), 6u);
  for (size_t i = 0; i < all.size(); ++i) {
    std::vector<double> round;
    for (const nlohmann::json& copy : j["ms_copies"]) round.push_back(copy.at(i).get<double>());
    EXPECT_DOUBLE_EQ(all[i], medianOf(round));
  }
  const std::vector<double> ratios = j["ratio_to_embree_copies"];
  ASSERT_EQ(ratios.size(), 6u);
  EXPECT_DOUBLE_EQ(j["ratio_ci_low"].get<double>(), *std::min_element(ratios.begin(), ratios.end()));
  EXPECT_DOUBLE_EQ(j["ratio_ci_high"].get<double>(), *std::max_element(ratios.begin(), ratios.end()));
  EXPECT_EQ(j["hit_mismatches"], 0);

  r = clitest::run("trace " + input + " --json --count 100 --frames 1 --program-copies 0");
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.err.find("--program-copies"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace bvhlab
