// Per-frame update time of the update strategies (builders/update.hpp) on a deforming mesh of 100,352
// triangles: refit, refit+rotate, and rebuild with lbvh and with sah-binned, all on one thread (refit
// and rotations run on one; the builders are given one so the ratios compare the same resources).
//
// The mesh: a UV sphere (224 x 224 quads) whose radius carries a travelling wave, one period over the
// clip's --frames frames (default 24), so frame F follows frame F - 1 as smoothly as frame 1 follows
// frame 0 and the clip loops. The frames are made before timing.
//
// One benchmark, all strategies interleaved: each iteration is a round in which every strategy brings
// its tree to the round's frame (round r: frame r mod F), in an order rotated by one each round, so
// drift on a shared machine hits all alike and the r-th times of two strategies are a pair. The first
// --frames rounds are a warm-up (each strategy's tree settles into the loop, caches and heap warm) and
// are not counted; then --rounds rounds (default 72) are timed. At the end: per strategy the median
// update ms with its 95% order-statistic interval and the median SAH of its trees, and the paired
// ratios (median of per-round ratios) with two 95% intervals: the order-statistic one (independent
// rounds) and the moving-block bootstrap one (render/frame_stats.hpp pairedRatioBlock), which holds
// when neighbouring rounds are alike (they are: a frame's work depends on its phase in the clip).
// Once, after the rounds: the EPO of each strategy's last tree and how long that one EPO took on one
// thread (what ClipOptions::epo would add per frame).
//   bench_updates [--frames=F] [--rounds=N]
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "builders/epo.hpp"
#include "builders/update.hpp"
#include "render/frame_stats.hpp"

using namespace bvhlab;

namespace {

constexpr uint32_t kQuadsU = 224, kQuadsV = 224;  // 2 x 224 x 224 = 100,352 triangles
uint32_t g_frames = 24;
uint32_t g_rounds = 72;

struct Frames {
  std::vector<std::vector<glm::vec3>> v0, v1, v2;
};

const Frames& waveSphere() {
  static const Frames frames = [] {
    Frames out;
    const float pi = 3.14159265358979f;
    for (uint32_t f = 0; f < g_frames; ++f) {
      const float t = 2.0f * pi * float(f) / float(g_frames);
      auto p = [&](uint32_t i, uint32_t k) {
        const float phi = 2.0f * pi * float(i % kQuadsU) / float(kQuadsU), theta = pi * float(k) / float(kQuadsV);
        const float r = 1.0f + 0.15f * std::sin(6.0f * phi - t) * std::sin(4.0f * theta + t);
        return r * glm::vec3(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi));
      };
      std::vector<glm::vec3> a, b, c;
      for (uint32_t k = 0; k < kQuadsV; ++k)
        for (uint32_t i = 0; i < kQuadsU; ++i) {
          a.push_back(p(i, k)), b.push_back(p(i + 1, k)), c.push_back(p(i + 1, k + 1));
          a.push_back(p(i, k)), b.push_back(p(i + 1, k + 1)), c.push_back(p(i, k + 1));
        }
      out.v0.push_back(std::move(a)), out.v1.push_back(std::move(b)), out.v2.push_back(std::move(c));
    }
    return out;
  }();
  return frames;
}

struct Row {
  std::string label, spec, builder;
};
const std::vector<Row> kRows = {{"refit", "refit", "sah-binned"},
                                {"refit+rotate", "refit+rotate", "sah-binned"},
                                {"rebuild(lbvh)", "rebuild", "lbvh"},
                                {"rebuild(sah-binned)", "rebuild", "sah-binned"}};

struct Results {
  std::vector<std::vector<double>> ms, sah;  // per row, per timed round
  std::vector<double> epo, epoMs;            // per row: the last tree's EPO and the time it took (1 thread)
};
Results g_results;

