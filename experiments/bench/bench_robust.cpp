// Frame time of the GLSL tracer per robustness variant (traversal/robustness.hpp) on the bunny and on
// the report's scene, as a ratio to the fast variant measured in the same process, frames interleaved:
// the "accuracy costs time" table. A summary table is printed at the end.
//   ./build/experiments/bench/bench_robust [--benchmark_filter=bunny]
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
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

// Prepared once per scene (the BVH build is not what is measured).
PreparedScene& scene(const std::string& file) {
  static std::map<std::string, std::unique_ptr<PreparedScene>> cache;
  auto it = cache.find(file);
  if (it == cache.end())
    it = cache.emplace(file, prepareScene(loadInput(std::filesystem::path(BVHLAB_SOURCE_DIR) / file), "sah-binned",
                                          BuildOptions{})).first;
  return *it->second;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n == 0 ? 0.0 : (n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]));
}

// Median frame ms by scene and variant, for the summary.
std::map<std::string, std::map<std::string, double>>& medians() {
  static std::map<std::string, std::map<std::string, double>> m;
  return m;
}

// All variants of one scene in one benchmark, interleaved: every iteration (a round) draws one frame of
// each variant, starting with a different one each round, so load drift on a busy machine hits every
// variant alike and the ratios to fast compare frames taken moments apart. The iteration time is the
// round's total; the counters are each variant's median frame ms and its ratio to fast's.
void renderVariants(benchmark::State& state, const char* label, const char* file) {
  context();
  PreparedScene* p = nullptr;
  try {
    p = &scene(file);
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());  // e.g. the bunny is not fetched (bash datasets/fetch.sh)
    return;
  }
  FrameOptions f;
  f.width = 640;
  f.height = 360;
  f.camera = p->scene.camera;
  f.exposure = p->scene.settings.exposure;
  const std::vector<Robustness>& variants = robustnessVariants();
  std::vector<std::unique_ptr<GpuRenderer>> renderers;
  for (Robustness v : variants) {
    ShaderOptions o;
    o.maxDepth = p->scene.settings.maxDepth;
    o.bvhStackSize = stackSizeFor(std::max<uint32_t>(1, p->packed.depth));
    o.robust = v;
    renderers.push_back(std::make_unique<GpuRenderer>(*p, o, f));
    for (int i = 0; i < 2; ++i) renderers.back()->drawFrame();  // warm-up: llvmpipe compiles at the first draw
  }
  std::vector<std::vector<double>> ms(variants.size());
  size_t round = 0;
  for (auto _ : state) {
    double total = 0.0;
    for (size_t k = 0; k < variants.size(); ++k) {
      const size_t i = (round + k) % variants.size();
      ms[i].push_back(renderers[i]->drawFrame());
      total += ms[i].back();
    }
    ++round;
    state.SetIterationTime(total / 1000.0);
  }
  const double fast = median(ms[0]);  // robustnessVariants() starts with fast
  for (size_t i = 0; i < variants.size(); ++i) {
    const std::string name = robustnessName(variants[i]);
    const double m = median(ms[i]);
    medians()[label][name] = m;
    state.counters[name + "_ms"] = m;
    if (fast > 0.0) state.counters[name + "_x_fast"] = m / fast;
  }
}

void registerAll() {
  const std::pair<const char*, const char*> scenes[] = {{"bunny", "datasets/cache/meshes/bunny00.off"},
                                                         {"report", "datasets/scenes/report.toml"}};
  for (const auto& [label, file] : scenes)
    benchmark::RegisterBenchmark(label, renderVariants, label, file)
        ->UseManualTime()
        ->Unit(benchmark::kMillisecond)
        ->Iterations(9);
}

}  // namespace

int main(int argc, char** argv) {
  registerAll();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  std::printf("\nframe time per robustness variant, ratio to fast (same process, median of the timed frames)\n");
  std::printf("%-12s", "variant");
  for (const auto& [label, byVariant] : medians()) std::printf(" %14s %8s", (label + " ms").c_str(), "x fast");
  std::printf("\n");
  for (const std::string& v : robustnessNames()) {
    std::printf("%-12s", v.c_str());
    for (const auto& [label, byVariant] : medians()) {
      auto it = byVariant.find(v), fast = byVariant.find("fast");
      if (it == byVariant.end()) {
        std::printf(" %14s %8s", "-", "-");
        continue;
      }
      std::printf(" %14.2f %8s", it->second,
                  fast != byVariant.end() && fast->second > 0.0
                      ? std::to_string(it->second / fast->second).substr(0, 5).c_str()
                      : "-");
    }
    std::printf("\n");
  }
  return 0;
}
