#include "experiments/findings.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "experiments/findings_adjust.hpp"
#include "experiments/findings_clip.hpp"
#include "experiments/findings_rows.hpp"
#include "experiments/replicates.hpp"
#include "render/frame_stats.hpp"

namespace bvhlab {

using nlohmann::json;
using namespace findings_detail;

const std::vector<std::string>& findingDesignAxes() {
  static const std::vector<std::string> axes = {"builder", "layout", "triangle_format", "kernel", "leaf_size"};
  return axes;
}

const std::vector<std::string>& findingKnobAxes() {
  static const std::vector<std::string> axes = {"depth",     "storage", "aa",   "robust",
                                                "branching", "view",    "uber", "smaa_edges", "texture_lod",
                                                "update"};
  return axes;
}

namespace {

// The counts shown beside every ratio (exact, clock-free).
const char* const kCounts[] = {"sah_cost", "epo", "node_visits_per_ray", "triangle_tests_per_ray", "ray_cost"};
// The measures whose rank correlation with frame time the report shows.
const char* const kPredictors[] = {"sah_cost", "epo", "node_visits_per_ray", "ray_cost"};
// Axes that change the tree but not the shader: two runs differing only here, with equal tree
// hashes, are the same computation.
const std::set<std::string> kTreeAxes = {"builder", "leaf_size"};
// Axes nested in another: a kernel walks one layout, so layouts are compared with the kernel left free
// (each layout at one of its kernels), never with the kernel held equal (no two layouts share one).
const std::map<std::string, std::string> kNestedAxis = {{"layout", "kernel"}};
// Misranked pairs listed per context (the largest ratios first): enough to see a pattern.
constexpr size_t kMaxMisrankedPerContext = 10;
constexpr const char* kAdjustmentMethod = "benjamini-hochberg";

bool contains(const std::vector<std::string>& list, const std::string& x) {
  return std::find(list.begin(), list.end(), x) != list.end();
}

// A comparison waiting for its verdict: the verdicts of tested comparisons are set once every test of
// the family is known (the adjustment needs them all).
struct Pending {
  json c;
  bool tested = false;  // has an interval and a band: its p-value enters the family
  BandTest test;
};

class Finder {
 public:
  Finder(const json& rows, const json& axisOrder, const json& baselines)
      : axisOrder_(axisOrder), baselines_(baselines.is_object() ? baselines : json::object()) {
    for (const json& r : rows)
      if (r.value("status", "") == "ok" && !r.value("reference_only", false) && number(r, "frame_ms"))
        ok_.push_back(&r);
    // The noise bands of each session: how far its A/A controls' intervals reach from 1.
    for (const json* row : ok_)
      for (const json* r : replicatesOf(*row))
        for (auto [prefix, bands] : {std::pair{"aa_control", &band_}, std::pair{"aa_shared_control", &sharedBand_}})
          if (const auto aa = control(*r, prefix); aa && aa->low > 0.0)
            (*bands)[session(*r)] = std::max((*bands)[session(*r)], extentOf(*aa));
    // Clip groups' A/A controls (experiments/findings_clip.hpp): the band of the session's clip comparisons.
    for (const json* row : ok_)
      if (const auto aa = clipRatio(clipFrameTotals(*row), clipControlTotals(*row), seedOf(label(*row, "key") + "/clip-aa")))
        clipBand_[session(*row)] = std::max(clipBand_[session(*row)], extentOf(aa->ratio));
    // The band between processes: each A/A control run measured again in another replicate (a new
    // process, minutes later) against its replicate 0: an A/A comparison across processes, made the
    // way runs from different sessions are compared (a block bootstrap of the two medians).
    for (const json* row : ok_) {
      const std::vector<const json*> reps = replicatesOf(*row);
      if (reps.size() < 2 || !(reps[0]->contains("aa_control_ratio") || reps[0]->contains("aa_control_frame_ms_all")))
        continue;
      for (size_t r = 1; r < reps.size(); ++r)
        for (int embree = 0; embree < 2; ++embree) {
          const std::vector<double> x = embree ? embreeNormalised(*reps[r]) : frames(*reps[r]),
                                    y = embree ? embreeNormalised(*reps[0]) : frames(*reps[0]);
          const auto aa = unpairedRatioBlock(x, y, seedOf(label(*row, "key") + "/between/" + std::to_string(r)));
          if (aa && aa->low > 0.0)
            betweenBand_[embree] = std::max(betweenBand_[embree].value_or(0.0), extentOf(*aa));
        }
    }
  }

