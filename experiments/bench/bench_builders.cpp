// Build time, SAH cost and node count of every registered builder (leaf size 4, Ct = Ci = 1) with 1
// and with 2 threads, on the bunny (75k triangles), a 1M-triangle procedural scene
// (datasets/procedural.hpp makeLargeMesh) and a 1M-triangle bumpy sphere, next to Embree's
// rtcBuildBVH at MEDIUM quality called directly with minimal callbacks ("embree-raw", on an Embree
// device of 2 threads): the reference, same process, same run. Embree's thread count is per process
// (TBB): a "threads=1" device next to a 2-thread one builds with 2 threads (measured: CPU time = 2x
// wall), so there is no 1-thread embree-raw row; the registered `embree` and `embree-low` builders
// ignore BuildOptions::threads (Embree's own pool), so their two rows are the same configuration.
//
// Every benchmark runs --reps repetitions (default 5; ->Repetitions(n)->ReportAggregatesOnly()), in
// random interleaving order unless --benchmark_enable_random_interleaving is given, and the
// figures are the MEDIAN over the repetitions (with min and max, ->ComputeStatistics). The end of
// the output is a table per mesh: median time with 1 and 2 threads, SAH and the ratios against
// embree-raw with 2 threads, then the sah-binned target line (1 thread vs embree-raw with 2 threads).
//   bench_builders [--reps=N] [--benchmark_filter=...]   (the bunny comes from `bash datasets/fetch.sh`)
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <new>
#include <string>
#include <tuple>
#include <vector>

#include <benchmark/benchmark.h>
#include <embree3/rtcore.h>

#include "builders/builder.hpp"
#include "builders/test_inputs.hpp"
#include "datasets/procedural.hpp"

