// bench_builders' reporter: Google Benchmark's console output (aggregates only), then per mesh a table
// of every builder's median times with 1 and 2 threads, SAH, ratios against embree-raw (2 threads) and
// paired ratios against sah-binned at the same thread count (render/frame_stats.hpp pairedRatio:
// repetition r of every benchmark runs in round r of the interleaving); then the target lines,
// or with --curve the bins curve. Benchmark names are "builder/mesh/threads:N"; the benchmarks report
// the counters "sah", "epo" and "ray_cost". With a paired-out file, every paired ratio it prints also
// goes there, one line each (across_processes.hpp: --processes=K combines them). Only
// bench_builders.cpp includes this.
#pragma once
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <benchmark/benchmark.h>

#include "experiments/bench/across_processes.hpp"
#include "render/frame_stats.hpp"

namespace bvhlab::bench {

// The name of the row of ploc with an SAH top (`--ploc-top-down F`), and its radius where it is not
// the builder's default.
inline std::string plocTopDownRow(uint32_t fraction, uint32_t radius) {
  const std::string r = radius == BuildOptions{}.plocRadius ? "" : ",radius=" + std::to_string(radius);
  return "ploc[top-down=" + std::to_string(fraction) + r + "]";
}

// sah-binned's bin counts on the bins curve (--curve).
constexpr uint32_t kCurveBins[] = {8, 12, 16, 24, 32, 48, 64, 128};

// Which accuracy curve bench_builders runs instead of its builder tables.
enum class Curve { None, Bins, Sbvh };

// The sbvh curve (--curve=sbvh): the overlap threshold alpha at the default reference budget, then
// the budget at the default alpha. alpha = 1 never allows a spatial split (an overlap is at most the
// node's area, at most the root's): sbvh's object splits alone, the control.
struct SbvhPoint {
  float alpha, budget;
};
constexpr SbvhPoint kSbvhCurve[] = {{1.0f, 2.0f},  {1e-2f, 2.0f},  {1e-3f, 2.0f}, {1e-4f, 2.0f}, {1e-5f, 2.0f},
                                    {1e-6f, 2.0f}, {0.0f, 2.0f},   {1e-5f, 1.1f}, {1e-5f, 1.25f}, {1e-5f, 1.5f},
                                    {1e-5f, 4.0f}};
inline std::string sbvhCurveRow(SbvhPoint p) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "sbvh[alpha=%g,budget=%g]", double(p.alpha), double(p.budget));
  return buf;
}

