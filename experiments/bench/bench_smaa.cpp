// Cost of SMAA 1x per quality preset and per pass (edge detection, blending weights, neighbourhood
// blending) at 640x360 on the report scene's rendered frame, next to the tracer's own frame time on
// the same frame (same run). Each pass is waited for (glFinish). Each repetition times ONE application
// (->Iterations(1)->Repetitions(n)) of a pass kept across the repetitions and warmed up once (llvmpipe
// compiles at the first draw), so the "_median" rows are median times, per pass in the edges_ms /
// weights_ms / blend_ms counters too (with "_min", "_max", and Google Benchmark's "_mean", "_stddev",
// "_cv"). Only aggregates are printed.
#include <algorithm>
#include <array>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

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
  static bool warm = false;  // a second warm-up draw, once (reportFrame drew the first)
  if (!warm) f->renderer->drawFrame(), warm = true;
  for (auto _ : state) state.SetIterationTime(f->renderer->drawFrame() / 1000.0);
}

// The SMAA pass of the benchmark now running, kept across its repetitions: created and warmed up once.
SmaaPass& smaaFor(const std::string& key, const SmaaSettings& settings, unsigned input) {
  static std::string cachedKey;
  static std::unique_ptr<SmaaPass> cached;
  if (cachedKey != key || !cached) {
    cached.reset();  // one pass at a time (repetitions of a benchmark run back to back)
    cached = std::make_unique<SmaaPass>(640, 360, settings);
    cached->applyProfiled(input);  // warm-up: JIT compile of the three passes
    cachedKey = key;
  }
  return *cached;
}

void smaaSettings(benchmark::State& state, const char* key, SmaaSettings settings) {
  Frame* f = nullptr;
  try {
    f = &reportFrame();
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  const unsigned input = f->renderer->colorTexture();
  SmaaPass& smaa = smaaFor(key, settings, input);
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

double minimum(const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); }
double maximum(const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); }

// One frame (or one SMAA application) per repetition; the median (and min, max) over the repetitions.
void once(benchmark::internal::Benchmark* b, int repetitions) {
  b->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(1)->Repetitions(repetitions)->ReportAggregatesOnly(true);
  b->ComputeStatistics("min", minimum)->ComputeStatistics("max", maximum);
}
void frames7(benchmark::internal::Benchmark* b) { once(b, 7); }
void applications11(benchmark::internal::Benchmark* b) { once(b, 11); }

}  // namespace

BENCHMARK(tracerFrame)->Name("tracer_report_640x360")->Apply(frames7);
#define BVHLAB_SMAA_BENCH(name, settings) BENCHMARK_CAPTURE(smaaSettings, name, #name, settings)->Apply(applications11)
BVHLAB_SMAA_BENCH(low, SmaaSettings::preset(SmaaPreset::Low));
BVHLAB_SMAA_BENCH(medium, SmaaSettings::preset(SmaaPreset::Medium));
BVHLAB_SMAA_BENCH(high, SmaaSettings::preset(SmaaPreset::High));
BVHLAB_SMAA_BENCH(ultra, SmaaSettings::preset(SmaaPreset::Ultra));
// What each accuracy feature of the high preset costs on its own.
BVHLAB_SMAA_BENCH(high_without_diagonals, withoutDiagonals(SmaaPreset::High));
BVHLAB_SMAA_BENCH(high_without_corner_detection, withoutCornerDetection(SmaaPreset::High));

BENCHMARK_MAIN();
