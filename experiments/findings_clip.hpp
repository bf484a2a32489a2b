// Clip comparisons for findings (experiments/findings.hpp): two update strategies' clips (`trace
// --update`, render/trace_clip.hpp) compared on total clip time, paired over frames.
//
// A clip row carries clip.frame_total_ms: per traced frame, the sum of the medians of its update,
// upload and trace times. Two clips of one session traced the same frames in lockstep (frame f of
// every clip before frame f + 1 of any), so frame f of one pairs with frame f of the other. The ratio
// a/b is the ratio of the clip totals, sum_f a_f / sum_f b_f; its 95% interval is a paired percentile
// bootstrap over frames (frames drawn with replacement, the same draw for both clips, the ratio of the
// resampled sums; kClipRatioResamples draws from a seed fixed by the two keys). It treats the traced
// frames as a sample of the clip's frames, so it spans both the timing noise and how unevenly the
// ratio falls over the clip.
//
// The noise band: the A/A control of a group of clips (render/trace_group.cpp): its first clip
// stepped a second time, interleaved with the others, as if it were another strategy
// (aa_clip_control.frame_total_ms on that clip's row). The control's ratio, computed as any clip
// comparison's, reaches max(|ln low|, |ln high|) from 1: that is the band of the session's clip
// comparisons (findings.cpp tests them against it as it tests runs against the A/A band).
#pragma once
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "render/frame_stats.hpp"

namespace bvhlab::findings_detail {

constexpr int kClipRatioResamples = 2000;

// clip.frame_total_ms of a clip row (empty when the row is not a clip or lacks it).
std::vector<double> clipFrameTotals(const nlohmann::json& row);
// clip.frame_update_ms and clip.frame_ray_cost: per traced frame, the update's median and the ray cost.
std::vector<double> clipFrameUpdates(const nlohmann::json& row);
std::vector<double> clipFrameRayCosts(const nlohmann::json& row);
// aa_clip_control.frame_total_ms of a clip row (empty without a control).
std::vector<double> clipControlTotals(const nlohmann::json& row);

struct ClipRatio {
  Interval ratio;                  // estimate = total a / total b; low/high the bootstrap's 2.5% / 97.5%
  std::vector<double> logRatios;   // every resample's ln(total a / total b), sorted
  BandTest test(double band) const;  // H0: the ratio inside [e^-band, e^band], from the resamples
};
// nullopt when the clips have different frame counts, fewer than kMinValuesForInterval frames, or a
// non-finite or non-positive frame total.
std::optional<ClipRatio> clipRatio(const std::vector<double>& a, const std::vector<double>& b, uint64_t seed);

// The noise entries of the clip controls among `rows` (findings.json "noise", control "clip").
std::vector<nlohmann::json> clipNoiseEntries(const std::string& scene, const std::vector<const nlohmann::json*>& rows,
                                             const std::vector<std::string>& contextAxes);

// Whether a mixed strategy (refit+rebuild:K, refit+rebuild:sah>R, refit+rotate) beats both pure refit and
// pure rebuild on the scene's clips: per context (the runs equal in every axis but `update`) that has
// both pure runs, each mixed run's clip ratio to each (clipRatio), with the session's clip band
// (`bands`, by session; none: band null). An entry {scene, strategies: [{update, key, context,
// vs_refit, vs_rebuild, beats_both, beats_both_beyond_band}], beats_both, beats_both_beyond_band},
// where beats_both = both intervals lie below 1 and beats_both_beyond_band = both lie below e^-band;
// an empty object when the scene has no such context. Each vs_* also compares two parts of the clips,
// each a clipRatio of its per-frame values: `update` (the clip's update time: what the mixed strategy
// saves) and `ray_cost` (its mean ray cost: what it pays), {ratio, ci_low, ci_high}, null without them.
nlohmann::json clipMixed(const std::string& scene, const std::vector<const nlohmann::json*>& rows,
                         const std::map<std::string, double>& bands);
// Over the scenes' clipMixed entries: the scenes where some mixed strategy beats both, with and
// beyond the band, and whether that holds on at least two animations.
nlohmann::json clipMixedSummary(const nlohmann::json& entries);

}  // namespace bvhlab::findings_detail
