// ab_revisions.sh's driver: two versions of builders/ (side A: a git revision, side B: the working
// tree) in one process, their builds of one mesh interleaved A B, B A, A B, ... so that both sides
// meet the same machine state, and the paired ratio B/A per round with its median and 95%
// order-statistic interval. The inputs are built once, by the main library, as the app makes them
// (layout's triangle boxes and centroids). Both sides' BuildInput and BuildOptions have the main
// library's layout (the same headers under another namespace name), so they are passed as is.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "builders/builder.hpp"
#include "builders/test_inputs.hpp"
#include "datasets/procedural.hpp"
#include "experiments/bench/heap_policy.hpp"
#include "layout/layout.hpp"

extern "C" double abBuildA(const char* builder, const void* input, const void* options, bool wall, uint64_t* hash);
extern "C" double abBuildB(const char* builder, const void* input, const void* options, bool wall, uint64_t* hash);

int main(int argc, char** argv) {
  using namespace bvhlab;
  CLI::App app("Interleaved A/B of two versions of the builders in one process (ab_revisions.sh).");
  std::string builder = "sah-binned", mesh = testing::bunnyPath().string();
  uint32_t rounds = 100, warmup = 5;
  bool wall = false;
  BuildOptions options;
  options.threads = 1;
  app.add_option("--builder", builder, "registered builder");
  app.add_option("--mesh", mesh, "mesh file, or large1M (makeLargeMesh(1M))");
  app.add_option("--rounds", rounds, "paired rounds")->check(CLI::Range(6u, 1000000u));
  app.add_option("--warmup", warmup, "unpaired builds per side first");
  app.add_option("--threads", options.threads, "BuildOptions::threads");
  app.add_option("--leaf-size", options.maxLeafSize, "BuildOptions::maxLeafSize");
  app.add_option("--bins", options.bins, "BuildOptions::bins");
  app.add_option("--ploc-radius", options.plocRadius, "BuildOptions::plocRadius");
  app.add_option("--ploc-top-down", options.plocTopDown, "BuildOptions::plocTopDown");
  app.add_flag("--wall", wall, "wall time (for several threads) instead of the thread's CPU time");
  std::string heap = "warm";  // as bench_builders: what a build frees, the next one reuses
  app.add_option("--heap", heap, "heap policy: warm, cold or adaptive (glibc's) (experiments/bench/heap_policy.hpp)")
      ->check(CLI::IsMember({"adaptive", "warm", "cold"}));
  CLI11_PARSE(app, argc, argv);
  if (!bench::applyHeapPolicy(*bench::parseHeapPolicy(heap))) {
    std::fprintf(stderr, "ab: --heap %s: the C library refused the policy\n", heap.c_str());
    return 2;
  }

  testing::PrimitiveSet set;
  if (mesh == "large1M") {
    const Mesh m = makeLargeMesh(1'000'000);
    for (const glm::uvec3& t : m.triangles) set.addTriangle(m.positions[t.x], m.positions[t.y], m.positions[t.z]);
  } else {
    set = testing::loadTriangles(mesh);
  }
  if (set.boxes.empty()) {
    std::fprintf(stderr, "ab: %s has no triangles (or could not be read)\n", mesh.c_str());
    return 2;
  }
  TriangleSoup soup;
  soup.v0 = set.v0, soup.v1 = set.v1, soup.v2 = set.v2;
  const std::vector<Aabb> boxes = triangleBoxes(soup);
  const std::vector<glm::vec3> centroids = triangleCentroids(soup);
  const BuildInput input{boxes, centroids, set.v0, set.v1, set.v2};
  validateBuildInput(input, options);
  (void)reviewBuildOptions(builder, options);  // an unknown builder or a bad option: its message

  uint64_t hashA = 0, hashB = 0;
  abBuildA(builder.c_str(), &input, &options, wall, &hashA);
  abBuildB(builder.c_str(), &input, &options, wall, &hashB);
  for (uint32_t k = 0; k < warmup; ++k)
    abBuildA(builder.c_str(), &input, &options, wall, nullptr), abBuildB(builder.c_str(), &input, &options, wall, nullptr);
  std::vector<double> a(rounds), b(rounds), ratio(rounds);
  for (uint32_t r = 0; r < rounds; ++r) {  // A first in even rounds, B first in odd ones
    if (r % 2 == 0) {
      a[r] = abBuildA(builder.c_str(), &input, &options, wall, nullptr);
      b[r] = abBuildB(builder.c_str(), &input, &options, wall, nullptr);
    } else {
      b[r] = abBuildB(builder.c_str(), &input, &options, wall, nullptr);
      a[r] = abBuildA(builder.c_str(), &input, &options, wall, nullptr);
    }
    ratio[r] = b[r] / a[r];
  }
  std::sort(a.begin(), a.end()), std::sort(b.begin(), b.end()), std::sort(ratio.begin(), ratio.end());
  // The median's 95% interval: order statistics n/2 -+ 0.98 sqrt(n) (normal approximation of the
  // binomial count below the median).
  const double half = 0.98 * std::sqrt(double(rounds));
  const size_t lo = size_t(std::max(0.0, std::floor(rounds / 2.0 - half)));
  const size_t hi = std::min(size_t(rounds) - 1, size_t(std::ceil(rounds / 2.0 + half)));
  std::printf("%s on %s (%zu triangles), %u rounds, heap %s, %s ms: A %.3f, B %.3f; B / A %.4f [%.4f, %.4f]; trees %s\n",
              builder.c_str(), mesh.c_str(), boxes.size(), rounds, heap.c_str(), wall ? "wall" : "thread CPU", a[rounds / 2],
              b[rounds / 2], ratio[rounds / 2], ratio[lo], ratio[hi], hashA == hashB ? "identical" : "DIFFER");
  return 0;
}
