// Frame time of the GLSL tracer: specialised shader vs --uber on the same scene, same run
// (the specialisation target is >= 1.5x on an analytic-only scene), and the report's scene.
// Frames are timed after warm-up draws (llvmpipe compiles at the first draw). Each repetition times
// ONE frame (->Iterations(1)->Repetitions(n)) on a renderer kept across the repetitions, so the
// "_median" row is the median frame time (with "_min" and "_max"; "_mean", "_stddev", "_cv" are
// Google Benchmark's defaults). Only aggregates are printed.
#include <algorithm>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "datasets/scene_io.hpp"
#include "render/gl_context.hpp"
#include "render/gpu_renderer.hpp"
#include "traversal/kernels.hpp"

using namespace bvhlab;

namespace {

GlContext& context() {
  static std::unique_ptr<GlContext> ctx = createContext(Backend::OSMesa);
  return *ctx;
}

// The renderer of the benchmark now running, kept across its repetitions: built and warmed up once.
struct Cached {
  std::string key;
  std::unique_ptr<PreparedScene> scene;
  std::unique_ptr<GpuRenderer> renderer;
};

GpuRenderer& rendererFor(const char* sceneFile, bool uber) {
  context();  // first: the context (a static) must outlive the cached renderer (destroyed in reverse order)
  static Cached cached;
  const std::string key = std::string(sceneFile) + (uber ? "/uber" : "/specialised");
  if (cached.key == key) return *cached.renderer;
  cached = Cached{};  // one renderer at a time (repetitions of a benchmark run back to back)
  std::filesystem::path path = std::filesystem::path(BVHLAB_SOURCE_DIR) / "datasets/scenes" / sceneFile;
  cached.scene = prepareScene(loadScene(path), "sah-binned", BuildOptions{});
  ShaderOptions o;
  o.maxDepth = cached.scene->scene.settings.maxDepth;
  o.uber = uber;
  o.bvhStackSize = stackSizeFor(std::max<uint32_t>(1, cached.scene->packed.depth));
  FrameOptions f;
  f.width = 640;
  f.height = 360;
  f.camera = cached.scene->scene.camera;
  f.exposure = cached.scene->scene.settings.exposure;
  cached.renderer = std::make_unique<GpuRenderer>(*cached.scene, o, f);
  for (int i = 0; i < 2; ++i) cached.renderer->drawFrame();  // warm-up: JIT compile
  cached.key = key;
  return *cached.renderer;
}

void renderScene(benchmark::State& state, const char* sceneFile, bool uber) {
  GpuRenderer* r = nullptr;
  try {
    r = &rendererFor(sceneFile, uber);
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  for (auto _ : state) state.SetIterationTime(r->drawFrame() / 1000.0);
  state.counters["effective_depth"] = r->shader().effectiveDepth;
  state.counters["source_lines"] = double(std::count(r->shader().source.begin(), r->shader().source.end(), '\n'));
}

double minimum(const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); }
double maximum(const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); }

// One frame per repetition; the median (and min, max) over the repetitions.
void frames(benchmark::internal::Benchmark* b, int n) {
  b->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(1)->Repetitions(n)->ReportAggregatesOnly(true);
  b->ComputeStatistics("min", minimum)->ComputeStatistics("max", maximum);
}
void frames7(benchmark::internal::Benchmark* b) { frames(b, 7); }
void frames5(benchmark::internal::Benchmark* b) { frames(b, 5); }

}  // namespace

BENCHMARK_CAPTURE(renderScene, analytic_specialised, "analytic.toml", false)->Apply(frames7);
BENCHMARK_CAPTURE(renderScene, analytic_uber, "analytic.toml", true)->Apply(frames7);
BENCHMARK_CAPTURE(renderScene, shadows_specialised, "shadows.toml", false)->Apply(frames7);
BENCHMARK_CAPTURE(renderScene, shadows_uber, "shadows.toml", true)->Apply(frames7);
BENCHMARK_CAPTURE(renderScene, report_specialised, "report.toml", false)->Apply(frames5);
BENCHMARK_CAPTURE(renderScene, report_uber, "report.toml", true)->Apply(frames5);

BENCHMARK_MAIN();
