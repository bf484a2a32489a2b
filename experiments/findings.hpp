// The comparisons an experiment report draws, computed once from the result rows and written to
// DIR/findings.json; the HTML report only renders this file (experiments/README.md, "Reading
// intervals and verdicts").
//
// Every comparison is a ratio of two runs' frame times, a/b, with its 95% interval: from paired
// frames (render/frame_stats.hpp pairedRatio) when both runs were measured interleaved in one session
// with the same number of rounds, else from a bootstrap of the two runs' frames. The verdict:
//   "same tree"                 both runs draw the same tree (tree_hash) with the same shader: the
//                               same computation, never called faster or slower;
//   "faster" / "slower"         the interval lies wholly below 1/(1+band) / above 1+band, where band is
//                               the extent of the A/A control's interval in the runs' sessions (0
//                               without one): a difference the noise floor cannot explain;
//   "no detectable difference"  otherwise, or when there are too few frames for an interval.
// Traced runs (two `bvhlab trace` processes, each with Embree's rounds interleaved) are compared
// through their per-round ratios to Embree (normalised_by "embree"): the machine's drift between the
// processes cancels.
// Beside each ratio: the runs' clock-free counts (SAH, EPO, visits and tests per ray, ray_cost).
#pragma once
#include <nlohmann/json.hpp>

namespace bvhlab {

// The axes findings compare along. Design axes compare each run with the fastest of its context
// (the runs equal in every other axis); knob axes compare each value with the config's first value.
// A kernel walks one layout, so along `layout` the context leaves the kernel free: each layout at its
// fastest kernel against the fastest layout.
const std::vector<std::string>& findingDesignAxes();  // builder, layout, triangle_format, kernel, leaf_size
const std::vector<std::string>& findingKnobAxes();    // depth, storage, aa, robust, branching, view, uber, smaa_edges, texture_lod

// `rows`: results.json's rows; `axisOrder`: plan.json's experiment.axes (singular axis -> labels in
// config order: a knob's baseline is its first value). Returns findings.json's object (format 1):
// comparisons, noise, predictors, misranked, skipped (field list in experiments/README.md).
nlohmann::json computeFindings(const nlohmann::json& rows, const nlohmann::json& axisOrder);

}  // namespace bvhlab