  json run() {
    out_ = {{"format", 2},
            {"comparisons", json::array()},
            {"noise", json::array()},
            {"predictors", json::array()},
            {"misranked", json::array()},
            {"skipped", json::array()},
            {"baselines", json::object()}};
    std::vector<std::string> scenes;
    for (const json* r : ok_)
      if (std::find(scenes.begin(), scenes.end(), label(*r, "scene")) == scenes.end())
        scenes.push_back(label(*r, "scene"));
    for (const std::string& scene : scenes) {
      std::vector<const json*> rows;
      for (const json* r : ok_)
        if (label(*r, "scene") == scene) rows.push_back(r);
      sceneFindings(scene, rows);
    }
    // The family: every comparison that has an interval and a band (same-tree pairs are never
    // directional and are checked on their own, below).
    std::vector<Pending*> family, sameTree;
    std::set<std::string> samePairs;  // a pair met along an axis and again as builder-best counts once
    for (Pending& p : pending_) {
      if (p.c["verdict"] != "same tree") family.push_back(&p);
      else if (samePairs.insert(p.c["a"].dump() + "/" + p.c["b"].dump()).second) sameTree.push_back(&p);
    }
    const size_t directional = decide(family, true);
    const size_t tests = size_t(std::count_if(family.begin(), family.end(), [](Pending* p) { return p->tested; }));
    out_["adjustment"] = {{"method", kAdjustmentMethod},
                          {"alpha", kFindingsAlpha},
                          {"tests", tests},
                          {"directional", directional},
                          // BH bounds the expected share of chance verdicts among the directional ones by
                          // alpha; without an adjustment, alpha of all tests would be called by chance.
                          {"expected_by_chance", kFindingsAlpha * double(directional)},
                          {"expected_by_chance_unadjusted", kFindingsAlpha * double(tests)}};
    // Pairs of identical computations (same tree, same shader): what the test would have called had
    // the tree hash not decided. A measured false-positive rate of the verdict rule on this sweep.
    for (Pending* p : sameTree) p->c["verdict"] = "pending";
    const size_t wouldCall = decide(sameTree, false);
    size_t sameTested = 0;
    std::map<std::string, json> sameAdjusted;
    for (Pending* p : sameTree) {
      sameTested += p->tested;
      p->c["verdict"] = "same tree";
      sameAdjusted[p->c["a"].dump() + "/" + p->c["b"].dump()] = p->c["p_adjusted"];
    }
    for (Pending& p : pending_)  // the second listing of a pair: the first's adjusted p
      if (p.c["verdict"] == "same tree") p.c["p_adjusted"] = sameAdjusted[p.c["a"].dump() + "/" + p.c["b"].dump()];
    out_["same_tree_check"] = {{"pairs", sameTree.size()},
                               {"tested", sameTested},
                               {"directional", wouldCall},
                               {"share", sameTested ? json(double(wouldCall) / double(sameTested)) : json()}};
    for (Pending& p : pending_) out_["comparisons"].push_back(std::move(p.c));
    if (out_.contains("clip_mixed")) out_["clip_mixed_summary"] = clipMixedSummary(out_["clip_mixed"]);
    return out_;
  }

 private:
  std::optional<Interval> control(const json& row, const std::string& prefix) {
    const auto key = std::make_pair(&row, prefix);
    auto it = controls_.find(key);
    if (it == controls_.end()) it = controls_.emplace(key, controlRatio(row, prefix)).first;
    return it->second;
  }

  // The axes that take more than one value among `rows`.
  std::vector<std::string> varying(const std::vector<const json*>& rows) {
    std::vector<std::string> out;
    for (const std::string& a : comparedAxes()) {
      std::set<std::string> values;
      for (const json* r : rows) values.insert(label(*r, a));
      if (values.size() > 1) out.push_back(a);
    }
    return out;
  }

  // Both runs drew with one compiled program (one session, the same `program`).
  static bool sharedProgram(const json& a, const json& b) {
    const auto pa = number(a, "program"), pb = number(b, "program");
    return pa && pb && *pa == *pb && !session(a).empty() && session(a) == session(b);
  }

