// Frame time of the GLSL tracer per robustness variant (traversal/robustness.hpp) on the bunny and on
// the report's scene, as a ratio to the fast variant measured in the same process: the "accuracy
// costs time" table of issue 4. Each benchmark builds its shader once, draws warm-up frames (llvmpipe
// compiles at the first draw) and times frames; the counter x_fast is this variant's median frame time
// over the fast variant's (fast runs first per scene). A summary table is printed at the end.
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

// Median frame ms by scene and variant, for x_fast and the summary.
std::map<std::string, std::map<std::string, double>>& medians() {
  static std::map<std::string, std::map<std::string, double>> m;
  return m;
}

void renderVariant(benchmark::State& state, const char* label, const char* file, const char* variant) {
  context();
  PreparedScene* p = nullptr;
  try {
    p = &scene(file);
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());  // e.g. the bunny is not fetched (bash datasets/fetch.sh)
    return;
  }
  ShaderOptions o;
  o.maxDepth = p->scene.settings.maxDepth;
  o.bvhStackSize = stackSizeFor(std::max<uint32_t>(1, p->packed.depth));
  o.robust = parseRobustness(variant);
  FrameOptions f;
  f.width = 640;
  f.height = 360;
  f.camera = p->scene.camera;
  f.exposure = p->scene.settings.exposure;
  GpuRenderer r(*p, o, f);
  for (int i = 0; i < 2; ++i) r.drawFrame();  // warm-up: JIT compile
  std::vector<double> ms;
  for (auto _ : state) {
    ms.push_back(r.drawFrame());
    state.SetIterationTime(ms.back() / 1000.0);
  }
  const double m = median(ms);
  medians()[label][variant] = m;
  const auto& sceneMedians = medians()[label];
  if (auto fast = sceneMedians.find("fast"); fast != sceneMedians.end() && fast->second > 0.0)
    state.counters["x_fast"] = m / fast->second;
  state.counters["median_ms"] = m;
}

void registerAll() {
  const std::pair<const char*, const char*> scenes[] = {{"bunny", "datasets/cache/meshes/bunny00.off"},
                                                         {"report", "datasets/scenes/report.toml"}};
  for (const auto& [label, file] : scenes)
    for (const std::string& v : robustnessNames())
      benchmark::RegisterBenchmark((std::string(label) + "/" + v).c_str(), renderVariant, label, file,
                                   v.c_str())  // the name table is static: the pointer stays valid
          ->UseManualTime()
          ->Unit(benchmark::kMillisecond)
          ->Iterations(7);
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
