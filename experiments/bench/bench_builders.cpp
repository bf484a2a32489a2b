// Build time, SAH cost and node count of every registered builder (leaf size 4, Ct = Ci = 1) on the
// bunny (75k triangles) and a generated 1M-triangle mesh, next to Embree's rtcBuildBVH at MEDIUM
// quality called directly with minimal callbacks ("embree-raw": the reference, same process, same
// run). The end of the output is a table of ratios against embree-raw (fastest repetition of each).
//   bench_builders [--benchmark_filter=...]   (the bunny comes from `bash datasets/fetch.sh`)
//   On a shared machine: --benchmark_repetitions=5 --benchmark_enable_random_interleaving=true
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <new>
#include <string>
#include <tuple>
#include <vector>

#include <benchmark/benchmark.h>
#include <embree3/rtcore.h>

#include "builders/builder.hpp"
#include "builders/test_inputs.hpp"

namespace {

using namespace bvhlab;
using bvhlab::testing::PrimitiveSet;

constexpr uint32_t kLeafSize = 4;

const PrimitiveSet& bunny() {
  static const PrimitiveSet set = bvhlab::testing::loadTriangles(bvhlab::testing::bunnyPath());
  return set;
}
const PrimitiveSet& bigMesh() {  // 1000 x 500 quads: 1,000,000 triangles
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

void embreeRaw(benchmark::State& state, const PrimitiveSet* set) {
  if (set->size() == 0) return state.SkipWithError("mesh missing: run `bash datasets/fetch.sh`");
  static RTCDevice device = rtcNewDevice(nullptr);
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

void buildWith(benchmark::State& state, std::string builder, const PrimitiveSet* set, uint32_t threads) {
  if (set->size() == 0) return state.SkipWithError("mesh missing: run `bash datasets/fetch.sh`");
  BuildOptions options;
  options.maxLeafSize = kLeafSize;
  options.threads = threads;
  validateBuildInput(set->input(), options);  // once, outside the timed loop (buildBvh does it per call)
  const BuilderInfo& info = findBuilder(builder);
  Bvh bvh;
  for (auto _ : state) {
    bvh = info.build(set->input(), options);
    benchmark::DoNotOptimize(bvh.nodes.data());
  }
  const BuildStats stats = computeStats(bvh, options.cost);
  state.counters["sah"] = stats.sahCost;
  state.counters["nodes"] = double(stats.nodes);
}

// Console output as usual, plus a ratio table against embree-raw at the end.
class RatioReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    ConsoleReporter::ReportRuns(runs);
    for (const Run& run : runs) {
      if (run.error_occurred || run.run_type != Run::RT_Iteration) continue;
      const auto sah = run.counters.find("sah");
      const Result result{run.benchmark_name(), run.GetAdjustedRealTime(),
                          sah == run.counters.end() ? 0.0 : double(sah->second)};
      // With --benchmark_repetitions the table keeps each benchmark's fastest repetition: on a
      // shared machine the minimum is the figure least disturbed by other work.
      auto same = std::find_if(results_.begin(), results_.end(), [&](const Result& r) { return r.name == result.name; });
      if (same == results_.end())
        results_.push_back(result);
      else
        same->time = std::min(same->time, result.time);
    }
  }
  void Finalize() override {
    ConsoleReporter::Finalize();
    // Names are "builder/mesh[/...]".
    auto meshOf = [](const std::string& name) {
      const size_t a = name.find('/') + 1, b = name.find('/', a);
      return name.substr(a, b == std::string::npos ? std::string::npos : b - a);
    };
    // Mesh by mesh, the reference first, then by name (random interleaving reports in any order).
    auto isReference = [](const Result& r) { return r.name.rfind("embree-raw/", 0) == 0; };
    std::sort(results_.begin(), results_.end(), [&](const Result& a, const Result& b) {
      return std::make_tuple(meshOf(a.name), !isReference(a), a.name) < std::make_tuple(meshOf(b.name), !isReference(b), b.name);
    });
    std::map<std::string, const Result*> reference;  // mesh -> embree-raw
    for (const Result& r : results_)
      if (isReference(r)) reference[meshOf(r.name)] = &r;
    std::printf("\n%-40s %10s %10s %10s %10s\n", "vs embree-raw (MEDIUM), best run", "time ms", "x time", "SAH",
                "x SAH");
    for (const Result& r : results_) {
      const auto ref = reference.find(meshOf(r.name));
      if (ref == reference.end()) continue;
      std::printf("%-40s %10.2f %10.2f %10.3f %10.4f\n", r.name.c_str(), r.time, r.time / ref->second->time, r.sah,
                  r.sah / ref->second->sah);
    }
  }

 private:
  struct Result {
    std::string name;
    double time;  // in the benchmark's unit (ms)
    double sah;
  };
  std::vector<Result> results_;
};

}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::pair<std::string, const PrimitiveSet*>> meshes = {{"bunny", &bunny()}, {"sphere1M", &bigMesh()}};
  for (const auto& [meshName, set] : meshes) {
    benchmark::RegisterBenchmark(("embree-raw/" + meshName).c_str(), embreeRaw, set)
        ->Unit(benchmark::kMillisecond)->UseRealTime();
    for (const BuilderInfo& info : builders()) {
      benchmark::RegisterBenchmark((info.name + "/" + meshName).c_str(), buildWith, info.name, set, 0u)
          ->Unit(benchmark::kMillisecond)->UseRealTime();
      if (info.name.rfind("sah-", 0) == 0)  // the threaded builders, single-threaded too
        benchmark::RegisterBenchmark((info.name + "/" + meshName + "/threads:1").c_str(), buildWith, info.name, set, 1u)
            ->Unit(benchmark::kMillisecond)->UseRealTime();
    }
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
}