  bool sameComputation(const json& a, const json& b) {
    const std::string ha = label(a, "tree_hash"), hb = label(b, "tree_hash");
    if (ha.empty() || ha != hb) return false;
    for (const std::string& axis : comparedAxes())
      if (!kTreeAxes.count(axis) && label(a, axis) != label(b, axis)) return false;
    return true;
  }

  // a/b as measured: its interval, the band that applies (if any) and the test against it.
  struct Measured {
    std::optional<Interval> ratio;
    double band = 0.0;
    bool hasBand = false;
    std::string bandSource;
    BandTest test;
    bool paired = false, sharedProgram = false, viaEmbree = false;
    std::string over;
    size_t n = 0;                         // frames behind the ratio when it has no interval
    std::vector<double> replicateRatios;  // pooled over replicates: each replicate's estimate
  };

  // The band of a comparison within one session: from the shared-program control when both runs
  // drew with one program and the session has one, else from the second-program control (which also
  // holds what two programs' code placement does to a ratio); none when the session has neither.
  void bandWithin(const json& a, const json& b, Measured& m) {
    if (sharedProgram(a, b))
      if (auto it = sharedBand_.find(session(a)); it != sharedBand_.end()) {
        m.band = it->second, m.hasBand = true, m.bandSource = "shared control";
        return;
      }
    if (auto it = band_.find(session(a)); it != band_.end())
      m.band = it->second, m.hasBand = true, m.bandSource = "program control";
  }

  // Two clips of one session: total clip time, paired over frames (experiments/findings_clip.hpp).
  std::optional<Measured> clipMeasured(const json& a, const json& b) {
    const std::vector<double> fa = clipFrameTotals(a), fb = clipFrameTotals(b);
    if (fa.empty() || fb.empty() || session(a).empty() || session(a) != session(b)) return std::nullopt;
    Measured m;
    m.paired = true;
    m.over = "clip frames";
    m.n = std::min(fa.size(), fb.size());
    const auto r = clipRatio(fa, fb, seedOf(label(a, "key") + "/" + label(b, "key") + "/clip"));
    if (r) m.ratio = r->ratio;
    if (auto it = clipBand_.find(session(a)); it != clipBand_.end())
      m.band = it->second, m.hasBand = true, m.bandSource = "clip control";
    if (r && m.hasBand) m.test = r->test(m.band);
    return m;
  }

  // Within one replicate (one row each): paired rounds in one session, program copies, or two sessions.
  Measured measuredOnce(const json& a, const json& b) {
    if (std::optional<Measured> clip = clipMeasured(a, b)) return *clip;
    Measured m;
    const std::vector<double> fa = frames(a), fb = frames(b);
    m.paired = !session(a).empty() && session(a) == session(b) && fa.size() == fb.size() && !fa.empty();
    // Traced runs in two processes: compared through their in-process Embree rounds (drift cancels).
    const std::vector<double> na = m.paired ? std::vector<double>() : embreeNormalised(a),
                              nb = m.paired ? std::vector<double>() : embreeNormalised(b);
    m.viaEmbree = !na.empty() && !nb.empty();
    const uint64_t seed = seedOf(label(a, "key") + "/" + label(b, "key") + "/" + label(a, "replicate"));
    const std::optional<AcrossCopies> copies = m.paired ? ratioAcrossCopies(a, b) : std::nullopt;
    const std::optional<PairedMeasure> rounds = m.paired && !copies ? pairedMeasure(fa, fb, seed) : std::nullopt;
    if (copies)
      m.ratio = copies->ratio;
    else if (m.paired)
      m.ratio = rounds ? std::optional<Interval>(rounds->ratio) : std::nullopt;
    else
      m.ratio = unpairedRatioBlock(m.viaEmbree ? na : fa, m.viaEmbree ? nb : fb, seed);
    if (m.paired) {
      bandWithin(a, b, m);
    } else if (const std::optional<double>& between = betweenBand_[m.viaEmbree ? 1 : 0]) {
      m.band = *between, m.hasBand = true, m.bandSource = "between processes";
    }
    if (m.ratio && m.hasBand)
      m.test = copies ? signBandTest(copies->logRatios, m.band)
               : rounds ? pairedBandTest(*rounds, m.band)
                        : normalBandTest(std::log(m.ratio->estimate), m.ratio->logSe, m.band);
    m.over = copies ? "program copies" : m.paired ? "rounds" : "bootstrap";
    m.sharedProgram = sharedProgram(a, b);
    m.n = std::min(fa.size(), fb.size());
    return m;
  }