// Console output as usual (aggregates only), plus a table per mesh at the end, from the medians.
class RatioReporter : public benchmark::ConsoleReporter {
 public:
  RatioReporter(Curve curve, uint32_t plocTopDown, uint32_t plocRadius, std::string pairedOut = "")
      : curve_(curve), plocTopDownRow_(plocTopDownRow(plocTopDown, plocRadius)), pairedOut_(std::move(pairedOut)) {}
  // False when the paired-out file could not be written (after Finalize).
  bool pairedOutWritten() const { return pairedOutOk_; }
  void ReportRuns(const std::vector<Run>& runs) override {
    std::vector<Run> aggregates;  // the console shows these; the repetitions feed the paired ratios
    for (const Run& run : runs)
      if (run.run_type == Run::RT_Aggregate) aggregates.push_back(run);
    ConsoleReporter::ReportRuns(aggregates);
    for (const Run& run : runs) {
      if (run.error_occurred) continue;
      // Names are "builder/mesh/threads:N" (run_name.str(): without the aggregate's suffix).
      const std::string name = run.run_name.str();
      const size_t a = name.find('/'), b = name.find("/threads:");
      if (a == std::string::npos || b == std::string::npos) continue;
      Result& r = results_[{name.substr(a + 1, b - a - 1), name.substr(0, a)}];
      const int threads = std::atoi(name.c_str() + b + 9) == 1 ? 0 : 1;
      const double t = run.GetAdjustedRealTime(), cpu = run.GetAdjustedCPUTime();
      if (run.run_type == Run::RT_Iteration) {  // one repetition: its time at its round
        if (run.repetition_index < 0) continue;
        std::vector<double>& rounds = r.rounds[threads];
        if (rounds.size() <= size_t(run.repetition_index)) rounds.resize(size_t(run.repetition_index) + 1, NAN);
        rounds[size_t(run.repetition_index)] = t;
        continue;
      }
      auto counter = [&run](const char* name) {
        const auto it = run.counters.find(name);
        return it == run.counters.end() ? 0.0 : double(it->second);
      };
      if (run.aggregate_name == "median") {
        r.time[threads] = t, r.cpu[threads] = cpu;
        r.sah = counter("sah"), r.epo = counter("epo"), r.rayCost = counter("ray_cost");
        r.references = counter("references");
        r.faults[threads] = counter("faults");
      } else if (run.aggregate_name == "min") {
        r.low[threads] = t, r.cpuLow[threads] = cpu;
      } else if (run.aggregate_name == "max") {
        r.high[threads] = t, r.cpuHigh[threads] = cpu;
      }
    }
  }
  void Finalize() override {
    ConsoleReporter::Finalize();
    writePairedOut();
    if (curve_ == Curve::Bins) return printCurve();
    if (curve_ == Curve::Sbvh) return printSbvhCurve();
    std::string mesh;
    for (const auto& [key, r] : results_) {
      if (key.first != mesh) {
        mesh = key.first;
        std::printf("\n%s: median of the repetitions [min, max], ms; ratios against embree-raw with 2 threads\n", mesh.c_str());
        std::printf("%-14s %26s %26s %9s %9s %9s %9s %9s %24s %24s %17s\n", "builder", "1 thread", "2 threads", "x t(1)", "x t(2)", "SAH",
                    "x SAH", "x b. SAH", "x sah-binned t(1) [95%]", "x sah-binned t(2) [95%]", "faults/build 1t 2t");
      }
      const Result* binned = find(mesh, "sah-binned");
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
      auto versusBinned = [&](int k) { return binned && key.second != "sah-binned" ? paired(r.rounds[k], binned->rounds[k]) : "-"; };
      std::printf("%-14s %26s %26s %9.3f %9.3f %9.3f %9.4f %9.4f %24s %24s %8.0f %8.0f\n", key.second.c_str(), cell(r, 0).c_str(),
                  cell(r, 1).c_str(), ratio(r.time[0]), ratio(r.time[1]), r.sah, ref && ref->sah > 0 ? r.sah / ref->sah : NAN,
                  binned && binned->sah > 0 ? r.sah / binned->sah : NAN, versusBinned(0).c_str(), versusBinned(1).c_str(),
                  r.faults[0], r.faults[1]);
    }
    std::printf("\n(x SAH: against embree-raw's tree; x b. SAH: against sah-binned's; faults/build: minor page faults "
                "of the process per build, all threads, median over the repetitions: the heap policy's effect.)\n");
    std::printf("\nTarget: sah-binned with 1 thread <= 0.5x embree-raw (MEDIUM) with 2 threads, SAH <= 1.01x\n");
    for (const auto& [key, r] : results_) {
      if (key.second != "sah-binned") continue;
      const Result* ref = find(key.first, "embree-raw");
      if (!ref || ref->time[1] <= 0 || r.time[0] <= 0) continue;
      std::printf("  %-10s sah-binned(1 thread) / embree-raw(2 threads) = %.3f (ratio of medians); paired %s   SAH ratio = %.4f\n",
                  key.first.c_str(), r.time[0] / ref->time[1], paired(r.rounds[0], ref->rounds[1]).c_str(),
                  ref->sah > 0 ? r.sah / ref->sah : NAN);
    }
    std::printf("\nTargets: sbvh SAH <= 0.92x sah-binned's; ploc SAH <= 1.05x sah-binned's and time <= "
                "sah-binned's\n");
    const std::set<std::string> meshes = meshNames();
    for (const std::string& m : meshes) {
      const Result* binned = find(m, "sah-binned");
      if (!binned || binned->sah <= 0) continue;
      auto sahRatio = [&](const Result* x) { return x && x->sah > 0 ? x->sah / binned->sah : NAN; };
      auto verdict = [](double v, double limit) { return v != v ? "-" : v <= limit ? "met" : "not met"; };
      const Result* sbvh = find(m, "sbvh");
      const Result* ploc = find(m, "ploc");
      const Result* plocTop = find(m, plocTopDownRow_);
      if (!sbvh && !ploc && !plocTop) continue;
      std::printf("  %-10s", m.c_str());
      if (sbvh) std::printf(" sbvh SAH %.4f (%s)  ", sahRatio(sbvh), verdict(sahRatio(sbvh), 0.92));
      for (const auto& [row, name] : {std::pair{ploc, "ploc"}, std::pair{plocTop, plocTopDownRow_.c_str()}})
        if (row)
          std::printf("\n  %-10s %s SAH %.4f (%s), / sah-binned time, paired: 1 thread %s, 2 threads %s", "", name,
                      sahRatio(row), verdict(sahRatio(row), 1.05), paired(row->rounds[0], binned->rounds[0]).c_str(),
                      paired(row->rounds[1], binned->rounds[1]).c_str());
      std::printf("\n");
    }
  }

