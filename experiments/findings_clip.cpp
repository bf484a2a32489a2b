// Clip comparisons for findings (experiments/findings_clip.hpp).
#include "experiments/findings_clip.hpp"

#include "experiments/findings_rows.hpp"

#include <algorithm>
#include <cmath>
#include <random>

namespace bvhlab::findings_detail {

using nlohmann::json;

namespace {

std::vector<double> listIn(const json& row, const char* object, const char* key) {
  std::vector<double> out;
  const auto o = row.find(object);
  if (o == row.end() || !o->is_object()) return out;
  const auto list = o->find(key);
  if (list == o->end() || !list->is_array()) return out;
  for (const json& x : *list) out.push_back(x.is_number() ? x.get<double>() : std::nan(""));
  return out;
}

// The 95% percentile interval's ends of sorted resamples, symmetric in rank: k = floor(0.025 (B - 1))
// values lie below the low end and k above the high end, which is what makes ClipRatio::test's
// p-values agree with the interval exactly (below).
size_t lowRank(size_t count) { return size_t(0.5 * (1.0 - kConfidence) * double(count - 1)); }

}  // namespace

std::vector<double> clipFrameTotals(const json& row) { return listIn(row, "clip", "frame_total_ms"); }
std::vector<double> clipControlTotals(const json& row) { return listIn(row, "aa_clip_control", "frame_total_ms"); }
std::vector<double> clipFrameUpdates(const json& row) { return listIn(row, "clip", "frame_update_ms"); }
std::vector<double> clipFrameRayCosts(const json& row) { return listIn(row, "clip", "frame_ray_cost"); }

std::optional<ClipRatio> clipRatio(const std::vector<double>& a, const std::vector<double>& b, uint64_t seed) {
  const size_t n = a.size();
  if (n != b.size() || n < kMinValuesForInterval) return std::nullopt;
  for (size_t f = 0; f < n; ++f)  // written so that a NaN refuses too
    if (!(std::isfinite(a[f]) && a[f] > 0.0 && std::isfinite(b[f]) && b[f] > 0.0)) return std::nullopt;
  double sa = 0.0, sb = 0.0;
  for (size_t f = 0; f < n; ++f) sa += a[f], sb += b[f];
  ClipRatio r;
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<size_t> pick(0, n - 1);
  r.logRatios.resize(kClipRatioResamples);
  for (double& x : r.logRatios) {
    double ra = 0.0, rb = 0.0;
    for (size_t k = 0; k < n; ++k) {
      const size_t f = pick(rng);  // one draw for both clips: frames stay paired
      ra += a[f], rb += b[f];
    }
    x = std::log(ra / rb);
  }
  std::sort(r.logRatios.begin(), r.logRatios.end());
  r.ratio.estimate = sa / sb;
  const size_t k = lowRank(r.logRatios.size());
  r.ratio.low = std::exp(r.logRatios[k]);
  r.ratio.high = std::exp(r.logRatios[r.logRatios.size() - 1 - k]);
  r.ratio.coverage = kConfidence;
  r.ratio.n = n;
  return r;
}

BandTest ClipRatio::test(double band) const {
  // One-sided bootstrap p-values, (count + 1) / (B + 1): the share of resamples on H0's side of the
  // band. low > band exactly when at most k resamples are <= band, i.e. pSlower <= (k + 1) / (B + 1),
  // and k = floor(0.025 (B - 1)) makes that bound the largest value below 0.025 that pSlower takes
  // (B = 2000: k = 49, 50/2001 < 0.025 < 51/2001): p() < 0.05 exactly when [low, high] lies outside
  // the band (tests/test_findings.cpp checks both sides).
  BandTest t;
  if (logRatios.empty()) return t;
  const double b = double(logRatios.size());
  const double notAbove = double(std::count_if(logRatios.begin(), logRatios.end(), [&](double x) { return x <= band; }));
  const double notBelow = double(std::count_if(logRatios.begin(), logRatios.end(), [&](double x) { return x >= -band; }));
  t.pSlower = std::min(1.0, (notAbove + 1.0) / (b + 1.0));
  t.pFaster = std::min(1.0, (notBelow + 1.0) / (b + 1.0));
  return t;
}

std::vector<json> clipNoiseEntries(const std::string& scene, const std::vector<const json*>& rows,
                                   const std::vector<std::string>& contextAxes) {
  std::vector<json> out;
  for (const json* row : rows) {
    const auto aa = clipRatio(clipFrameTotals(*row), clipControlTotals(*row), seedOf(label(*row, "key") + "/clip-aa"));
    if (!aa) continue;
    out.push_back({{"scene", scene},
                   {"key", (*row)["key"]},
                   {"session", session(*row)},
                   {"control", "clip"},
                   {"description", describe(*row, contextAxes)},
                   {"ratio", aa->ratio.estimate},
                   {"ci_low", aa->ratio.low},
                   {"ci_high", aa->ratio.high},
                   {"n", aa->ratio.n},
                   {"lag1_autocorrelation", json()},
                   {"block", json()}});
  }
  return out;
}

namespace {

bool isMixed(const std::string& update) { return update.rfind("refit+rebuild:", 0) == 0 || update == "refit+rotate"; }

// One side of a mixed strategy's comparison: its clip ratio to a pure strategy's run.
json side(const json& mixed, const json& pure, const std::map<std::string, double>& bands, bool& below,
          bool& beyond) {
  const auto r = clipRatio(clipFrameTotals(mixed), clipFrameTotals(pure),
                           seedOf(label(mixed, "key") + "/" + label(pure, "key") + "/clip"));
  const auto band = bands.find(session(mixed));
  const bool hasBand = band != bands.end() && session(mixed) == session(pure);
  below = r && r->ratio.high < 1.0;
  beyond = below && hasBand && r->ratio.high < std::exp(-band->second);
  // A part of the clips, per frame, compared as the totals are.
  const auto part = [&](std::vector<double> (*values)(const json&), const char* name) -> json {
    const auto p = clipRatio(values(mixed), values(pure),
                             seedOf(label(mixed, "key") + "/" + label(pure, "key") + "/" + name));
    if (!p) return json();
    return {{"ratio", p->ratio.estimate}, {"ci_low", p->ratio.low}, {"ci_high", p->ratio.high}};
  };
  return {{"b", pure["key"]},
          {"ratio", r ? json(r->ratio.estimate) : json()},
          {"ci_low", r ? json(r->ratio.low) : json()},
          {"ci_high", r ? json(r->ratio.high) : json()},
          {"n", r ? json(r->ratio.n) : json()},
          {"band", hasBand ? json(band->second) : json()},
          {"p_value", r && hasBand ? json(r->test(band->second).p()) : json()},
          {"update", part(clipFrameUpdates, "update")},
          {"ray_cost", part(clipFrameRayCosts, "ray_cost")}};
}

}  // namespace

json clipMixed(const std::string& scene, const std::vector<const json*>& rows, const std::map<std::string, double>& bands) {
  std::map<std::string, std::vector<const json*>> contexts;
  std::vector<std::string> order;
  for (const json* r : rows) {
    if (label(*r, "update").empty() || clipFrameTotals(*r).empty()) continue;
    json values = axisValues(*r);
    values.erase("update");
    const std::string ctx = values.dump();
    if (!contexts.count(ctx)) order.push_back(ctx);
    contexts[ctx].push_back(r);
  }
  json strategies = json::array();
  bool anyBoth = false, anyBeyond = false;
  for (const std::string& ctx : order) {
    const auto& runs = contexts[ctx];
    const auto find = [&](const std::string& update) -> const json* {
      for (const json* r : runs)
        if (label(*r, "update") == update) return r;
      return nullptr;
    };
    const json *refit = find("refit"), *rebuild = find("rebuild");
    if (!refit || !rebuild) continue;
    for (const json* r : runs) {
      if (!isMixed(label(*r, "update"))) continue;
      bool belowRefit = false, beyondRefit = false, belowRebuild = false, beyondRebuild = false;
      json e = {{"update", label(*r, "update")},
                {"key", (*r)["key"]},
                {"context", json::parse(ctx)},
                {"vs_refit", side(*r, *refit, bands, belowRefit, beyondRefit)},
                {"vs_rebuild", side(*r, *rebuild, bands, belowRebuild, beyondRebuild)}};
      e["beats_both"] = belowRefit && belowRebuild;
      e["beats_both_beyond_band"] = beyondRefit && beyondRebuild;
      anyBoth = anyBoth || (belowRefit && belowRebuild);
      anyBeyond = anyBeyond || (beyondRefit && beyondRebuild);
      strategies.push_back(std::move(e));
    }
  }
  if (strategies.empty()) return json::object();
  return {{"scene", scene}, {"strategies", strategies}, {"beats_both", anyBoth}, {"beats_both_beyond_band", anyBeyond}};
}

json clipMixedSummary(const json& entries) {
  json both = json::array(), beyond = json::array();
  for (const json& e : entries) {
    if (e.value("beats_both", false)) both.push_back(e["scene"]);
    if (e.value("beats_both_beyond_band", false)) beyond.push_back(e["scene"]);
  }
  return {{"scenes", entries.size()},
          {"scenes_beats_both", both},
          {"scenes_beats_both_beyond_band", beyond},
          {"on_two_or_more", both.size() >= 2},
          {"on_two_or_more_beyond_band", beyond.size() >= 2}};
}

}  // namespace bvhlab::findings_detail
