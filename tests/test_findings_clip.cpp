// Clip verdicts (experiments/findings_clip.hpp): update strategies compared on total clip time, paired
// over frames, called only beyond the clip group's A/A band; the mixed-strategy question; and the
// bootstrap's p-values agreeing with its interval.
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "experiments/findings.hpp"
#include "experiments/findings_clip.hpp"

namespace bvhlab {
namespace {

using nlohmann::json;
using namespace findings_detail;

// A clip's per-frame totals: `base` growing over the clip (as refit's trace time on a decaying tree)
// by `growth` per frame, times `factor`, each frame with i.i.d. log-normal noise of sd `noise`.
std::vector<double> clipFrames(std::mt19937_64& rng, double factor, double growth, double noise, size_t n = 15) {
  std::normal_distribution<double> z(0.0, 1.0);
  std::vector<double> v;
  for (size_t f = 0; f < n; ++f) v.push_back(factor * 40.0 * (1.0 + growth * double(f)) * std::exp(noise * z(rng)));
  return v;
}

json clipRow(const std::string& update, const std::vector<double>& frames, const std::string& session = "g0") {
  double total = 0.0;
  for (double x : frames) total += x;
  return {{"key", session + "-" + update}, {"status", "ok"},  {"scene", "explode"}, {"builder", "sah-binned"},
          {"update", update},              {"session", session}, {"frame_ms", total},
          {"clip", {{"frame_total_ms", frames}, {"total_ms", total}}}};
}

TEST(FindingsClip, TheRatioIsOfTotalsAndItsPValueAgreesWithItsInterval) {
  std::mt19937_64 rng(7);
  const std::vector<double> a = clipFrames(rng, 1.0, 0.1, 0.05), b = clipFrames(rng, 1.0, 0.0, 0.05);
  const auto r = clipRatio(a, b, 1);
  ASSERT_TRUE(r);
  double sa = 0.0, sb = 0.0;
  for (size_t f = 0; f < a.size(); ++f) sa += a[f], sb += b[f];
  EXPECT_DOUBLE_EQ(r->ratio.estimate, sa / sb);
  EXPECT_LT(r->ratio.low, r->ratio.estimate);
  EXPECT_GT(r->ratio.high, r->ratio.estimate);
  EXPECT_EQ(r->ratio.n, a.size());
  // p < 0.05 exactly when the interval lies outside the band, on either side, at bands around its ends.
  for (const double end : {std::log(r->ratio.low), -std::log(r->ratio.high), std::log(r->ratio.high)}) {
    for (const double band : {std::abs(end) * 0.999, std::abs(end) * 1.001}) {
      const bool outside = r->ratio.low > std::exp(band) || r->ratio.high < std::exp(-band);
      EXPECT_EQ(r->test(band).p() < 0.05, outside) << "band " << band << " p " << r->test(band).p();
    }
  }
  const auto flipped = clipRatio(b, a, 1);
  ASSERT_TRUE(flipped);
  for (const double band : {0.5 * std::log(r->ratio.low), std::log(r->ratio.low) * 1.001})
    EXPECT_EQ(flipped->test(band).p() < 0.05, flipped->ratio.high < std::exp(-band)) << band;
  // Refused: other lengths, too few frames, a non-positive or NaN frame.
  EXPECT_FALSE(clipRatio(a, std::vector<double>(b.begin(), b.end() - 1), 1));
  EXPECT_FALSE(clipRatio({1, 2, 3, 4, 5}, {1, 2, 3, 4, 5}, 1));
  std::vector<double> bad = b;
  bad[3] = 0.0;
  EXPECT_FALSE(clipRatio(a, bad, 1));
  bad[3] = std::nan("");
  EXPECT_FALSE(clipRatio(a, bad, 1));
}

TEST(FindingsClip, StrategiesAreCalledOnlyBeyondTheClipControlsBand) {
  std::mt19937_64 rng(11);
  // rebuild: flat; refit: grows 8% a frame; refit+rebuild:4 20% under rebuild; refit+rotate: rebuild's
  // twin (noise only). rebuild carries the group's A/A control.
  json rebuild = clipRow("rebuild", clipFrames(rng, 1.0, 0.0, 0.03));
  rebuild["aa_clip_control"] = {{"frame_total_ms", clipFrames(rng, 1.0, 0.0, 0.03)}};
  const json rows = json::array({rebuild, clipRow("refit", clipFrames(rng, 0.9, 0.08, 0.03)),
                                  clipRow("refit+rebuild:4", clipFrames(rng, 0.8, 0.0, 0.03)),
                                  clipRow("refit+rotate", clipFrames(rng, 1.0, 0.0, 0.03))});
  const json f = computeFindings(rows, json{{"update", {"rebuild", "refit", "refit+rebuild:4", "refit+rotate"}}},
                                 json{{"update", "rebuild"}});
  std::map<std::string, std::string> verdict;
  for (const json& c : f["comparisons"]) {
    if (c["axis"] != "update") continue;
    EXPECT_EQ(c["interval_over"], "clip frames");
    EXPECT_EQ(c["band_source"], "clip control");
    verdict[c["a_label"].get<std::string>()] = c["verdict"];
  }
  EXPECT_EQ(verdict["refit+rebuild:4"], "faster");
  EXPECT_EQ(verdict["refit"], "slower");
  EXPECT_EQ(verdict["refit+rotate"], "no detectable difference");
  bool clipNoise = false;
  for (const json& n : f["noise"]) clipNoise = clipNoise || n["control"] == "clip";
  EXPECT_TRUE(clipNoise);
  // The mixed question: refit+rebuild:4 beats both pure strategies; refit+rotate does not.
  ASSERT_EQ(f["clip_mixed"].size(), 1u);
  for (const json& s : f["clip_mixed"][0]["strategies"])
    EXPECT_EQ(s["beats_both"], s["update"] == "refit+rebuild:4") << s.dump();
  EXPECT_EQ(f["clip_mixed_summary"]["scenes_beats_both"], json::array({"explode"}));
  EXPECT_FALSE(f["clip_mixed_summary"]["on_two_or_more"].get<bool>());

  // Without the control no clip comparison is called.
  json noControl = rows;
  noControl[0].erase("aa_clip_control");
  const json g = computeFindings(noControl, json::object(), json{{"update", "rebuild"}});
  for (const json& c : g["comparisons"]) {
    if (c["axis"] == "update") {
      EXPECT_EQ(c["verdict"], "not called: no noise band") << c.dump();
    }
  }
}

// The mixed question also compares the clips' update time and ray cost (what a mixed strategy saves
// and pays), each a paired ratio over frames with its interval; null where the rows lack them.
TEST(FindingsClip, MixedStrategiesCompareUpdateTimeAndRayCostOverFrames) {
  std::mt19937_64 rng(5);
  auto withParts = [&](json row, double update, double rayCost, double growth) {
    row["clip"]["frame_update_ms"] = clipFrames(rng, update, 0.0, 0.05);
    row["clip"]["frame_ray_cost"] = clipFrames(rng, rayCost, growth, 0.0);
    return row;
  };
  json rebuild = withParts(clipRow("rebuild", clipFrames(rng, 1.0, 0.0, 0.03)), 1.0, 1.0, 0.0);
  rebuild["aa_clip_control"] = {{"frame_total_ms", clipFrames(rng, 1.0, 0.0, 0.03)}};
  const json rows = json::array({rebuild, withParts(clipRow("refit", clipFrames(rng, 0.9, 0.08, 0.03)), 0.1, 1.0, 0.2),
                                 withParts(clipRow("refit+rebuild:sah>1.5", clipFrames(rng, 0.8, 0.0, 0.03)), 0.3, 1.1, 0.0),
                                 clipRow("refit+rotate", clipFrames(rng, 1.0, 0.0, 0.03))});
  const json f = computeFindings(rows, json::object(), json{{"update", "rebuild"}});
  ASSERT_EQ(f["clip_mixed"].size(), 1u);
  bool seen = false;
  for (const json& s : f["clip_mixed"][0]["strategies"]) {
    if (s["update"] == "refit+rotate") {  // no parts on its row
      EXPECT_TRUE(s["vs_rebuild"]["update"].is_null());
      EXPECT_TRUE(s["vs_rebuild"]["ray_cost"].is_null());
      continue;
    }
    seen = true;
    const json& u = s["vs_rebuild"]["update"];
    const json& c = s["vs_rebuild"]["ray_cost"];
    ASSERT_TRUE(u.is_object() && c.is_object()) << s.dump();
    EXPECT_NEAR(u["ratio"].get<double>(), 0.3, 0.03);
    EXPECT_LT(u["ci_low"].get<double>(), u["ratio"].get<double>());
    EXPECT_GT(u["ci_high"].get<double>(), u["ratio"].get<double>());
    EXPECT_LT(u["ci_high"].get<double>(), 1.0);
    EXPECT_NEAR(c["ratio"].get<double>(), 1.1, 1e-9);  // noise-free ray costs: the ratio of the sums exactly
    // Against refit: 3x its update time, under its growing ray cost.
    EXPECT_GT(s["vs_refit"]["update"]["ci_low"].get<double>(), 1.0);
    EXPECT_LT(s["vs_refit"]["ray_cost"]["ratio"].get<double>(), 1.0);
  }
  EXPECT_TRUE(seen);
}

}  // namespace
}  // namespace bvhlab
