// Build time, SAH cost and node count of every registered builder (leaf size 4, Ct = Ci = 1) with 1
// and with 2 threads, on the bunny (75k triangles), the two other scans the quality targets name
// (elephant 89k, armadillo 52k), the ship (CG-57, 180k, a CAD model: long thin
// triangles), the bench suite's interior (200k: slabs and walls spanning a building;
// datasets/bench_generators.hpp), a 1M-triangle procedural scene (datasets/procedural.hpp
// makeLargeMesh) and a 1M-triangle bumpy sphere, next to Embree's
// rtcBuildBVH at MEDIUM quality called directly with minimal callbacks ("embree-raw", on an Embree
// device of 2 threads): the reference, same process, same run. Embree's thread count is per process
// (TBB): a "threads=1" device next to a 2-thread one builds with 2 threads (measured: CPU time = 2x
// wall), so there is no 1-thread embree-raw row; the registered `embree` and `embree-low` builders
// ignore BuildOptions::threads (Embree's own pool), so their two rows are the same configuration.
//
// Every benchmark runs --reps repetitions (default 7; ->Repetitions(n)), in
// random interleaving order unless --benchmark_enable_random_interleaving is given, and the
// figures are the MEDIAN over the repetitions (with min and max, ->ComputeStatistics). The end of
// the output is a table per mesh: median time with 1 and 2 threads, SAH and the ratios against
// embree-raw with 2 threads, and each builder's time against sah-binned's at the same thread count
// as a paired ratio with its 95% interval (render/frame_stats.hpp pairedRatio: repetition r of every
// benchmark runs in round r of the interleaving, so the r-th times of two builders are a pair; the
// interval needs 6 or more repetitions, hence the default of 7); then the target lines per mesh:
// sah-binned with 1 thread vs embree-raw with 2 threads (paired the same way), sbvh's SAH and ploc's
// SAH and time against sah-binned's (the SAH targets were set on scans, but their anchors come from
// architectural scenes: the ship and the interior are that class here). One more row, "ploc[top-down=F]",
// is ploc with an SAH top (BuildOptions::plocTopDown = F, 4 unless --ploc-top-down=F says otherwise; 0:
// no such row) and the search radius --ploc-radius=R (16, the builder's default, unless given), with
// its own target line; the plain ploc row keeps the default radius.
//
// --curve runs the accuracy curve of sah-binned's bin count instead (what accuracy costs in
// time): bins in kCurveBins on the bunny, the elephant, the armadillo and makeLargeMesh(1M), 1 and 2
// threads, beside embree-raw (2 threads), all repetitions interleaved. Beside wall time it records
// the process's CPU time (all threads; MeasureProcessCPUTime), which other processes on a loaded
// machine do not inflate; Embree's is halved for the comparison (its 2-thread wall time can be no
// shorter than that), so the CPU-time ratio is the conservative one. Per tree, once, outside the
// timing: SAH, EPO (builders/epo.hpp) and the ray cost (node visits + triangle tests per ray, Ct =
// Ci = 1) of closest-hit rays traversed front to back on the CPU here, against the registered
// `embree` builder's tree (MEDIUM, the same build embree-raw times).
// --curve=sbvh runs sbvh's accuracy knobs instead (experiments/bench/builders_report.hpp kSbvhCurve):
// the overlap threshold alpha from 1 (no spatial split can pass it: the control) to 0 (every node
// tries spatial splits) at the default budget, and the reference budget 1.1..4 at the default alpha,
// on the bunny, the armadillo, the ship and the interior, one thread, beside sah-binned: time paired
// against sah-binned's and against sbvh's defaults, and per tree its leaf references, SAH, EPO and
// ray cost (experiments/bench/ray_cost.hpp) against sah-binned's tree.
//
// --processes=K (K >= 2) runs the same benchmarks in K processes one after another (each with its own
// interleaving) and prints every paired ratio combined across them: the median of the processes'
// estimates with its order-statistic interval across processes (6 or more), which, unlike one
// process's interval, covers what differs from process to process (experiments/bench/across_processes.hpp).
// Each process's full output is kept in a file whose path is printed.
// --heap=warm|cold|adaptive: the heap policy (experiments/bench/heap_policy.hpp). warm, the default:
// memory a build frees is reused by the next one, as embree-raw's own allocator reuses its blocks
// (one RTCBVH for all its builds; 0 page faults per build here, as for every builder of ours warm),
// so the times are the builders' work and the ratios hold from process to process. cold: every big
// block fresh, faulted in per build (a one-off build in a new process); adaptive: glibc's default,
// whose choice between the two depends on the process's history (this program's default before
// 4 December 2026). Printed in the output's first line; each table gives the page faults per build.
//   bench_builders [--reps=N] [--curve[=bins|sbvh]] [--ploc-top-down=F] [--ploc-radius=R] [--processes=K]
//                  [--heap=P] [--paired-out=FILE] [--benchmark_filter=...]   (meshes: `bash datasets/fetch.sh`)
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <new>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <unistd.h>
#include <embree3/rtcore.h>

