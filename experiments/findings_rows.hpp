// Reading results.json rows for the findings (experiments/findings.hpp): axis labels, frame lists,
// program copies, A/A controls and replicates, each read defensively (a missing or malformed field
// reads as absent, never as a number).
#pragma once
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "render/frame_stats.hpp"

namespace bvhlab::findings_detail {

// The axes findings compare along: every experiment axis but the scene, in experimentAxes() order.
const std::vector<std::string>& comparedAxes();
// A row's value on `axis` as a label ("" when absent): the string a config names it by.
std::string label(const nlohmann::json& row, const std::string& axis);
// {axis: label} for every compared axis the row has a value for.
nlohmann::json axisValues(const nlohmann::json& row);
std::optional<double> number(const nlohmann::json& row, const std::string& key);
std::vector<double> numbers(const nlohmann::json& row, const std::string& key);  // numeric entries of a list
std::vector<double> frames(const nlohmann::json& row);                            // frame_ms_all
// A traced run's rounds as multiples of Embree's time in the same round; empty without such pairs.
std::vector<double> embreeNormalised(const nlohmann::json& row);
std::string session(const nlohmann::json& row);
// "stack-ordered leaf_size=4": the values of `axes`, for people.
std::string describe(const nlohmann::json& row, const std::vector<std::string>& axes);
// A run's frames per program copy (copy 0 first); empty without copies or when malformed.
std::vector<std::vector<double>> programCopies(const nlohmann::json& row);
// A run's measurements: each replicate's row (`replicate_rows`), or the row itself.
std::vector<const nlohmann::json*> replicatesOf(const nlohmann::json& row);
// FNV-1a 64 of a string: the seed of a comparison's bootstrap (the same on every standard library).
uint64_t seedOf(const std::string& text);
// Paired rounds a/b: the median of the per-round log ratios with the hull of two 95% intervals, the
// moving-block bootstrap's (holds under autocorrelated rounds) and the order-statistic one (exact
// under independent rounds; with few rounds the bootstrap's normal interval can be the narrower):
// whichever is more cautious. The interval keeps the bootstrap's logSe, block and lag1.
struct PairedMeasure {
  Interval ratio;
  std::vector<double> logRatios;
};
std::optional<PairedMeasure> pairedMeasure(std::span<const double> a, std::span<const double> b, uint64_t seed);
// The test that matches that hull: per side the larger p of the normal (bootstrap) and the sign test,
// so p < 0.05 exactly when both intervals, hence the hull, lie outside the band.
BandTest pairedBandTest(const PairedMeasure& m, double band);
// A run's A/A control (`prefix` "aa_control" or "aa_shared_control"): pairedMeasure of the run's frames
// (copy 0's with program copies) and the control's, else the ratio `measure` stored (its i.i.d.
// interval; logSe 0, block 0). nullopt without one.
std::optional<Interval> controlRatio(const nlohmann::json& row, const std::string& prefix);

// Spearman's rank correlation of a measure with frame_ms over the rows; nullopt when a row lacks either.
std::optional<double> correlationOf(const std::vector<const nlohmann::json*>& rows, const char* metric);
// The band of an A/A interval: how far it reaches from 1, on the log scale.
double extentOf(const Interval& aa);
// a/b across program copies: per copy, the paired ratio of the two runs' frames drawn with that copy;
// the median of those ratios with its order-statistic interval over the copies, and their logs (for
// the sign test, the interval's dual). nullopt unless both runs have the same number of copies, at
// least kMinValuesForInterval, with paired frames each.
struct AcrossCopies {
  Interval ratio;
  std::vector<double> logRatios;
};
std::optional<AcrossCopies> ratioAcrossCopies(const nlohmann::json& a, const nlohmann::json& b);

}  // namespace bvhlab::findings_detail