  // Both runs measured in two or more common replicates: the comparison in each, pooled
  // (experiments/replicates.hpp); else replicate 0's alone.
  Measured measured(const json& a, const json& b) {
    const auto ra = a.find("replicate_rows"), rb = b.find("replicate_rows");
    if (ra == a.end() || rb == b.end() || !ra->is_array() || !rb->is_array()) return measuredOnce(a, b);
    std::vector<ReplicateRatio> each;
    Measured pooled;
    pooled.paired = pooled.sharedProgram = true;
    for (const json& x : *ra)
      for (const json& y : *rb) {
        if (x.value("replicate", -1) != y.value("replicate", -2)) continue;
        const Measured m = measuredOnce(x, y);
        each.push_back({m.ratio, m.band, m.hasBand, m.test});
        if (m.ratio) pooled.replicateRatios.push_back(m.ratio->estimate);
        if (pooled.bandSource.empty() || !m.hasBand) pooled.bandSource = m.bandSource;
        pooled.paired = pooled.paired && m.paired;
        pooled.sharedProgram = pooled.sharedProgram && m.sharedProgram;
        pooled.viaEmbree = pooled.viaEmbree || m.viaEmbree;
        pooled.n = std::max(pooled.n, m.n);
      }
    const std::optional<PooledRatio> p = poolReplicateRatios(each);
    if (!p) return measuredOnce(a, b);
    pooled.ratio = p->ratio;
    pooled.band = p->band;
    pooled.hasBand = p->hasBand;
    pooled.test = p->test;
    pooled.over = p->over;
    if (p->over == "replicates") pooled.bandSource = "replicates";
    return pooled;
  }

  Pending compare(const json& a, const json& b, const std::string& scene, const std::string& kind,
                  const std::string& axis, const std::string& context, bool baseline) {
    json c = {{"scene", scene},
              {"kind", kind},
              {"axis", axis.empty() ? json() : json(axis)},
              {"a", a["key"]},
              {"b", b["key"]},
              {"a_label", axis.empty() ? json() : json(label(a, axis))},
              {"b_label", axis.empty() ? json() : json(label(b, axis))},
              {"a_values", axisValues(a)},
              {"b_values", axisValues(b)},
              {"baseline", baseline},
              {"a_description", describe(a, contextAxes_)},
              {"b_description", describe(b, contextAxes_)},
              {"context", context},
              {"metric", "frame_ms"}};
    const Measured m = measured(a, b);
    c["paired"] = m.paired;
    c["interval_over"] = m.over;
    c["shared_program"] = m.sharedProgram;
    c["normalised_by"] = m.viaEmbree ? json("embree") : json();
    c["band"] = m.hasBand ? json(m.band) : json();
    c["band_source"] = m.hasBand ? json(m.bandSource) : json();
    c["n"] = m.ratio ? m.ratio->n : m.n;
    c["ratio"] = m.ratio ? m.ratio->estimate : *number(a, "frame_ms") / *number(b, "frame_ms");
    c["ci_low"] = m.ratio ? json(m.ratio->low) : json();
    c["ci_high"] = m.ratio ? json(m.ratio->high) : json();
    c["block"] = m.ratio && m.ratio->block ? json(m.ratio->block) : json();
    if (!m.replicateRatios.empty()) c["replicate_ratios"] = m.replicateRatios;
    Pending p;
    p.tested = m.ratio && m.hasBand;
    p.test = m.test;
    c["p_value"] = p.tested ? json(m.test.p()) : json();
    c["p_adjusted"] = json();
    if (sameComputation(a, b))
      c["verdict"] = "same tree";
    else if (!m.ratio)
      c["verdict"] = "no detectable difference";  // too few frames for an interval
    else if (!m.hasBand)
      c["verdict"] = "not called: no noise band";
    else
      c["verdict"] = "pending";
    json counts = json::object();
    for (const char* k : kCounts) {
      const auto x = number(a, k), y = number(b, k);
      counts[k] = json::array({x ? json(*x) : json(), y ? json(*y) : json()});
    }
    c["counts"] = counts;
    p.c = std::move(c);
    return p;
  }