#include "builders/builder.hpp"
#include "builders/epo.hpp"
#include "builders/test_inputs.hpp"
#include "datasets/bench_generators.hpp"
#include "datasets/mesh_io.hpp"
#include "datasets/procedural.hpp"
#include "layout/layout.hpp"
#include "experiments/bench/builders_report.hpp"
#include "experiments/bench/embree_raw.hpp"
#include "experiments/bench/heap_policy.hpp"
#include "experiments/bench/ray_cost.hpp"
#include "experiments/process.hpp"

namespace {

using namespace bvhlab;
using bvhlab::testing::PrimitiveSet;
using bench::Ray, bench::curveRays, bench::rayCost;
using bench::RawNode, bench::rawCreateNode, bench::rawSetChildren, bench::rawSetBounds, bench::rawCreateLeaf, bench::rawStats;

constexpr uint32_t kLeafSize = 4;

// The builders get the inputs the app gives them (`bvhlab build`, `render`: layout/layout.hpp's
// triangleBoxes and triangleCentroids, the centre of each triangle's box), not the test sets' vertex
// means. Which one a builder bins matters where triangles are long: on the bench interior, whose walls
// are quads split into two right triangles, the two halves of a wall have one box but vertex means a
// third of the wall apart, and sah-binned's SAH over vertex means is 1.31x Embree's (184.1 against
// 140.3; Embree bins box centres), over box centres 0.998x; on the ship 1.066x against 0.989x.
PrimitiveSet asTheAppSeesIt(PrimitiveSet s) {
  if (!s.hasTriangles()) return s;  // a missing mesh (empty) stays empty
  TriangleSoup soup;
  soup.v0 = s.v0, soup.v1 = s.v1, soup.v2 = s.v2;
  s.centroids = triangleCentroids(soup);
  return s;
}

std::filesystem::path bunnyDir() { return bvhlab::testing::bunnyPath().parent_path(); }
const PrimitiveSet& bunny() {
  static const PrimitiveSet set = asTheAppSeesIt(bvhlab::testing::loadTriangles(bvhlab::testing::bunnyPath()));
  return set;
}
const PrimitiveSet& largeMesh() {  // makeLargeMesh: dense and sparse regions, long thin gaps, overlaps
  static const PrimitiveSet set = [] {
    PrimitiveSet s;
    s.name = "large1M";
    const Mesh mesh = makeLargeMesh(1'000'000);
    for (const glm::uvec3& t : mesh.triangles) s.addTriangle(mesh.positions[t.x], mesh.positions[t.y], mesh.positions[t.z]);
    return asTheAppSeesIt(s);
  }();
  return set;
}
const PrimitiveSet& elephantMesh() {
  static const PrimitiveSet set = asTheAppSeesIt(bvhlab::testing::loadTriangles(bunnyDir() / "refined_elephant.off"));
  return set;
}
const PrimitiveSet& armadilloMesh() {
  static const PrimitiveSet set = asTheAppSeesIt(bvhlab::testing::loadTriangles(bunnyDir() / "armadillo.off"));
  return set;
}
PrimitiveSet fromMesh(const std::string& name, const Mesh& mesh) {
  PrimitiveSet s;
  s.name = name;
  for (const glm::uvec3& t : mesh.triangles) s.addTriangle(mesh.positions[t.x], mesh.positions[t.y], mesh.positions[t.z]);
  return asTheAppSeesIt(s);
}
const PrimitiveSet& shipMesh() {  // flightgear's CG-57 (datasets/fetch.sh), through the AC3D importer
  static const PrimitiveSet set = [] {
    const std::filesystem::path path = bunnyDir() / "CG-57.ac";
    return std::filesystem::exists(path) ? fromMesh("ship", loadMesh(path)) : PrimitiveSet{};
  }();
  return set;
}
const PrimitiveSet& interiorMesh() {  // the bench suite's interior.toml mesh
  static const PrimitiveSet set = fromMesh("interior", generateBenchMesh("interior", 200000, 1));
  return set;
}
const PrimitiveSet& sphereMesh() {  // 1000 x 500 quads: 1,000,000 triangles
  static const PrimitiveSet set = asTheAppSeesIt(bvhlab::testing::sphereSoup(1000, 500, 0.2f));
  return set;
}

// ---- Embree MEDIUM, raw (the tree and its callbacks: experiments/bench/embree_raw.hpp) ---------

// The process's page faults since `before` (bench::minorPageFaults()) per iteration of `state`.
double faultsPerBuild(const benchmark::State& state, long before) {
  return double(bench::minorPageFaults() - before) / double(std::max<int64_t>(1, state.iterations()));
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
  const long faults = bench::minorPageFaults();
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
  state.counters["faults"] = faultsPerBuild(state, faults);
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

void buildWith(benchmark::State& state, std::string builder, MeshFn mesh, uint32_t threads, uint32_t plocTopDown = 0,
               uint32_t plocRadius = 0) {
  const PrimitiveSet* set = &mesh();
  if (set->size() == 0) return state.SkipWithError("mesh missing: run `bash datasets/fetch.sh`");
  BuildOptions options;
  options.maxLeafSize = kLeafSize;
  options.threads = threads;
  options.plocTopDown = plocTopDown;
  if (plocRadius) options.plocRadius = plocRadius;
  const BuildInput input = set->inputWithTriangles();  // builders that clip (sbvh) get the triangles
  validateBuildInput(input, options);  // once, outside the timed loop (buildBvh does it per call)
  const BuilderInfo& info = findBuilder(builder);
  Bvh bvh;
  const long faults = bench::minorPageFaults();
  for (auto _ : state) {
    bvh = info.build(input, options);
    benchmark::DoNotOptimize(bvh.nodes.data());
  }
  state.counters["faults"] = faultsPerBuild(state, faults);
  const BuildStats stats = computeStats(bvh, options.cost);
  state.counters["sah"] = stats.sahCost;
  state.counters["nodes"] = double(stats.nodes);
}

// ---- the accuracy curves (--curve, --curve=sbvh): tree quality beside the time --------------------

struct Quality {
  double sah = 0, epo = 0, rayCost = 0, references = 0;
};

BuildOptions curveOptions(uint32_t bins) {
  BuildOptions options;
  options.maxLeafSize = kLeafSize;
  options.bins = bins;
  return options;
}

// Once per (mesh, label): repetitions reuse it. `options` are those of the timed builds (threads do
// not change a tree); builders that clip (sbvh) get the triangles, as in the timed builds.
const Quality& treeQuality(const PrimitiveSet& set, const std::string& builder, const BuildOptions& options,
                           const std::string& label) {
  static std::map<std::pair<std::string, std::string>, Quality> cache;
  static std::map<std::string, std::vector<Ray>> rays;
  const auto key = std::make_pair(set.name, label);
  if (const auto it = cache.find(key); it != cache.end()) return it->second;
  const Bvh bvh = buildBvh(builder, set.inputWithTriangles(), options);
  std::vector<Ray>& r = rays[set.name];
  if (r.empty()) r = curveRays(set, 20000);
  Quality q;
  q.sah = sahCost(bvh, options.cost);
  q.epo = endPointOverlap(bvh, set.v0, set.v1, set.v2, options.cost);
  q.rayCost = rayCost(bvh, set, r);
  q.references = double(bvh.primIndices.size());
  return cache[key] = q;
}

void reportQuality(benchmark::State& state, const Quality& q) {
  state.counters["sah"] = q.sah;
  state.counters["epo"] = q.epo;
  state.counters["ray_cost"] = q.rayCost;
  state.counters["references"] = q.references;
}

// Times `builder` with `options` on `threads` threads; the tree's quality once, beside it.
void curveBuild(benchmark::State& state, MeshFn mesh, std::string builder, BuildOptions options, uint32_t threads,
                std::string label) {
  const PrimitiveSet* set = &mesh();
  if (set->size() == 0) return state.SkipWithError("mesh missing: run `bash datasets/fetch.sh`");
  options.threads = threads;
  const BuildInput input = set->inputWithTriangles();
  validateBuildInput(input, options);
  const BuilderInfo& info = findBuilder(builder);
  for (auto _ : state) {
    Bvh bvh = info.build(input, options);
    benchmark::DoNotOptimize(bvh.nodes.data());
  }
  reportQuality(state, treeQuality(*set, builder, options, label));
}

// embree-raw for the time, and the registered `embree` builder's tree for the quality measures.
void curveEmbree(benchmark::State& state, MeshFn mesh) {
  embreeRaw(state, mesh, 2);
  const PrimitiveSet& set = mesh();
  if (set.size() == 0) return;
  reportQuality(state, treeQuality(set, "embree", curveOptions(0), "embree"));
}

// --processes=K: this program again, K times, with `args` (our flags less --processes) and a
// --paired-out file each; then the paired ratios across the processes. Returns the exit code.
int runProcesses(int processes, const std::vector<std::string>& args) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("bench_builders_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::vector<std::vector<bench::PairedLine>> perProcess;
  for (int k = 1; k <= processes; ++k) {
    const fs::path paired = dir / ("process-" + std::to_string(k) + ".tsv");
    const fs::path output = dir / ("process-" + std::to_string(k) + ".txt");
    std::vector<std::string> argv{"/proc/self/exe"};
    argv.insert(argv.end(), args.begin(), args.end());
    argv.push_back("--paired-out=" + paired.string());
    std::fprintf(stderr, "bench_builders: process %d of %d ...\n", k, processes);
    const ProcessResult r = runProcess(argv);
    std::ofstream(output) << r.out << r.err;
    if (!r.ok()) {
      std::fprintf(stderr, "bench_builders: process %d failed (%s); its output: %s\n", k, r.status().c_str(),
                   output.string().c_str());
      return 1;
    }
    std::ifstream in(paired);
    std::vector<bench::PairedLine> lines;
    int lineNo = 0;
    for (std::string line; std::getline(in, line);) {
      ++lineNo;
      const std::optional<bench::PairedLine> p = bench::parsePairedLine(line);
      if (!p) {
        std::fprintf(stderr, "bench_builders: %s:%d: not a paired-ratio line\n", paired.string().c_str(), lineNo);
        return 1;
      }
      lines.push_back(*p);
    }
    perProcess.push_back(std::move(lines));
  }
  std::printf("Paired ratios across %d processes (each process: the median per-round ratio of its repetitions; here the "
              "median over the processes with its 95%% order-statistic interval, which needs 6 processes). Outputs: %s\n\n",
              processes, dir.string().c_str());
  std::printf("%-10s %-34s %-18s %-26s %-26s %s\n", "mesh", "row", "versus", "across processes [95%]", "verdict",
              "per process");
  for (const bench::AcrossProcesses& a : bench::combineProcesses(perProcess)) {
    char cell[64] = "-";
    if (a.interval) std::snprintf(cell, sizeof cell, "%.3f [%.3f, %.3f]", a.interval->estimate, a.interval->low, a.interval->high);
    std::string each;
    for (double e : a.estimates) {
      char buf[16];
      std::snprintf(buf, sizeof buf, "%s%.3f", each.empty() ? "" : " ", e);
      each += buf;
    }
    std::printf("%-10s %-34s %-18s %-26s %-26s %s\n", a.mesh.c_str(), a.row.c_str(), a.versus.c_str(), cell,
                a.verdict.c_str(), each.c_str());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // Our own flag, and random interleaving by default (a shared machine drifts; interleaved
  // repetitions see the same drift).
  int reps = 7;  // 6 or more for a 95% interval of a median (paired ratios)
  bool interleaving = false;
  bench::Curve curve = bench::Curve::None;
  uint32_t plocTopDown = 4;  // the extra ploc row: `--ploc-top-down 4` (0: no such row)
  uint32_t plocRadius = BuildOptions{}.plocRadius;  // and its search radius
  int processes = 1;
  bench::HeapPolicy heap = bench::HeapPolicy::Warm;
  std::string pairedOut;
  std::vector<std::string> childArgs;  // every argument but --processes (and argv[0])
  for (int i = 1; i < argc; ++i)
    if (std::strncmp(argv[i], "--processes=", 12) != 0) childArgs.push_back(argv[i]);
  std::vector<char*> args;
  for (int i = 0; i < argc; ++i) {
    if (std::strncmp(argv[i], "--processes=", 12) == 0) {
      processes = std::atoi(argv[i] + 12);
      if (processes < 1 || processes > 100) {
        std::fprintf(stderr, "bench_builders: --processes=%s: expected 1..100\n", argv[i] + 12);
        return 2;
      }
      continue;
    }
    if (std::strncmp(argv[i], "--paired-out=", 13) == 0) {
      pairedOut = argv[i] + 13;
      continue;
    }
    if (std::strncmp(argv[i], "--reps=", 7) == 0) {
      reps = std::max(1, std::atoi(argv[i] + 7));
      continue;
    }
    if (std::strncmp(argv[i], "--ploc-top-down=", 16) == 0) {
      plocTopDown = uint32_t(std::max(0, std::atoi(argv[i] + 16)));
      continue;
    }
    if (std::strncmp(argv[i], "--ploc-radius=", 14) == 0) {
      const int r = std::atoi(argv[i] + 14);
      if (r < 1 || r > int(kMaxPlocRadius)) {
        std::fprintf(stderr, "bench_builders: --ploc-radius=%s: expected 1..%u\n", argv[i] + 14, kMaxPlocRadius);
        return 2;
      }
      plocRadius = uint32_t(r);
      continue;
    }
    if (std::strncmp(argv[i], "--heap=", 7) == 0) {
      const std::optional<bench::HeapPolicy> policy = bench::parseHeapPolicy(argv[i] + 7);
      if (!policy) {
        std::fprintf(stderr, "bench_builders: --heap=%s: expected warm, cold or adaptive\n", argv[i] + 7);
        return 2;
      }
      heap = *policy;
      continue;
    }
    if (std::strcmp(argv[i], "--curve") == 0 || std::strcmp(argv[i], "--curve=bins") == 0) {
      curve = bench::Curve::Bins;
      continue;
    }
    if (std::strcmp(argv[i], "--curve=sbvh") == 0) {
      curve = bench::Curve::Sbvh;
      continue;
    }
    if (std::strncmp(argv[i], "--curve", 7) == 0) {
      std::fprintf(stderr, "bench_builders: %s: expected --curve, --curve=bins or --curve=sbvh\n", argv[i]);
      return 2;
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
    // Every repetition reaches the reporter (the paired ratios need them); it shows the aggregates only.
    b->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(0.2)->Repetitions(reps)->ReportAggregatesOnly(false);
    b->ComputeStatistics("min", minimum)->ComputeStatistics("max", maximum);
  };
  const std::vector<std::pair<std::string, MeshFn>> curveMeshes = {
      {"bunny", bunny}, {"elephant", elephantMesh}, {"armadillo", armadilloMesh}, {"large1M", largeMesh}};
  for (const auto& [meshName, set] : curve == bench::Curve::Bins ? curveMeshes : decltype(curveMeshes){}) {
    auto timeCpuToo = [&](benchmark::internal::Benchmark* b) { configure(b), b->MeasureProcessCPUTime(); };
    timeCpuToo(benchmark::RegisterBenchmark(("embree-raw/" + meshName + "/threads:2").c_str(), curveEmbree, set));
    for (uint32_t bins : bench::kCurveBins)
      for (uint32_t threads : {1u, 2u}) {
        const std::string label = "sah-binned:" + std::to_string(bins);
        timeCpuToo(benchmark::RegisterBenchmark((label + "/" + meshName + "/threads:" + std::to_string(threads)).c_str(),
                                                curveBuild, set, "sah-binned", curveOptions(bins), threads, label));
      }
  }
  // The sbvh curve: scans (bunny, armadillo) and scenes of long thin triangles (ship, interior), one
  // thread, sah-binned's tree and time as the reference.
  const std::vector<std::pair<std::string, MeshFn>> sbvhMeshes = {
      {"bunny", bunny}, {"armadillo", armadilloMesh}, {"ship", shipMesh}, {"interior", interiorMesh}};
  for (const auto& [meshName, set] : curve == bench::Curve::Sbvh ? sbvhMeshes : decltype(sbvhMeshes){}) {
    const std::string suffix = "/" + meshName + "/threads:1";
    configure(benchmark::RegisterBenchmark(("sah-binned" + suffix).c_str(), curveBuild, set, "sah-binned",
                                           curveOptions(0), 1u, "sah-binned"));
    for (const bench::SbvhPoint& p : bench::kSbvhCurve) {
      BuildOptions options = curveOptions(0);
      options.sbvhAlpha = p.alpha;
      options.sbvhReferenceBudget = p.budget;
      const std::string label = bench::sbvhCurveRow(p);
      configure(benchmark::RegisterBenchmark((label + suffix).c_str(), curveBuild, set, "sbvh", options, 1u, label));
    }
  }
  const std::vector<std::pair<std::string, MeshFn>> meshes = {
      {"bunny", bunny}, {"elephant", elephantMesh}, {"armadillo", armadilloMesh}, {"ship", shipMesh},
      {"interior", interiorMesh}, {"large1M", largeMesh}, {"sphere1M", sphereMesh}};
  for (const auto& [meshName, set] : curve != bench::Curve::None ? decltype(meshes){} : meshes) {
    for (unsigned threads : {1u, 2u}) {
      const std::string suffix = "/" + meshName + "/threads:" + std::to_string(threads);
      if (threads == 2) configure(benchmark::RegisterBenchmark(("embree-raw" + suffix).c_str(), embreeRaw, set, threads));
      for (const BuilderInfo& info : builders())
        configure(benchmark::RegisterBenchmark((info.name + suffix).c_str(), buildWith, info.name, set, threads, 0u, 0u));
      // PLOC with an SAH top: the last n/4 clusters split by binned SAH (BuildOptions::plocTopDown).
      if (plocTopDown)
        configure(benchmark::RegisterBenchmark((bench::plocTopDownRow(plocTopDown, plocRadius) + suffix).c_str(),
                                               buildWith, "ploc", set, threads, plocTopDown, plocRadius));
    }
  }
  std::printf("heap policy: %s\n", bench::heapPolicyName(heap));
  if (processes > 1) return runProcesses(processes, childArgs);
  if (!bench::applyHeapPolicy(heap)) {
    std::fprintf(stderr, "bench_builders: --heap=%s: the C library refused the policy\n", bench::heapPolicyName(heap));
    return 2;
  }
  benchmark::Initialize(&count, args.data());
  if (benchmark::ReportUnrecognizedArguments(count, args.data())) return 1;
  bench::RatioReporter reporter(curve, plocTopDown, plocRadius, pairedOut);
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
  if (!reporter.pairedOutWritten()) {
    std::fprintf(stderr, "bench_builders: could not write --paired-out=%s\n", pairedOut.c_str());
    return 1;
  }
}
