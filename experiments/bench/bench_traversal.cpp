// Every registered layout (layout/layouts.hpp) with every one of its kernels (traversal/kernels.hpp)
// against Embree 3 on the same primary rays, in one run: the bunny filling a 640x360 view (the close
// view) and the report scene's camera. One sah-binned tree (leaf size 4) per scene, packed
// into each layout; the GLSL kernels trace it in the compute shader of `bvhlab trace`
// (render/ray_tracer_gl), Embree (its own BVH, robust, every core) the identical ray buffer.
//
// Rounds are interleaved: each round traces every combination and Embree once, in a new shuffled order,
// so machine drift hits all alike. Printed per combination: median time with its 95% interval, the
// median of per-round ratios to Embree's time with its 95% interval (render/frame_stats), and the
// clock-free counts beside them (node visits, box and triangle tests per ray, SAH, bytes per
// triangle), plus rays whose hit/miss answer differs from Embree's. Layouts and kernels come from the
// registries, so a new one appears here without an edit. Target: best <= 1.25x Embree.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "datasets/scene_io.hpp"
#include "layout/layouts.hpp"
#include "render/frame_stats.hpp"
#include "render/gl_context.hpp"
#include "render/prepared_scene.hpp"
#include "render/ray_tracer_gl.hpp"
#include "render/workloads.hpp"
#include "traversal/embree_tracer.hpp"
#include "traversal/kernels.hpp"

using namespace bvhlab;
namespace fs = std::filesystem;