namespace {

using namespace bvhlab;
using bvhlab::testing::PrimitiveSet;

constexpr uint32_t kLeafSize = 4;

const PrimitiveSet& bunny() {
  static const PrimitiveSet set = bvhlab::testing::loadTriangles(bvhlab::testing::bunnyPath());
  return set;
}
const PrimitiveSet& largeMesh() {  // makeLargeMesh: dense and sparse regions, long thin gaps, overlaps
  static const PrimitiveSet set = [] {
    PrimitiveSet s;
    s.name = "large1M";
    const Mesh mesh = makeLargeMesh(1'000'000);
    for (const glm::uvec3& t : mesh.triangles) s.addTriangle(mesh.positions[t.x], mesh.positions[t.y], mesh.positions[t.z]);
    return s;
  }();
  return set;
}
const PrimitiveSet& sphereMesh() {  // 1000 x 500 quads: 1,000,000 triangles
  static const PrimitiveSet set = bvhlab::testing::sphereSoup(1000, 500, 0.2f);
  return set;
}

// ---- Embree MEDIUM, raw: the nodes Embree's own tutorial would make, no conversion ----------------

struct RawNode {
  bool leaf;
};
struct RawInner : RawNode {
  RTCBounds bounds[2];
  RawNode* children[2];
};
struct RawLeaf : RawNode {
  uint32_t count;
  uint32_t ids[1];  // `count` ids follow in the same allocation
};

void* rawCreateNode(RTCThreadLocalAllocator alloc, unsigned int, void*) {
  return new (rtcThreadLocalAlloc(alloc, sizeof(RawInner), 16)) RawInner{{false}, {}, {nullptr, nullptr}};
}
void rawSetChildren(void* node, void** children, unsigned int count, void*) {
  for (unsigned int i = 0; i < count; ++i) static_cast<RawInner*>(node)->children[i] = static_cast<RawNode*>(children[i]);
}
void rawSetBounds(void* node, const RTCBounds** bounds, unsigned int count, void*) {
  for (unsigned int i = 0; i < count; ++i) static_cast<RawInner*>(node)->bounds[i] = *bounds[i];
}
void* rawCreateLeaf(RTCThreadLocalAllocator alloc, const RTCBuildPrimitive* prims, size_t count, void*) {
  auto* leaf = new (rtcThreadLocalAlloc(alloc, sizeof(RawLeaf) + count * sizeof(uint32_t), 16)) RawLeaf{{true}, uint32_t(count), {0}};
  for (size_t i = 0; i < count; ++i) leaf->ids[i] = prims[i].primID;
  return leaf;
}

double halfArea(const RTCBounds& b) {
  const double x = b.upper_x - b.lower_x, y = b.upper_y - b.lower_y, z = b.upper_z - b.lower_z;
  return x * y + y * z + z * x;
}

// SAH (Ct = Ci = 1, normalised by the root) and node count of a raw tree, from Embree's own bounds.
void rawStats(const RawNode* root, const RTCBounds& rootBounds, double& sah, size_t& nodes) {
  double sum = 0.0;
  nodes = 0;
  std::vector<std::pair<const RawNode*, RTCBounds>> stack{{root, rootBounds}};
  while (!stack.empty()) {
    auto [node, bounds] = stack.back();
    stack.pop_back();
    ++nodes;
    if (node->leaf) {
      sum += halfArea(bounds) * static_cast<const RawLeaf*>(node)->count;
    } else {
      sum += halfArea(bounds);
      const auto* inner = static_cast<const RawInner*>(node);
      for (int i = 0; i < 2; ++i) stack.push_back({inner->children[i], inner->bounds[i]});
    }
  }
  sah = sum / halfArea(rootBounds);
}

// One Embree device per thread count ("threads=N"; see the note at the top: the count is per process).
RTCDevice embreeDevice(unsigned threads) {
  static std::map<unsigned, RTCDevice> devices;
  auto& device = devices[threads];
  if (!device) device = rtcNewDevice(("threads=" + std::to_string(threads)).c_str());
  return device;
}

using MeshFn = const PrimitiveSet& (*)();  // meshes are made on first use (a filter may skip them)

void embreeRaw(benchmark::State& state, MeshFn mesh, unsigned threads) {
  const PrimitiveSet* set = &mesh();
  if (set->size() == 0) return state.SkipWithError("mesh missing: run `bash datasets/fetch.sh`");
  RTCDevice device = embreeDevice(threads);
  if (!device) return state.SkipWithError("rtcNewDevice failed");
  std::vector<RTCBuildPrimitive> source(set->size()), prims;
  RTCBounds rootBounds{+INFINITY, +INFINITY, +INFINITY, 0, -INFINITY, -INFINITY, -INFINITY, 0};
  for (size_t i = 0; i < set->size(); ++i) {
    const Aabb& b = set->boxes[i];
    source[i] = {b.min.x, b.min.y, b.min.z, 0u, b.max.x, b.max.y, b.max.z, uint32_t(i)};
    rootBounds.lower_x = std::min(rootBounds.lower_x, b.min.x), rootBounds.upper_x = std::max(rootBounds.upper_x, b.max.x);
    rootBounds.lower_y = std::min(rootBounds.lower_y, b.min.y), rootBounds.upper_y = std::max(rootBounds.upper_y, b.max.y);
    rootBounds.lower_z = std::min(rootBounds.lower_z, b.min.z), rootBounds.upper_z = std::max(rootBounds.upper_z, b.max.z);
  }
  RTCBVH bvh = rtcNewBVH(device);
  const RawNode* root = nullptr;
  for (auto _ : state) {
    prims = source;  // Embree reorders its input: every build starts from a fresh copy (timed)
    RTCBuildArguments args = rtcDefaultBuildArguments();
    args.buildQuality = RTC_BUILD_QUALITY_MEDIUM;
    args.maxBranchingFactor = 2;
    args.maxDepth = 1024;
    args.minLeafSize = 1;
    args.maxLeafSize = kLeafSize;
    args.bvh = bvh;
    args.primitives = prims.data();
    args.primitiveCount = prims.size();
    args.primitiveArrayCapacity = prims.size();
    args.createNode = rawCreateNode;
    args.setNodeChildren = rawSetChildren;
    args.setNodeBounds = rawSetBounds;
    args.createLeaf = rawCreateLeaf;
    root = static_cast<RawNode*>(rtcBuildBVH(&args));
    if (!root) {
      state.SkipWithError("rtcBuildBVH failed");
      break;
    }
  }
  if (root) {  // the last build's nodes live until the RTCBVH is released
    double sah = 0.0;
    size_t nodes = 0;
    rawStats(root, rootBounds, sah, nodes);
    state.counters["sah"] = sah;
    state.counters["nodes"] = double(nodes);
  }
  rtcReleaseBVH(bvh);
}

// ---- every registered builder ---------------------------------------------------------------------

void buildWith(benchmark::State& state, std::string builder, MeshFn mesh, uint32_t threads) {
  const PrimitiveSet* set = &mesh();
  if (set->size() == 0) return state.SkipWithError("mesh missing: run `bash datasets/fetch.sh`");
  BuildOptions options;
  options.maxLeafSize = kLeafSize;
  options.threads = threads;
  const BuildInput input = set->inputWithTriangles();  // builders that clip (sbvh) get the triangles
  validateBuildInput(input, options);  // once, outside the timed loop (buildBvh does it per call)
  const BuilderInfo& info = findBuilder(builder);
  Bvh bvh;
  for (auto _ : state) {
    bvh = info.build(input, options);
    benchmark::DoNotOptimize(bvh.nodes.data());
  }
  const BuildStats stats = computeStats(bvh, options.cost);
  state.counters["sah"] = stats.sahCost;
  state.counters["nodes"] = double(stats.nodes);
}

// Console output as usual (aggregates only), plus a table per mesh at the end, from the medians.
class RatioReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    ConsoleReporter::ReportRuns(runs);
    for (const Run& run : runs) {
      if (run.error_occurred || run.run_type != Run::RT_Aggregate) continue;
      // Names are "builder/mesh/threads:N" (run_name.str(): without the aggregate's suffix).
      const std::string name = run.run_name.str();
      const size_t a = name.find('/'), b = name.find("/threads:");
      if (a == std::string::npos || b == std::string::npos) continue;
      Result& r = results_[{name.substr(a + 1, b - a - 1), name.substr(0, a)}];
      const int threads = std::atoi(name.c_str() + b + 9) == 1 ? 0 : 1;
      const double t = run.GetAdjustedRealTime();
      if (run.aggregate_name == "median") {
        r.time[threads] = t;
        const auto sah = run.counters.find("sah");
        if (sah != run.counters.end()) r.sah = sah->second;
      } else if (run.aggregate_name == "min") {
        r.low[threads] = t;
      } else if (run.aggregate_name == "max") {
        r.high[threads] = t;
      }
    }
  }
  void Finalize() override {
    ConsoleReporter::Finalize();
    std::string mesh;
    for (const auto& [key, r] : results_) {
      if (key.first != mesh) {
        mesh = key.first;
        std::printf("\n%s: median of the repetitions [min, max], ms; ratios against embree-raw with 2 threads\n", mesh.c_str());
        std::printf("%-14s %26s %26s %9s %9s %9s %9s\n", "builder", "1 thread", "2 threads", "x t(1)", "x t(2)", "SAH",
                    "x SAH");
      }
      const Result* ref = find(mesh, "embree-raw");
      auto cell = [](const Result& x, int k) {
        char buf[64];
        if (x.time[k] > 0)
          std::snprintf(buf, sizeof buf, "%8.2f [%7.2f,%7.2f]", x.time[k], x.low[k], x.high[k]);
        else
          std::snprintf(buf, sizeof buf, "%s", "-");
        return std::string(buf);
      };
      auto ratio = [&](double x) { return ref && ref->time[1] > 0 && x > 0 ? x / ref->time[1] : NAN; };
      std::printf("%-14s %26s %26s %9.3f %9.3f %9.3f %9.4f\n", key.second.c_str(), cell(r, 0).c_str(), cell(r, 1).c_str(),
                  ratio(r.time[0]), ratio(r.time[1]), r.sah, ref && ref->sah > 0 ? r.sah / ref->sah : NAN);
    }
    std::printf("\nTarget (issue 15): sah-binned with 1 thread <= 0.5x embree-raw (MEDIUM) with 2 threads, SAH <= 1.01x\n");
    for (const auto& [key, r] : results_) {
      if (key.second != "sah-binned") continue;
      const Result* ref = find(key.first, "embree-raw");
      if (!ref || ref->time[1] <= 0 || r.time[0] <= 0) continue;
      std::printf("  %-10s sah-binned(1 thread) / embree-raw(2 threads) = %.3f   SAH ratio = %.4f\n", key.first.c_str(),
                  r.time[0] / ref->time[1], ref->sah > 0 ? r.sah / ref->sah : NAN);
    }
  }

 private:
  struct Result {
    double time[2] = {0, 0}, low[2] = {0, 0}, high[2] = {0, 0};  // [1 thread, 2 threads], ms
    double sah = 0;
  };
  const Result* find(const std::string& mesh, const std::string& builder) const {
    const auto it = results_.find({mesh, builder});
    return it == results_.end() ? nullptr : &it->second;
  }
  std::map<std::pair<std::string, std::string>, Result> results_;  // (mesh, builder)
};

}  // namespace