  // Adjusts the family's p-values (Benjamini-Hochberg) and sets the pending verdicts: a direction
  // where the adjusted p is at most alpha, on the side the test rejected; returns how many.
  static size_t decide(const std::vector<Pending*>& family, bool setVerdicts) {
    std::vector<double> p;
    std::vector<Pending*> tested;
    for (Pending* x : family)
      if (x->tested) {
        p.push_back(x->test.p());
        tested.push_back(x);
      }
    const std::vector<double> adjusted = adjustBenjaminiHochberg(p);
    size_t directional = 0;
    for (size_t i = 0; i < tested.size(); ++i) {
      Pending& x = *tested[i];
      x.c["p_adjusted"] = adjusted[i];
      if (x.c["verdict"] != "pending") continue;
      const bool called = adjusted[i] <= kFindingsAlpha;
      directional += called;
      if (setVerdicts)
        x.c["verdict"] = !called ? "no detectable difference" : x.test.slowerSide() ? "slower" : "faster";
    }
    return directional;
  }

  // The baseline of an axis: the config's [findings] baseline, else its first value in config order
  // (plan.json), else (no plan) the first value among the rows.
  std::string baselineOf(const std::string& axis, const std::vector<const json*>& rows) {
    if (auto it = baselines_.find(axis); it != baselines_.end() && it->is_string()) return it->get<std::string>();
    const json values = axisOrder_.is_object() ? axisOrder_.value(axis, json::array()) : json::array();
    if (values.is_array() && !values.empty())
      return values[0].is_string() ? values[0].get<std::string>() : values[0].dump();
    for (const json* r : rows)
      if (std::string v = label(*r, axis); !v.empty()) return v;
    return "";
  }

  static bool isNestedInner(const std::string& axis) {
    return std::any_of(kNestedAxis.begin(), kNestedAxis.end(), [&](const auto& n) { return n.second == axis; });
  }

  // Config order of a value on an axis (the baseline first; unknown values after the known ones).
  size_t orderOf(const std::string& axis, const std::string& value, const std::string& baseline) {
    if (value == baseline) return 0;
    const json values = axisOrder_.is_object() ? axisOrder_.value(axis, json::array()) : json::array();
    for (size_t i = 0; values.is_array() && i < values.size(); ++i)
      if ((values[i].is_string() ? values[i].get<std::string>() : values[i].dump()) == value) return i + 1;
    return std::numeric_limits<size_t>::max();
  }

  void noiseEntries(const std::string& scene, const std::vector<const json*>& rows) {
    for (const json* row : rows)
      for (const json* r : replicatesOf(*row))
        for (const char* prefix : {"aa_control", "aa_shared_control"})
          if (const auto aa = control(*r, prefix)) {
            const bool fromFrames = aa->block > 0;  // recomputed from the frame lists (else measure's ratio)
            json entry = {{"scene", scene},
                          {"key", (*row)["key"]},
                          {"session", session(*r)},
                          {"control", std::string(prefix) == "aa_control" ? "program" : "shared"},
                          {"description", describe(*row, contextAxes_)},
                          {"ratio", aa->estimate},
                          {"ci_low", aa->low},
                          {"ci_high", aa->high},
                          {"n", aa->n},
                          // Of the per-round log ratios control vs run: how much a round says about the next.
                          {"lag1_autocorrelation", fromFrames ? json(aa->lag1) : json()},
                          {"block", fromFrames ? json(aa->block) : json()}};
            if (r != row) entry["replicate"] = (*r).value("replicate", 0);
            out_["noise"].push_back(std::move(entry));
          }
  }