void updates(benchmark::State& state) {
  const Frames& frames = waveSphere();
  std::vector<std::unique_ptr<UpdateStrategy>> strategies;
  for (const Row& row : kRows) {
    UpdateOptions options;
    options.builder = row.builder;  // frame 0 of refit and refit+rotate: sah-binned's tree
    options.build.threads = 1;
    strategies.push_back(makeUpdateStrategy(row.spec, options));
  }
  Results results;
  results.ms.resize(kRows.size()), results.sah.resize(kRows.size());
  uint64_t round = 0;
  for (auto _ : state) {
    const uint32_t f = uint32_t(round % g_frames);
    const FrameTriangles frame{frames.v0[f], frames.v1[f], frames.v2[f]};
    double total = 0.0;
    for (size_t k = 0; k < kRows.size(); ++k) {
      const size_t i = (round + k) % kRows.size();
      const auto start = std::chrono::steady_clock::now();
      strategies[i]->update(frame);
      const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
      total += ms;
      if (round >= g_frames) {
        results.ms[i].push_back(ms);
        results.sah[i].push_back(sahCost(strategies[i]->tree(), strategies[i]->options().build.cost));
      }
    }
    ++round;
    state.SetIterationTime(total / 1000.0);
  }
  for (size_t i = 0; i < kRows.size(); ++i) state.counters[kRows[i].label + "_ms"] = medianOf(results.ms[i]);
  // What an EPO per frame would add to a clip (UpdateRecord::epo is optional for that reason): once per
  // strategy, on its last tree, outside the rounds.
  const uint32_t last = uint32_t((round + g_frames - 1) % g_frames);
  for (size_t i = 0; i < kRows.size(); ++i) {
    const auto start = std::chrono::steady_clock::now();
    results.epo.push_back(endPointOverlap(strategies[i]->tree(), frames.v0[last], frames.v1[last], frames.v2[last],
                                          strategies[i]->options().build.cost, 1));
    results.epoMs.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  }
  g_results = std::move(results);
}

void printSummary() {
  const Results& r = g_results;
  if (r.ms.empty() || r.ms[0].empty()) return;
  std::printf("\nupdate time per frame, 100,352-triangle wave sphere, 1 thread, %zu timed rounds (%u frames per loop)\n",
              r.ms[0].size(), g_frames);
  std::printf("%-22s %10s %24s %12s %10s %14s\n", "strategy", "median ms", "95% interval", "median SAH", "last EPO",
              "EPO ms (once)");
  for (size_t i = 0; i < kRows.size(); ++i) {
    const std::optional<Interval> m = medianInterval(r.ms[i]);
    char interval[64] = "-";
    if (m) std::snprintf(interval, sizeof interval, "[%.3f, %.3f]", m->low, m->high);
    std::printf("%-22s %10.3f %24s %12.3f %10.3f %14.1f\n", kRows[i].label.c_str(), medianOf(r.ms[i]), interval,
                medianOf(r.sah[i]), r.epo[i], r.epoMs[i]);
  }
  const std::pair<size_t, size_t> pairs[] = {{0, 2}, {0, 3}, {1, 2}, {1, 3}, {1, 0}, {2, 3}};
  std::printf("\npaired ratio of update times (a / b, median of per-round ratios)\n");
  std::printf("%-42s %9s %26s %26s\n", "a / b", "ratio", "95% order-statistic", "95% block bootstrap");
  for (const auto& [a, b] : pairs) {
    const std::optional<Interval> os = pairedRatio(r.ms[a], r.ms[b]);
    const std::optional<Interval> bb = pairedRatioBlock(r.ms[a], r.ms[b], 20261206);
    char c1[64] = "-", c2[64] = "-";
    if (os) std::snprintf(c1, sizeof c1, "[%.4f, %.4f]", os->low, os->high);
    if (bb) std::snprintf(c2, sizeof c2, "[%.4f, %.4f] (block %zu)", bb->low, bb->high, bb->block);
    const std::string label = kRows[a].label + " / " + kRows[b].label;
    std::printf("%-42s %9.4f %26s %26s\n", label.c_str(), os ? os->estimate : 0.0, c1, c2);
  }
}

bool parseCount(const char* arg, const char* flag, uint32_t& out) {
  const size_t n = std::strlen(flag);
  if (std::strncmp(arg, flag, n) != 0) return false;
  char* end = nullptr;
  const long v = std::strtol(arg + n, &end, 10);
  if (*end != '\0' || v < 1 || v > 100000) {
    std::fprintf(stderr, "bench_updates: %s: expected a whole number in 1..100000\n", arg);
    std::exit(2);
  }
  out = uint32_t(v);
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<char*> args;
  for (int i = 0; i < argc; ++i)
    if (!(i > 0 && (parseCount(argv[i], "--frames=", g_frames) || parseCount(argv[i], "--rounds=", g_rounds))))
      args.push_back(argv[i]);
  int count = int(args.size());
  benchmark::RegisterBenchmark("updates/wave-sphere-100k/threads:1", updates)
      ->UseManualTime()
      ->Unit(benchmark::kMillisecond)
      ->Iterations(g_frames + g_rounds);
  benchmark::Initialize(&count, args.data());
  if (benchmark::ReportUnrecognizedArguments(count, args.data())) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  printSummary();
  return 0;
}