int main(int argc, char** argv) {
  // Our own flag, and random interleaving by default (a shared machine drifts; interleaved
  // repetitions see the same drift).
  int reps = 5;
  bool interleaving = false;
  std::vector<char*> args;
  for (int i = 0; i < argc; ++i) {
    if (std::strncmp(argv[i], "--reps=", 7) == 0) {
      reps = std::max(1, std::atoi(argv[i] + 7));
      continue;
    }
    if (std::strncmp(argv[i], "--benchmark_enable_random_interleaving", 38) == 0) interleaving = true;
    args.push_back(argv[i]);
  }
  std::string interleave = "--benchmark_enable_random_interleaving=true";
  if (!interleaving) args.push_back(interleave.data());
  int count = int(args.size());

  auto minimum = [](const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); };
  auto maximum = [](const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); };
  auto configure = [&](benchmark::internal::Benchmark* b) {
    b->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(0.2)->Repetitions(reps)->ReportAggregatesOnly(true);
    b->ComputeStatistics("min", minimum)->ComputeStatistics("max", maximum);
  };
  const std::vector<std::pair<std::string, MeshFn>> meshes = {{"bunny", bunny}, {"large1M", largeMesh}, {"sphere1M", sphereMesh}};
  for (const auto& [meshName, set] : meshes) {
    for (unsigned threads : {1u, 2u}) {
      const std::string suffix = "/" + meshName + "/threads:" + std::to_string(threads);
      if (threads == 2) configure(benchmark::RegisterBenchmark(("embree-raw" + suffix).c_str(), embreeRaw, set, threads));
      for (const BuilderInfo& info : builders())
        configure(benchmark::RegisterBenchmark((info.name + suffix).c_str(), buildWith, info.name, set, threads));
    }
  }
  benchmark::Initialize(&count, args.data());
  if (benchmark::ReportUnrecognizedArguments(count, args.data())) return 1;
  RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
}
