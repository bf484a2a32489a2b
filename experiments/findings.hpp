// The comparisons an experiment report draws, computed once from the result rows and written to
// DIR/findings.json (format 2; every field in docs/measurement.md, "findings.json"); the HTML report
// only renders this file.
//
// Every comparison is a ratio of two runs' frame times, a/b, with its 95% interval and a p-value:
//   - both runs in one session with paired rounds: the median of the per-round log ratios, its
//     interval the hull of a moving-block bootstrap's over the rounds (render/frame_stats.hpp; it holds
//     when consecutive rounds are correlated) and the order-statistic one; from 6 program copies,
//     across the copies instead;
//   - runs in different sessions (interleave = false, another group or shard): a block bootstrap of
//     the ratio of the two medians;
//   - runs measured in replicates: pooled over them (experiments/replicates.hpp).
// The noise band: from the sessions' A/A controls for a comparison within a session (the shared-
// program control when both runs drew with one program); across sessions, the band between
// processes (the A/A control runs measured again in other replicates); pooled over 6 or more
// replicates, the replicates' own spread (band 0). A comparison with no such band is
// "not called: no noise band".
// The test: H0 "the true ratio lies inside the band", p_value two-sided against the band
// (frame_stats.hpp BandTest: p < 0.05 exactly when the 95% interval lies outside the band), then
// adjusted over the file's tests by Benjamini-Hochberg (p_adjusted). The verdict:
//   "same tree"                   both runs draw the same tree (tree_hash) with the same shader;
//   "not called: no noise band"   no band covers the comparison;
//   "faster" / "slower"           p_adjusted <= alpha (0.05), on the side of the interval;
//   "no detectable difference"    otherwise, or when there are too few frames for an interval.
// A directional verdict therefore always has its 95% interval outside the band (p_adjusted >= p).
// Design axes compare every run with a fixed baseline (the `[findings] baseline` of the config, else
// the axis's first value in config order), never with the fastest (which is reported, `fastest`).
#pragma once
#include <nlohmann/json.hpp>

namespace bvhlab {

// The axes findings compare along. Design axes compare each run with the baseline run of its context
// (the runs equal in every other axis); knob axes compare each value with the baseline value too.
// A kernel walks one layout, so along `layout` the context leaves the kernel free: each layout at its
// first kernel in config order.
const std::vector<std::string>& findingDesignAxes();  // builder, layout, triangle_format, kernel, leaf_size
const std::vector<std::string>& findingKnobAxes();    // depth, storage, aa, robust, branching, view, uber, smaa_edges, texture_lod, update

// The level at which adjusted p-values are called.
constexpr double kFindingsAlpha = 0.05;

// `rows`: results.json's rows; `axisOrder`: plan.json's experiment.axes (singular axis -> labels in
// config order); `baselines`: plan.json's experiment.findings.baseline ({axis: label}, from the
// config's [findings] baseline; axes it does not name take their first value). Returns findings.json's
// object (format 2).
nlohmann::json computeFindings(const nlohmann::json& rows, const nlohmann::json& axisOrder,
                               const nlohmann::json& baselines = nlohmann::json::object());

}  // namespace bvhlab
