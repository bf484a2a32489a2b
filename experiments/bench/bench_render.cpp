// Frame time of the GLSL tracer: specialised shader vs --uber on the same scene, same run
// (the specialisation target is >= 1.5x on an analytic-only scene), and the report's scene.
// Frames are timed after warm-up draws (llvmpipe compiles at the first draw); Google Benchmark
// reports the median over repetitions.
#include <filesystem>
#include <memory>

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

void renderScene(benchmark::State& state, const char* sceneFile, bool uber) {
  context();
  std::filesystem::path path = std::filesystem::path(BVHLAB_SOURCE_DIR) / "datasets/scenes" / sceneFile;
  std::unique_ptr<PreparedScene> p;
  try {
    p = prepareScene(loadScene(path), "sah-binned", BuildOptions{});
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  ShaderOptions o;
  o.maxDepth = p->scene.settings.maxDepth;
  o.uber = uber;
  o.bvhStackSize = stackSizeFor(std::max<uint32_t>(1, p->packed.depth));
  FrameOptions f;
  f.width = 640;
  f.height = 360;
  f.camera = p->scene.camera;
  f.exposure = p->scene.settings.exposure;
  GpuRenderer r(*p, o, f);
  for (int i = 0; i < 2; ++i) r.drawFrame();  // warm-up: JIT compile
  for (auto _ : state) state.SetIterationTime(r.drawFrame() / 1000.0);
  state.counters["effective_depth"] = r.shader().effectiveDepth;
  state.counters["source_lines"] = double(std::count(r.shader().source.begin(), r.shader().source.end(), '\n'));
}

}  // namespace

BENCHMARK_CAPTURE(renderScene, analytic_specialised, "analytic.toml", false)->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(5);
BENCHMARK_CAPTURE(renderScene, analytic_uber, "analytic.toml", true)->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(5);
BENCHMARK_CAPTURE(renderScene, shadows_specialised, "shadows.toml", false)->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(5);
BENCHMARK_CAPTURE(renderScene, shadows_uber, "shadows.toml", true)->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(5);
BENCHMARK_CAPTURE(renderScene, report_specialised, "report.toml", false)->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK_CAPTURE(renderScene, report_uber, "report.toml", true)->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(3);

BENCHMARK_MAIN();