  void sceneFindings(const std::string& scene, const std::vector<const json*>& rows) {
    contextAxes_ = varying(rows);
    noiseEntries(scene, rows);
    for (json& entry : clipNoiseEntries(scene, rows, contextAxes_)) out_["noise"].push_back(std::move(entry));
    if (json mixed = clipMixed(scene, rows, clipBand_); !mixed.empty()) out_["clip_mixed"].push_back(std::move(mixed));
    const bool deep = std::any_of(rows.begin(), rows.end(), [](const json* r) {
      return number(*r, "effective_depth").value_or(2.0) > 1.0;  // unknown: assume it matters
    });
    for (const std::string& axis : contextAxes_) {
      const bool design = contains(findingDesignAxes(), axis), knob = contains(findingKnobAxes(), axis);
      if (!design && !knob) continue;
      if (axis == "depth" && !deep) {
        out_["skipped"].push_back("depth comparisons on " + scene +
                                  " skipped: its effective depth is 1 at every depth (nothing to reflect or refract)");
        continue;
      }
      const std::string baseline = baselineOf(axis, rows);
      out_["baselines"][axis] = baseline;
      const auto nested = kNestedAxis.find(axis);
      const std::string nestedBaseline = nested == kNestedAxis.end() ? "" : baselineOf(nested->second, rows);
      std::vector<std::string> others;
      for (const std::string& a : contextAxes_)
        if (a != axis && (nested == kNestedAxis.end() || a != nested->second)) others.push_back(a);
      std::map<std::string, std::vector<const json*>> contexts;
      std::vector<std::string> order;
      for (const json* r : rows) {
        const std::string ctx = describe(*r, others);
        if (!contexts.count(ctx)) order.push_back(ctx);
        std::vector<const json*>& members = contexts[ctx];
        if (nested != kNestedAxis.end()) {
          // One run per value of `axis`: the one at the nested axis's first value in config order (its
          // baseline when that walks this layout): a fixed choice, not the fastest.
          const std::string& n = nested->second;
          auto same = std::find_if(members.begin(), members.end(),
                                   [&](const json* m) { return label(*m, axis) == label(*r, axis); });
          if (same != members.end()) {
            if (orderOf(n, label(*r, n), nestedBaseline) < orderOf(n, label(**same, n), nestedBaseline)) *same = r;
            continue;
          }
        }
        members.push_back(r);
      }
      for (const std::string& ctx : order) {
        const std::vector<const json*>& members = contexts[ctx];
        if (members.size() < 2) continue;
        const json* base = nullptr;
        for (const json* r : members)
          if (label(*r, axis) == baseline) base = r;
        if (!base && isNestedInner(axis)) {
          // A kernel walks one layout: in a layout the baseline kernel does not walk, that layout's kernels
          // are compared with its first kernel in config order (a fixed choice, not the fastest).
          base = *std::min_element(members.begin(), members.end(), [&](const json* x, const json* y) {
            return orderOf(axis, label(*x, axis), baseline) < orderOf(axis, label(*y, axis), baseline);
          });
        }
        if (!base) {
          out_["skipped"].push_back(axis + " comparisons on " + scene + (ctx.empty() ? "" : " (" + ctx + ")") +
                                    " skipped: the baseline " + axis + " " + baseline + " was not measured there");
          continue;
        }
        // Reported, never the reference: the run with the fastest point estimate.
        const json* fastest = *std::min_element(members.begin(), members.end(), [](const json* x, const json* y) {
          return *number(*x, "frame_ms") < *number(*y, "frame_ms");
        });
        for (const json* r : members)
          if (r != base) {
            Pending p = compare(*r, *base, scene, "axis", axis, ctx, true);
            p.c["fastest"] = {{"key", (*fastest)["key"]}, {"label", label(*fastest, axis)}};
            pending_.push_back(std::move(p));
          }
      }
    }
    builderBest(scene, rows);
    predictors(scene, rows);
  }

  // Each builder at its best (over kernels and leaf sizes) against the baseline builder at its best,
  // with every knob (depth, aa, robust, ...) held fixed: a builder is not "best" because it ran at
  // depth 1. Both sides are selected the same way, so the selection favours neither.
  void builderBest(const std::string& scene, const std::vector<const json*>& rows) {
    if (!contains(contextAxes_, "builder")) return;
    const std::string baseline = baselineOf("builder", rows);
    std::vector<std::string> knobs;
    for (const std::string& a : contextAxes_)
      if (!contains(findingDesignAxes(), a)) knobs.push_back(a);
    std::map<std::string, std::map<std::string, const json*>> bestOf;  // knob context -> builder -> run
    std::vector<std::string> knobOrder;
    for (const json* r : rows) {
      const std::string ctx = describe(*r, knobs);
      if (!bestOf.count(ctx)) knobOrder.push_back(ctx);
      const json*& best = bestOf[ctx][label(*r, "builder")];
      if (!best || *number(*r, "frame_ms") < *number(*best, "frame_ms")) best = r;
    }
    for (const std::string& ctx : knobOrder) {
      const auto& builders = bestOf[ctx];
      const auto base = builders.find(baseline);
      if (builders.size() < 2 || base == builders.end()) continue;
      const std::string context = ctx.empty() ? "each at its best" : "each at its best, " + ctx;
      const json* fastest = nullptr;
      for (const auto& [b, r] : builders)
        if (!fastest || *number(*r, "frame_ms") < *number(*fastest, "frame_ms")) fastest = r;
      for (const auto& [b, r] : builders)
        if (r != base->second) {
          Pending p = compare(*r, *base->second, scene, "builder-best", "builder", context, true);
          p.c["fastest"] = {{"key", (*fastest)["key"]}, {"label", label(*fastest, "builder")}};
          pending_.push_back(std::move(p));
        }
    }
  }

