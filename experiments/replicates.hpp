// Replicates: a sweep measured R times over ([experiment] replicates, `bvhlab run --replicates R`,
// `bvhlab merge --replicates`; docs/measurement.md, "Noise bands").
//
// One group's rounds pair its runs' frames within one process, so a paired ratio's interval says how
// sure that process is. What a process shares across all its rounds (where llvmpipe's JIT put the
// shared program, the heap and huge pages it got, the machine's state while it ran) is outside that
// interval and moves ratios by 1-5% from process to process (experiments/README.md, "One program per
// shader text"). A replicate is one more pass over every group, each group in a new child process,
// after the whole previous pass: the same runs at another time. A comparison is then made in every
// replicate (paired within it as before) and the replicates' ratios are pooled:
//   - 6 or more replicates: the median of the per-replicate ratios with its order-statistic 95%
//     interval over the replicates (interval_over "replicates"); band 0: the replicates are separate
//     processes, so their spread is a band measured across processes; the test is the sign test over
//     the replicates' log ratios (the dual of that interval);
//   - 2 to 5: the median ratio with the hull of the replicates' intervals, and the widest of their
//     bands (interval_over "replicates (hull)"): a direction needs every replicate's interval beyond
//     the noise floor, so the one-sided p-values are the largest of the replicates' (an
//     intersection-union test), and a replicate without a band leaves the pool without one.
#pragma once
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "render/frame_stats.hpp"

namespace bvhlab {

// A run record's file stem: "KEY" for replicate 0, "KEY.rR" for replicate R >= 1.
std::string replicateStem(const std::string& key, int replicate);
// The replicate a record file stem names (0 for a bare key); nullopt when the stem is not KEY[.rR].
std::optional<int> replicateOfStem(const std::string& stem);

// Pools a run's rows (results.json rows of its replicates, replicate 0 first, each ok): with two or
// more, `row` (replicate 0's) gets `replicate_rows` (every replicate's row, each with its
// `replicate`), `frame_ms_replicates` (their medians), `frame_ms` = the median of those,
// `frame_ms_ci_low/high` = the hull of their intervals and `fps` from the new median. Always sets
// `replicates` (how many rows were pooled: 1 when fewer than two, or when one has no time).
void poolReplicateRows(nlohmann::json& row, const std::vector<nlohmann::json>& replicateRows);

// One comparison a/b within one replicate: its ratio (paired, over program copies, or bootstrap)
// and the A/A band that applies to it.
struct ReplicateRatio {
  std::optional<Interval> ratio;
  double band = 0.0;
  bool hasBand = true;  // false: that replicate's runs had no A/A band (band is then meaningless)
  BandTest test = {};   // the replicate's test against its band
};
struct PooledRatio {
  Interval ratio;
  double band = 0.0;
  std::string over;  // "replicates" or "replicates (hull)"
  bool hasBand = true;
  BandTest test = {};
};
// The rule above; nullopt when fewer than two replicates have an interval.
std::optional<PooledRatio> poolReplicateRatios(const std::vector<ReplicateRatio>& replicates);

}  // namespace bvhlab