namespace {

constexpr int kWidth = 640, kHeight = 360;
constexpr int kWarmup = 2;   // untimed traces per combination (llvmpipe compiles at the first dispatch)
constexpr int kRounds = 15;  // timed rounds: enough for a 95% interval of a median (>= 6 values)
const char* const kBuilder = "sah-binned";

struct SceneCase {
  std::string name;
  fs::path file;
  bool closeView;  // the bunny: camera moved in until the mesh fills the frame
};

Scene loadCase(const SceneCase& c) {
  Scene s;
  if (c.closeView) {
    MeshSceneOptions mo;
    mo.groundPlane = false;
    s = loadMeshScene(c.file, mo);
    const glm::vec3 toEye = s.camera.eye - s.camera.target;
    s.camera.eye = s.camera.target + 0.45f * toEye;
  } else {
    s = loadInput(c.file);
  }
  s.settings.width = kWidth;
  s.settings.height = kHeight;
  return s;
}

// One layout x kernel over its layout's packing of the scene's tree.
struct Combination {
  const LayoutInfo* layout;
  const KernelInfo* kernel;
  const PreparedScene* prepared;
  std::unique_ptr<GlRayTracer> tracer;
  std::vector<double> ms;
};

std::string intervalText(const std::optional<Interval>& i, int digits) {
  if (!i) return "(too few rounds)";
  char buf[96];
  std::snprintf(buf, sizeof buf, "%.*f [%.*f, %.*f]", digits, i->estimate, digits, i->low, digits, i->high);
  return buf;
}

void layoutsAgainstEmbree(benchmark::State& state, const SceneCase& sc) {
  static std::unique_ptr<GlContext> ctx = createContext(Backend::OSMesa);
  if (!fs::exists(sc.file)) return state.SkipWithError((sc.file.string() + " missing: run datasets/fetch.sh").c_str());
  const Scene base = loadCase(sc);

  std::vector<std::unique_ptr<PreparedScene>> trees;  // one per layout, same builder and options
  std::vector<Combination> combos;
  for (const LayoutInfo& layout : layouts()) {
    trees.push_back(prepareScene(Scene(base), kBuilder, BuildOptions{}, layout.name));
    for (const KernelInfo& kernel : kernelsFor(layout.name)) combos.push_back({&layout, &kernel, trees.back().get(), {}, {}});
  }
  const TriangleSoup& soup = trees.front()->soup;  // every layout packs the same triangles
  EmbreeTracer embree(soup);
  WorkloadRequest request;
  request.count = uint32_t(kWidth) * uint32_t(kHeight);
  request.width = kWidth;
  request.height = kHeight;
  const RayWorkload rays = generateWorkload(request, trees.front()->scene, soup, [&embree](const std::vector<BatchRay>& r) {
    std::vector<BatchHit> hits;
    embree.closest(r, hits);
    return hits;
  });
  std::vector<BatchHit> embreeHits;
  for (Combination& c : combos) {
    RayTracerOptions options;
    options.kernel = c.kernel->name;
    c.tracer = std::make_unique<GlRayTracer>(c.prepared->packed, options);
    c.tracer->setRays(rays.rays);
    for (int i = 0; i < kWarmup; ++i) c.tracer->trace();
  }
  for (int i = 0; i < kWarmup; ++i) embree.closest(rays.rays, embreeHits);

  // Rounds: every combination and Embree (index combos.size()) once each, in a shuffled order.
  std::vector<double> embreeMs;
  std::vector<size_t> order(combos.size() + 1);
  std::iota(order.begin(), order.end(), size_t(0));
  std::mt19937_64 shuffle(0x6c61796f757473ull);  // fixed seed: the same orders every run
  for (auto _ : state) {
    std::shuffle(order.begin(), order.end(), shuffle);
    double roundMs = 0.0;
    for (size_t i : order) {
      const double ms = i < combos.size() ? combos[i].tracer->trace() : embree.closest(rays.rays, embreeHits);
      (i < combos.size() ? combos[i].ms : embreeMs).push_back(ms);
      roundMs += ms;
    }
    state.SetIterationTime(roundMs / 1000.0);  // the benchmark's own time is a whole round
  }

  std::printf("\n%s: %zu primary rays (%dx%d), %zu triangles, %s tree (leaf size 4), %u Embree threads, %d rounds\n",
              sc.name.c_str(), rays.rays.size(), kWidth, kHeight, soup.size(), kBuilder, embree.threads(), kRounds);
  std::printf("  %-26s %-24s %-24s %8s %8s %8s %7s %9s %8s\n", "layout/kernel", "ms [95%]", "x Embree [95%]",
              "visits", "boxes", "tests", "SAH", "B/tri", "hit/miss");
  std::printf("  %-26s %-24s\n", "embree (rtcIntersect1)", intervalText(medianInterval(embreeMs), 2).c_str());
  for (Combination& c : combos) {
    const std::string name = c.layout->name + "/" + c.kernel->name;
    const std::optional<Interval> ratio = pairedRatio(c.ms, embreeMs);
    std::vector<BatchHit> hits;
    const std::vector<glm::uvec4> counts = c.tracer->traceCounted(&hits);
    double visits = 0.0, tests = 0.0, boxes = 0.0;
    for (const glm::uvec4& k : counts) visits += k.x, tests += k.y, boxes += k.w;  // w: box tests (0 if uncounted)
    const double n = double(std::max<size_t>(1, counts.size()));
    size_t hitMiss = 0;  // rays one tracer hits and the other misses (no tolerance needed)
    for (size_t i = 0; i < hits.size() && i < embreeHits.size(); ++i) hitMiss += hits[i].hit != embreeHits[i].hit;
    const BuildStats& b = c.prepared->stats;
    std::printf("  %-26s %-24s %-24s %8.2f %8.2f %8.2f %7.2f %9.1f %8zu\n", name.c_str(),
                intervalText(medianInterval(c.ms), 2).c_str(), intervalText(ratio, 3).c_str(), visits / n, boxes / n,
                tests / n, b.sahCost, double(b.bytes) / double(soup.size()), hitMiss);
    if (ratio) state.counters[name] = ratio->estimate;  // ratio to Embree in the benchmark's own output
  }
  if (const auto e = medianInterval(embreeMs)) state.counters["embree_ms"] = e->estimate;
  std::fflush(stdout);
}

const SceneCase kBunny{"bunny close view", fs::path(BVHLAB_SOURCE_DIR) / "datasets/cache/meshes/bunny00.off", true};
const SceneCase kReport{"report scene", fs::path(BVHLAB_SOURCE_DIR) / "datasets/scenes/report.toml", false};

}  // namespace

BENCHMARK_CAPTURE(layoutsAgainstEmbree, bunny_close, kBunny)
    ->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(kRounds);
BENCHMARK_CAPTURE(layoutsAgainstEmbree, report_primary, kReport)
    ->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(kRounds);

BENCHMARK_MAIN();