  // Within each context of fixed kernel and knobs (the trees vary): how well each clock-free measure
  // ranks the runs by time, and the pairs SAH ranks wrongly (tested as a family of their own).
  void predictors(const std::string& scene, const std::vector<const json*>& rows) {
    std::vector<std::string> fixed;
    for (const std::string& a : contextAxes_)
      if (!kTreeAxes.count(a)) fixed.push_back(a);
    std::map<std::string, std::vector<const json*>> contexts;
    std::vector<std::string> order;
    for (const json* r : rows) {
      const std::string ctx = describe(*r, fixed);
      if (!contexts.count(ctx)) order.push_back(ctx);
      contexts[ctx].push_back(r);
    }
    for (const std::string& ctx : order) {
      const std::vector<const json*>& members = contexts[ctx];
      if (members.size() < 4) continue;  // fewer points rank nothing worth a number
      json rho = json::object();
      for (const char* m : kPredictors) {
        const auto v = correlationOf(members, m);
        rho[m] = v ? json(*v) : json();
      }
      out_["predictors"].push_back({{"scene", scene}, {"context", ctx}, {"n", members.size()}, {"spearman", rho}});

      std::vector<Pending> candidates;
      std::vector<std::pair<double, double>> sah;
      for (const json* x : members)
        for (const json* y : members) {
          const auto sx = number(*x, "sah_cost"), sy = number(*y, "sah_cost");
          // Strictly cheaper by SAH, beyond float noise in the cost itself (1e-6 relative: the
          // cost is summed in double from float areas).
          if (!sx || !sy || !(*sx < *sy * (1.0 - 1e-6))) continue;
          candidates.push_back(compare(*x, *y, scene, "misranked", "", ctx, false));
          sah.emplace_back(*sx, *sy);
        }
      std::vector<Pending*> family;
      for (Pending& p : candidates) family.push_back(&p);
      decide(family, true);
      std::vector<json> wrong;
      for (size_t i = 0; i < candidates.size(); ++i) {
        const json& c = candidates[i].c;
        if (c["verdict"] != "slower") continue;
        wrong.push_back({{"scene", scene},
                         {"context", ctx},
                         {"a", c["a"]},
                         {"b", c["b"]},
                         {"a_label", c["a_description"]},
                         {"b_label", c["b_description"]},
                         {"sah", json::array({sah[i].first, sah[i].second})},
                         {"ratio", c["ratio"]},
                         {"ci_low", c["ci_low"]},
                         {"ci_high", c["ci_high"]},
                         {"p_adjusted", c["p_adjusted"]}});
      }
      std::sort(wrong.begin(), wrong.end(),
                [](const json& p, const json& q) { return p["ratio"].get<double>() > q["ratio"].get<double>(); });
      if (wrong.size() > kMaxMisrankedPerContext) wrong.resize(kMaxMisrankedPerContext);
      for (json& w : wrong) out_["misranked"].push_back(std::move(w));
    }
  }

  const json& axisOrder_;
  const json baselines_;
  std::vector<const json*> ok_;
  std::map<std::string, double> band_, sharedBand_;  // per session: second-program / shared-program control
  std::map<std::string, double> clipBand_;            // per session: the clip group's A/A control
  std::optional<double> betweenBand_[2];             // across processes: frames, Embree-normalised frames
  std::map<std::pair<const json*, std::string>, std::optional<Interval>> controls_;
  std::vector<std::string> contextAxes_;
  std::vector<Pending> pending_;
  json out_;
};

}  // namespace

json computeFindings(const json& rows, const json& axisOrder, const json& baselines) {
  return Finder(rows, axisOrder, baselines).run();
}

}  // namespace bvhlab
