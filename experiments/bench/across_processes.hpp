// bench_builders --processes=K: the same benchmarks run in K processes one after another, and every
// paired ratio combined across them.
//
// Why: a paired interval from one process describes that process only. Build times also depend on
// the process (its heap, which transparent huge pages it was granted, where its arrays landed), and
// that effect is shared by all rounds of a process, so its intervals miss it. Measured: bunny,
// ploc[top-down=4,radius=4] / sah-binned, one thread, five processes of the same command: 0.990
// [0.932, 1.032], 1.092 [1.059, 1.115], 1.012 [0.962, 1.071], 1.124 [1.026, 1.199], 0.978 [0.927,
// 1.010] (docs/builders.md) -- intervals that exclude one another.
//
// Each process writes its paired ratios (--paired-out=FILE) as tab-separated lines
//   mesh  row  versus  estimate  low  high
// and the parent takes, per comparison, the median of the processes' estimates with its
// order-statistic interval across processes (render/frame_stats.hpp medianInterval: 6 processes or
// more), so a difference counts only when it holds from process to process.
#pragma once
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "render/frame_stats.hpp"

namespace bvhlab::bench {

// One paired ratio of one process: `row`'s time over `versus`'s, both named "builder t(N)".
struct PairedLine {
  std::string mesh, row, versus;
  double estimate = 0.0, low = 0.0, high = 0.0;
};

inline std::string formatPairedLine(const PairedLine& p) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "\t%.17g\t%.17g\t%.17g", p.estimate, p.low, p.high);
  return p.mesh + "\t" + p.row + "\t" + p.versus + buf;
}

// nullopt for a line that is not six tab-separated fields with three finite positive numbers.
inline std::optional<PairedLine> parsePairedLine(const std::string& line) {
  std::vector<std::string> f;
  std::stringstream in(line);
  for (std::string field; std::getline(in, field, '\t');) f.push_back(field);
  if (f.size() != 6 || f[0].empty() || f[1].empty() || f[2].empty()) return std::nullopt;
  PairedLine p{f[0], f[1], f[2]};
  double* values[3] = {&p.estimate, &p.low, &p.high};
  for (int i = 0; i < 3; ++i) {
    char* end = nullptr;
    *values[i] = std::strtod(f[3 + i].c_str(), &end);
    if (end == f[3 + i].c_str() || *end != '\0' || !(*values[i] > 0.0) || !std::isfinite(*values[i])) return std::nullopt;
  }
  return p;
}

// One comparison over the processes that made it.
struct AcrossProcesses {
  std::string mesh, row, versus;
  std::vector<double> estimates;    // one per process, in process order
  std::optional<Interval> interval;  // median of the estimates and its interval (>= 6 processes)
  // "below 1" / "above 1" when the whole interval is on that side, "no detectable difference" when
  // it holds 1, and without an interval "< 6 processes: no interval".
  std::string verdict;
};

inline std::vector<AcrossProcesses> combineProcesses(const std::vector<std::vector<PairedLine>>& processes) {
  std::map<std::tuple<std::string, std::string, std::string>, AcrossProcesses> byKey;
  for (const std::vector<PairedLine>& lines : processes)
    for (const PairedLine& p : lines) {
      AcrossProcesses& a = byKey[{p.mesh, p.row, p.versus}];
      a.mesh = p.mesh, a.row = p.row, a.versus = p.versus;
      a.estimates.push_back(p.estimate);
    }
  std::vector<AcrossProcesses> out;
  for (auto& [key, a] : byKey) {
    a.interval = medianInterval(a.estimates);
    if (!a.interval)
      a.verdict = "< 6 processes: no interval";
    else if (a.interval->high < 1.0)
      a.verdict = "below 1";
    else if (a.interval->low > 1.0)
      a.verdict = "above 1";
    else
      a.verdict = "no detectable difference";
    out.push_back(std::move(a));
  }
  return out;
}

}  // namespace bvhlab::bench