 private:
  struct Result {
    double time[2] = {0, 0}, low[2] = {0, 0}, high[2] = {0, 0};  // [1 thread, 2 threads], wall ms
    double cpu[2] = {0, 0}, cpuLow[2] = {0, 0}, cpuHigh[2] = {0, 0};  // process CPU ms (--curve)
    double sah = 0, epo = 0, rayCost = 0, references = 0;
    double faults[2] = {NAN, NAN};  // minor page faults per build, median over the repetitions
    std::vector<double> rounds[2];  // wall ms of each repetition, by round (NaN: none that round)
  };

  static std::optional<Interval> pairedInterval(const std::vector<double>& a, const std::vector<double>& b) {
    const size_t n = std::min(a.size(), b.size());
    return pairedRatio(std::span(a.data(), n), std::span(b.data(), n));
  }
  // a / b over the rounds both ran: the median per-round ratio and its 95% interval, or why not.
  static std::string paired(const std::vector<double>& a, const std::vector<double>& b) {
    const std::optional<Interval> q = pairedInterval(a, b);
    if (!q) return std::min(a.size(), b.size()) ? "- (< 6 rounds)" : "-";
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.3f [%.3f, %.3f]", q->estimate, q->low, q->high);
    return buf;
  }

  // Ratios of medians, with the range [min / ref max, max / ref min] over the repetitions beside them.
  static std::string ratio(double median, double low, double high, double refMedian, double refLow, double refHigh) {
    char buf[64];
    if (median > 0 && refMedian > 0)
      std::snprintf(buf, sizeof buf, "%.3f [%.2f-%.2f]", median / refMedian, low / refHigh, high / refLow);
    else
      std::snprintf(buf, sizeof buf, "-");
    return buf;
  }
  void printCurve() const {
    std::printf("\nsah-binned bins curve (leaf 4, Ct = Ci = 1): ratios to embree-raw (MEDIUM, 2 threads) as median "
                "[min-max range over the repetitions]; wall = real time; CPU = process CPU time, against Embree's "
                "halved (its 2-thread wall time is at least that); SAH, EPO and ray cost against the registered "
                "embree builder's tree\n");
    const std::set<std::string> meshes = meshNames();
    for (const std::string& mesh : meshes) {
      const Result* ref = find(mesh, "embree-raw");
      if (!ref) continue;
      std::printf("\n%s: embree-raw wall %.2f [%.2f, %.2f] ms, CPU %.2f ms; SAH %.3f, EPO %.3f, ray cost %.2f\n", mesh.c_str(),
                  ref->time[1], ref->low[1], ref->high[1], ref->cpu[1], ref->sah, ref->epo, ref->rayCost);
      std::printf("%5s %10s %20s %20s %10s %20s %8s %8s %8s\n", "bins", "1t wall ms", "x wall (1 thread)", "x CPU/2 (1 thread)",
                  "2t wall ms", "x wall (2 threads)", "x SAH", "x EPO", "x rays");
      for (uint32_t bins : kCurveBins) {
        const Result* r = find(mesh, "sah-binned:" + std::to_string(bins));
        if (!r) continue;
        const double half = 0.5;  // Embree's CPU time over its two threads, halved
        std::printf("%5u %10.2f %20s %20s %10.2f %20s %8.4f %8.4f %8.4f\n", bins, r->time[0],
                    ratio(r->time[0], r->low[0], r->high[0], ref->time[1], ref->low[1], ref->high[1]).c_str(),
                    ratio(r->cpu[0], r->cpuLow[0], r->cpuHigh[0], half * ref->cpu[1], half * ref->cpuLow[1], half * ref->cpuHigh[1]).c_str(),
                    r->time[1], ratio(r->time[1], r->low[1], r->high[1], ref->time[1], ref->low[1], ref->high[1]).c_str(),
                    r->sah / ref->sah, r->epo / ref->epo, r->rayCost / ref->rayCost);
      }
    }
  }
  // The paired ratios of the tables and target lines above, one line each, into pairedOut_: every row
  // against sah-binned at its thread count, and sah-binned with one thread against embree-raw with two.
  void writePairedOut() {
    if (pairedOut_.empty()) return;
    std::vector<PairedLine> lines;
    auto add = [&](const std::string& mesh, const std::string& row, const std::string& versus,
                   const std::optional<Interval>& q) {
      if (q) lines.push_back({mesh, row, versus, q->estimate, q->low, q->high});
    };
    const char* threads[2] = {" t(1)", " t(2)"};
    for (const auto& [key, r] : results_) {
      const Result* binned = find(key.first, "sah-binned");
      if (binned && key.second != "sah-binned")
        for (int k = 0; k < 2; ++k)
          add(key.first, key.second + threads[k], std::string("sah-binned") + threads[k], pairedInterval(r.rounds[k], binned->rounds[k]));
      const Result* ref = find(key.first, "embree-raw");
      if (ref && key.second == "sah-binned")
        add(key.first, "sah-binned t(1)", "embree-raw t(2)", pairedInterval(r.rounds[0], ref->rounds[1]));
    }
    std::ofstream out(pairedOut_);
    for (const PairedLine& p : lines) out << formatPairedLine(p) << '\n';
    out.close();
    pairedOutOk_ = bool(out);
  }
  // The sbvh curve: per mesh, each point's one-thread time against sah-binned's and against sbvh's
  // defaults (alpha 1e-5, budget 2), paired over the rounds, beside its tree: leaf references per
  // primitive, SAH, EPO and ray cost against sah-binned's tree.
  void printSbvhCurve() const {
    std::printf("\nsbvh curve (leaf 4, Ct = Ci = 1, 32 bins, 1 thread): alpha (spatial splits where the object split's "
                "children overlap more than alpha x the root's area) and the reference budget (leaf references <= "
                "budget x primitives); times are medians [min, max] and paired ratios [95%%] over the rounds; "
                "references, SAH, EPO and ray cost against sah-binned's tree\n");
    const std::set<std::string> meshes = meshNames();
    const std::string defaults = sbvhCurveRow({BuildOptions{}.sbvhAlpha, BuildOptions{}.sbvhReferenceBudget});
    for (const std::string& mesh : meshes) {
      const Result* binned = find(mesh, "sah-binned");
      const Result* standard = find(mesh, defaults);
      if (!binned || binned->references <= 0) continue;
      std::printf("\n%s: sah-binned %.2f [%.2f, %.2f] ms, SAH %.3f, EPO %.3f, ray cost %.2f, %.0f primitives\n", mesh.c_str(),
                  binned->time[0], binned->low[0], binned->high[0], binned->sah, binned->epo, binned->rayCost,
                  binned->references);
      std::printf("%8s %6s %26s %24s %24s %8s %8s %8s %8s\n", "alpha", "budget", "1 thread ms", "x sah-binned t(1) [95%]",
                  "x sbvh default [95%]", "refs/n", "x SAH", "x EPO", "x rays");
      for (const SbvhPoint& p : kSbvhCurve) {
        const Result* r = find(mesh, sbvhCurveRow(p));
        if (!r || r->time[0] <= 0) continue;
        char cell[64];
        std::snprintf(cell, sizeof cell, "%8.2f [%7.2f,%7.2f]", r->time[0], r->low[0], r->high[0]);
        std::printf("%8g %6g %26s %24s %24s %8.4f %8.4f %8.4f %8.4f\n", double(p.alpha), double(p.budget), cell,
                    paired(r->rounds[0], binned->rounds[0]).c_str(),
                    standard && r != standard ? paired(r->rounds[0], standard->rounds[0]).c_str() : "-",
                    r->references / binned->references, r->sah / binned->sah, r->epo / binned->epo,
                    r->rayCost / binned->rayCost);
      }
    }
  }
  Curve curve_ = Curve::None;
  std::string plocTopDownRow_;
  std::string pairedOut_;
  bool pairedOutOk_ = true;
  std::set<std::string> meshNames() const {
    std::set<std::string> names;
    for (const auto& [key, r] : results_) names.insert(key.first);
    return names;
  }
  const Result* find(const std::string& mesh, const std::string& builder) const {
    const auto it = results_.find({mesh, builder});
    return it == results_.end() ? nullptr : &it->second;
  }
  std::map<std::pair<std::string, std::string>, Result> results_;  // (mesh, builder)
};


}  // namespace bvhlab::bench
