// Cost of SMAA 1x per quality preset and per pass (edge detection, blending weights, neighbourhood
// blending) at 640x360 on the report scene's rendered frame, next to the tracer's own frame time on
// the same frame (same run). Each pass is waited for (glFinish); medians over the iterations after a
// warm-up application (llvmpipe compiles at the first draw).
#include <filesystem>
#include <memory>

#include <benchmark/benchmark.h>

#include "datasets/scene_io.hpp"
#include "render/gl_context.hpp"
#include "render/gpu_renderer.hpp"
#include "render/smaa.hpp"
#include "traversal/kernels.hpp"

using namespace bvhlab;

namespace {

GlContext& context() {
  static std::unique_ptr<GlContext> ctx = createContext(Backend::OSMesa);
  return *ctx;
}

struct Frame {
  std::unique_ptr<PreparedScene> scene;
  std::unique_ptr<GpuRenderer> renderer;
};

// The report scene rendered once at 640x360 (its colour texture is the SMAA input).
Frame& reportFrame() {
  static Frame f = [] {
    context();
    Frame out;
    out.scene = prepareScene(loadScene(std::filesystem::path(BVHLAB_SOURCE_DIR) / "datasets/scenes/report.toml"),
                             "sah-binned", BuildOptions{});
    ShaderOptions o;
    o.maxDepth = out.scene->scene.settings.maxDepth;
    o.bvhStackSize = stackSizeFor(std::max<uint32_t>(1, out.scene->packed.depth));
    FrameOptions fo;
    fo.width = 640;
    fo.height = 360;
    fo.camera = out.scene->scene.camera;
    fo.exposure = out.scene->scene.settings.exposure;
    out.renderer = std::make_unique<GpuRenderer>(*out.scene, o, fo);
    out.renderer->drawFrame();
    return out;
  }();
  return f;
}

void tracerFrame(benchmark::State& state) {
  Frame* f = nullptr;
  try {
    f = &reportFrame();
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  f->renderer->drawFrame();
  for (auto _ : state) state.SetIterationTime(f->renderer->drawFrame() / 1000.0);
}

void smaaSettings(benchmark::State& state, SmaaSettings settings) {
  Frame* f = nullptr;
  try {
    f = &reportFrame();
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  SmaaPass smaa(640, 360, settings);
  const unsigned input = f->renderer->colorTexture();
  smaa.applyProfiled(input);  // warm-up: JIT compile of the three passes
  double edges = 0, weights = 0, blend = 0;
  for (auto _ : state) {
    const std::array<double, 3> ms = smaa.applyProfiled(input);
    edges += ms[0], weights += ms[1], blend += ms[2];
    state.SetIterationTime((ms[0] + ms[1] + ms[2]) / 1000.0);
  }
  const double n = double(state.iterations());
  state.counters["edges_ms"] = edges / n;
  state.counters["weights_ms"] = weights / n;
  state.counters["blend_ms"] = blend / n;
}

SmaaSettings withoutDiagonals(SmaaPreset preset) {
  SmaaSettings s = SmaaSettings::preset(preset);
  s.maxDiagSearchSteps = 0;
  return s;
}

SmaaSettings withoutCornerDetection(SmaaPreset preset) {
  SmaaSettings s = SmaaSettings::preset(preset);
  s.cornerRounding = 100;
  return s;
}

}  // namespace

BENCHMARK(tracerFrame)->Name("tracer_report_640x360")->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(5);
#define BVHLAB_SMAA_BENCH(name, settings) \
  BENCHMARK_CAPTURE(smaaSettings, name, settings)->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(10)
BVHLAB_SMAA_BENCH(low, SmaaSettings::preset(SmaaPreset::Low));
BVHLAB_SMAA_BENCH(medium, SmaaSettings::preset(SmaaPreset::Medium));
BVHLAB_SMAA_BENCH(high, SmaaSettings::preset(SmaaPreset::High));
BVHLAB_SMAA_BENCH(ultra, SmaaSettings::preset(SmaaPreset::Ultra));
// What each accuracy feature of the high preset costs on its own.
BVHLAB_SMAA_BENCH(high_without_diagonals, withoutDiagonals(SmaaPreset::High));
BVHLAB_SMAA_BENCH(high_without_corner_detection, withoutCornerDetection(SmaaPreset::High));

BENCHMARK_MAIN();
