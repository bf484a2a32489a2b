#include "experiments/findings.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "experiments/config.hpp"
#include "experiments/replicates.hpp"
#include "render/frame_stats.hpp"

namespace bvhlab {

using nlohmann::json;

const std::vector<std::string>& findingDesignAxes() {
  static const std::vector<std::string> axes = {"builder", "layout", "triangle_format", "kernel", "leaf_size"};
  return axes;
}

const std::vector<std::string>& findingKnobAxes() {
  static const std::vector<std::string> axes = {"depth",     "storage", "aa",   "robust",
                                                "branching", "view",    "uber", "smaa_edges", "texture_lod"};
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
// (each layout at its fastest kernel), never with the kernel held equal (no two layouts share one).
const std::map<std::string, std::string> kNestedAxis = {{"layout", "kernel"}};
// Misranked pairs listed per context (the largest ratios first): enough to see a pattern.
constexpr size_t kMaxMisrankedPerContext = 10;

std::vector<std::string> comparedAxes() {
  std::vector<std::string> out;
  for (const AxisInfo& a : experimentAxes())
    if (a.singular != "scene") out.emplace_back(a.singular);
  return out;
}

std::string label(const json& row, const std::string& axis) {
  auto it = row.find(axis);
  if (it == row.end() || it->is_null()) return "";
  if (it->is_string()) return it->get<std::string>();
  if (it->is_boolean()) return it->get<bool>() ? "true" : "false";
  if (it->is_number_integer()) return std::to_string(it->get<int64_t>());
  return it->dump();
}

std::optional<double> number(const json& row, const std::string& key) {
  auto it = row.find(key);
  if (it == row.end() || !it->is_number()) return std::nullopt;
  const double v = it->get<double>();
  if (!std::isfinite(v)) return std::nullopt;
  return v;
}

std::vector<double> frames(const json& row) {
  std::vector<double> out;
  if (auto it = row.find("frame_ms_all"); it != row.end() && it->is_array())
    for (const json& v : *it)
      if (v.is_number()) out.push_back(v.get<double>());
  return out;
}

// A traced run's rounds as multiples of Embree's time in the same round (frame_ms_all[i] /
// embree_ms_all[i]): Embree ran interleaved in the same process, so this cancels what the machine did
// to the whole process (load, clock). Empty when the run has no such pairs.
std::vector<double> embreeNormalised(const json& row) {
  const std::vector<double> glsl = frames(row);
  std::vector<double> embree, out;
  if (auto it = row.find("embree_ms_all"); it != row.end() && it->is_array())
    for (const json& v : *it)
      if (v.is_number()) embree.push_back(v.get<double>());
  if (embree.size() != glsl.size()) return {};
  for (size_t i = 0; i < glsl.size(); ++i) {
    if (!(embree[i] > 0.0)) return {};  // NaN or 0: no honest ratio
    out.push_back(glsl[i] / embree[i]);
  }
  return out;
}

std::string session(const json& row) {
  auto it = row.find("session");
  return it != row.end() && it->is_string() ? it->get<std::string>() : "";
}

// "stack-ordered leaf_size=4": the values of `axes` that vary in the scene, for people.
std::string describe(const json& row, const std::vector<std::string>& axes) {
  std::string out;
  for (const std::string& a : axes) {
    const std::string v = label(row, a);
    if (v.empty()) continue;
    if (!out.empty()) out += ' ';
    out += (a == "builder" || a == "kernel") ? v : a + "=" + v;
  }
  return out;
}

std::optional<double> correlationOf(const std::vector<const json*>& rows, const char* metric) {
  std::vector<double> x, y;
  for (const json* r : rows) {
    const auto m = number(*r, metric);
    const auto t = number(*r, "frame_ms");
    if (!m || !t) return std::nullopt;  // a run without the measure: no honest correlation
    x.push_back(*m);
    y.push_back(*t);
  }
  return spearman(x, y);
}

// A run's frames per program copy (`frame_ms_copies`, copy 0 first); empty without copies or when a
// list is malformed or of another length than the rest.
std::vector<std::vector<double>> programCopies(const json& row) {
  std::vector<std::vector<double>> out;
  auto it = row.find("frame_ms_copies");
  if (it == row.end() || !it->is_array() || it->size() < 2) return {};
  for (const json& list : *it) {
    if (!list.is_array()) return {};
    std::vector<double>& ms = out.emplace_back();
    for (const json& v : list) {
      if (!v.is_number()) return {};
      ms.push_back(v.get<double>());
    }
    if (ms.size() != out.front().size()) return {};
  }
  return out;
}

// a/b across program copies: per copy, the paired ratio of the two runs' frames drawn with that copy
// (one code placement, shared by both runs when they share a program); the median of those ratios
// with its order-statistic interval over the copies. nullopt unless both runs have the same number of
// copies, at least kMinValuesForInterval, with paired frames each.
std::optional<Interval> ratioAcrossCopies(const json& a, const json& b) {
  const auto ca = programCopies(a), cb = programCopies(b);
  if (ca.size() < kMinValuesForInterval || ca.size() != cb.size()) return std::nullopt;
  std::vector<double> perCopy;
  for (size_t j = 0; j < ca.size(); ++j) {
    if (ca[j].size() != cb[j].size()) return std::nullopt;
    const auto r = pairedRatio(ca[j], cb[j]);
    if (!r) return std::nullopt;
    perCopy.push_back(r->estimate);
  }
  return medianInterval(perCopy);
}

// A run's A/A control (`prefix` "aa_control": a second program; "aa_shared_control": the same
// program, its own buffers; render/measure_command.cpp): recomputed from the two frame lists (so
// findings always use the current interval method), else the ratio `measure` stored.
std::optional<Interval> controlRatio(const json& row, const std::string& prefix = "aa_control") {
  const std::vector<double> control = [&] {
    std::vector<double> out;
    if (auto it = row.find(prefix + "_frame_ms_all"); it != row.end() && it->is_array())
      for (const json& v : *it)
        if (v.is_number()) out.push_back(v.get<double>());
    return out;
  }();
  // The control repeats the run's own program copy: with program copies, copy 0's frames.
  const std::vector<std::vector<double>> copies = programCopies(row);
  const std::vector<double> original = copies.empty() ? frames(row) : copies.front();
  if (!control.empty() && control.size() == original.size()) return pairedRatio(original, control);
  const auto ratio = number(row, prefix + "_ratio"), lo = number(row, prefix + "_ci_low"),
             hi = number(row, prefix + "_ci_high");
  if (!ratio || !lo || !hi) return std::nullopt;
  return Interval{*ratio, *lo, *hi, kConfidence, original.size()};
}

// A run's measurements: each replicate's row (results.json `replicate_rows`), or the row itself.
std::vector<const json*> replicatesOf(const json& row) {
  std::vector<const json*> out;
  if (auto it = row.find("replicate_rows"); it != row.end() && it->is_array())
    for (const json& r : *it) out.push_back(&r);
  if (out.empty()) out.push_back(&row);
  return out;
}

class Finder {
 public:
  Finder(const json& rows, const json& axisOrder) : axisOrder_(axisOrder) {
    for (const json& r : rows)
      if (r.value("status", "") == "ok" && !r.value("reference_only", false) && number(r, "frame_ms"))
        ok_.push_back(&r);
    // The noise bands of each session: how far its A/A controls' intervals reach from 1.
    for (const json* row : ok_)
      for (const json* r : replicatesOf(*row))
        for (auto [prefix, bands] : {std::pair{"aa_control", &band_}, std::pair{"aa_shared_control", &sharedBand_}})
          if (const auto aa = controlRatio(*r, prefix); aa && aa->low > 0.0)
            (*bands)[session(*r)] = std::max(std::abs(std::log(aa->low)), std::abs(std::log(aa->high)));
  }

  json run() {
    out_ = {{"format", 1},
            {"comparisons", json::array()},
            {"noise", json::array()},
            {"predictors", json::array()},
            {"misranked", json::array()},
            {"skipped", json::array()}};
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
    return out_;
  }

 private:
  // The axes that take more than one value among `rows`.
  std::vector<std::string> varying(const std::vector<const json*>& rows, const std::set<std::string>& skip = {}) {
    std::vector<std::string> out;
    for (const std::string& a : comparedAxes()) {
      if (skip.count(a)) continue;
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

  // The noise band of a comparison: from the shared-program control when both runs drew with one
  // program and their session has one, else from the second-program control (which also holds what
  // two programs' code placement does to a ratio).
  double bandOf(const json& a, const json& b) {
    if (sharedProgram(a, b))
      if (auto it = sharedBand_.find(session(a)); it != sharedBand_.end()) return it->second;
    double band = 0.0;
    for (const json* r : {&a, &b})
      if (auto it = band_.find(session(*r)); it != band_.end()) band = std::max(band, it->second);
    return band;
  }

  bool sameComputation(const json& a, const json& b) {
    const std::string ha = label(a, "tree_hash"), hb = label(b, "tree_hash");
    if (ha.empty() || ha != hb) return false;
    for (const std::string& axis : comparedAxes())
      if (!kTreeAxes.count(axis) && label(a, axis) != label(b, axis)) return false;
    return true;
  }

  // a/b as measured: its interval, what the interval is over, and the A/A band that applies.
  struct Measured {
    std::optional<Interval> ratio;
    double band = 0.0;
    bool paired = false, sharedProgram = false, viaEmbree = false;
    std::string over;
    size_t n = 0;                         // frames behind the ratio when it has no interval
    std::vector<double> replicateRatios;  // pooled over replicates: each replicate's estimate
  };

  // Within one replicate (one row each): paired rounds in one session, program copies, or a bootstrap.
  Measured measuredOnce(const json& a, const json& b) {
    Measured m;
    const std::vector<double> fa = frames(a), fb = frames(b);
    m.paired = !session(a).empty() && session(a) == session(b) && fa.size() == fb.size() && !fa.empty();
    // Traced runs in two processes: compared through their in-process Embree rounds (drift cancels).
    const std::vector<double> na = m.paired ? std::vector<double>() : embreeNormalised(a),
                              nb = m.paired ? std::vector<double>() : embreeNormalised(b);
    m.viaEmbree = !na.empty() && !nb.empty();
    // With 6 or more program copies the interval spans code placements, which is what the A/A
    // bands stand in for otherwise: no band on top.
    const std::optional<Interval> acrossCopies = m.paired ? ratioAcrossCopies(a, b) : std::nullopt;
    if (acrossCopies)
      m.ratio = acrossCopies;
    else if (m.paired)
      m.ratio = pairedRatio(fa, fb);
    else
      m.ratio = unpairedRatio(m.viaEmbree ? na : fa, m.viaEmbree ? nb : fb,
                              std::hash<std::string>{}(label(a, "key") + "/" + label(b, "key")));
    m.band = acrossCopies ? 0.0 : bandOf(a, b);
    m.over = acrossCopies ? "program copies" : m.paired ? "rounds" : "bootstrap";
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
        each.push_back({m.ratio, m.band});
        if (m.ratio) pooled.replicateRatios.push_back(m.ratio->estimate);
        pooled.paired = pooled.paired && m.paired;
        pooled.sharedProgram = pooled.sharedProgram && m.sharedProgram;
        pooled.viaEmbree = pooled.viaEmbree || m.viaEmbree;
        pooled.n = std::max(pooled.n, m.n);
      }
    const std::optional<PooledRatio> p = poolReplicateRatios(each);
    if (!p) return measuredOnce(a, b);
    pooled.ratio = p->ratio;
    pooled.band = p->band;
    pooled.over = p->over;
    return pooled;
  }

  json compare(const json& a, const json& b, const std::string& scene, const std::string& kind,
               const std::string& axis, const std::string& context) {
    json c = {{"scene", scene},
              {"kind", kind},
              {"axis", axis.empty() ? json() : json(axis)},
              {"a", a["key"]},
              {"b", b["key"]},
              {"a_label", axis.empty() ? json() : json(label(a, axis))},
              {"b_label", axis.empty() ? json() : json(label(b, axis))},
              {"a_description", describe(a, contextAxes_)},
              {"b_description", describe(b, contextAxes_)},
              {"context", context},
              {"metric", "frame_ms"}};
    const Measured m = measured(a, b);
    c["paired"] = m.paired;
    c["interval_over"] = m.over;
    c["shared_program"] = m.sharedProgram;
    c["normalised_by"] = m.viaEmbree ? json("embree") : json();
    c["band"] = m.band;
    c["n"] = m.ratio ? m.ratio->n : m.n;
    c["ratio"] = m.ratio ? m.ratio->estimate : *number(a, "frame_ms") / *number(b, "frame_ms");
    c["ci_low"] = m.ratio ? json(m.ratio->low) : json();
    c["ci_high"] = m.ratio ? json(m.ratio->high) : json();
    if (!m.replicateRatios.empty()) c["replicate_ratios"] = m.replicateRatios;
    const std::optional<Interval>& ratio = m.ratio;
    const double band = m.band;
    std::string verdict = "no detectable difference";
    if (sameComputation(a, b))
      verdict = "same tree";
    else if (ratio && ratio->high < std::exp(-band))
      verdict = "faster";
    else if (ratio && ratio->low > std::exp(band))
      verdict = "slower";
    c["verdict"] = verdict;
    json counts = json::object();
    for (const char* k : kCounts) {
      const auto x = number(a, k), y = number(b, k);
      counts[k] = json::array({x ? json(*x) : json(), y ? json(*y) : json()});
    }
    c["counts"] = counts;
    return c;
  }

  void sceneFindings(const std::string& scene, const std::vector<const json*>& rows) {
    contextAxes_ = varying(rows);
    // Noise floor: every run that carries an A/A control.
    for (const json* row : rows)
      for (const json* r : replicatesOf(*row))
        for (const char* control : {"aa_control", "aa_shared_control"})
          if (const auto aa = controlRatio(*r, control)) {
            json entry = {{"scene", scene},
                          {"key", (*row)["key"]},
                          {"session", session(*r)},
                          {"control", std::string(control) == "aa_control" ? "program" : "shared"},
                          {"description", describe(*row, contextAxes_)},
                          {"ratio", aa->estimate},
                          {"ci_low", aa->low},
                          {"ci_high", aa->high},
                          {"n", aa->n}};
            if (r != row) entry["replicate"] = (*r).value("replicate", 0);
            out_["noise"].push_back(std::move(entry));
          }

    const bool deep = std::any_of(rows.begin(), rows.end(), [](const json* r) {
      return number(*r, "effective_depth").value_or(2.0) > 1.0;  // unknown: assume it matters
    });
    for (const std::string& axis : contextAxes_) {
      const bool design = std::find(findingDesignAxes().begin(), findingDesignAxes().end(), axis) != findingDesignAxes().end();
      const bool knob = std::find(findingKnobAxes().begin(), findingKnobAxes().end(), axis) != findingKnobAxes().end();
      if (!design && !knob) continue;
      if (axis == "depth" && !deep) {
        out_["skipped"].push_back("depth comparisons on " + scene +
                                  " skipped: its effective depth is 1 at every depth (nothing to reflect or refract)");
        continue;
      }
      const auto nested = kNestedAxis.find(axis);
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
          // One run per value of `axis`: its fastest over the nested axis.
          auto same = std::find_if(members.begin(), members.end(),
                                   [&](const json* m) { return label(*m, axis) == label(*r, axis); });
          if (same != members.end()) {
            if (*number(*r, "frame_ms") < *number(**same, "frame_ms")) *same = r;
            continue;
          }
        }
        members.push_back(r);
      }
      for (const std::string& ctx : order) {
        const std::vector<const json*>& members = contexts[ctx];
        if (members.size() < 2) continue;
        const json* base = nullptr;
        if (design) {
          base = *std::min_element(members.begin(), members.end(), [](const json* x, const json* y) {
            return *number(*x, "frame_ms") < *number(*y, "frame_ms");
          });
        } else {
          const json values = axisOrder_.value(axis, json::array());
          const std::string first = values.empty() ? std::string() : values[0].is_string() ? values[0].get<std::string>() : values[0].dump();
          for (const json* r : members)
            if (label(*r, axis) == first) base = r;
          if (!base) continue;  // the baseline value is not in this context
        }
        for (const json* r : members)
          if (r != base) out_["comparisons"].push_back(compare(*r, *base, scene, "axis", axis, ctx));
      }
    }

    // Each builder at its best (over kernels and leaf sizes) against the fastest run, with every knob
    // (depth, aa, robust, ...) held fixed: a builder is not "best" because it ran at depth 1.
    std::vector<std::string> knobs;
    for (const std::string& a : contextAxes_)
      if (std::find(findingDesignAxes().begin(), findingDesignAxes().end(), a) == findingDesignAxes().end())
        knobs.push_back(a);
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
      if (builders.size() < 2) continue;
      const json* top = nullptr;
      for (const auto& [b, r] : builders)
        if (!top || *number(*r, "frame_ms") < *number(*top, "frame_ms")) top = r;
      const std::string context = ctx.empty() ? "each at its best" : "each at its best, " + ctx;
      for (const auto& [b, r] : builders)
        if (r != top) out_["comparisons"].push_back(compare(*r, *top, scene, "builder-best", "builder", context));
    }

    predictors(scene, rows);
  }

  // Within each context of fixed kernel and knobs (the trees vary): how well each clock-free measure
  // ranks the runs by time, and the pairs SAH ranks wrongly.
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

      std::vector<json> wrong;
      for (const json* x : members)
        for (const json* y : members) {
          const auto sx = number(*x, "sah_cost"), sy = number(*y, "sah_cost");
          // Strictly cheaper by SAH, beyond float noise in the cost itself (1e-6 relative: the
          // cost is summed in double from float areas).
          if (!sx || !sy || !(*sx < *sy * (1.0 - 1e-6))) continue;
          json c = compare(*x, *y, scene, "misranked", "", ctx);
          if (c["verdict"] != "slower") continue;
          wrong.push_back({{"scene", scene},
                           {"context", ctx},
                           {"a", c["a"]},
                           {"b", c["b"]},
                           {"a_label", c["a_description"]},
                           {"b_label", c["b_description"]},
                           {"sah", json::array({*sx, *sy})},
                           {"ratio", c["ratio"]},
                           {"ci_low", c["ci_low"]},
                           {"ci_high", c["ci_high"]}});
        }
      std::sort(wrong.begin(), wrong.end(),
                [](const json& p, const json& q) { return p["ratio"].get<double>() > q["ratio"].get<double>(); });
      if (wrong.size() > kMaxMisrankedPerContext) wrong.resize(kMaxMisrankedPerContext);
      for (json& w : wrong) out_["misranked"].push_back(std::move(w));
    }
  }

  const json& axisOrder_;
  std::vector<const json*> ok_;
  std::map<std::string, double> band_, sharedBand_;  // per session: second-program / shared-program control
  std::vector<std::string> contextAxes_;
  json out_;
};

}  // namespace

json computeFindings(const json& rows, const json& axisOrder) { return Finder(rows, axisOrder).run(); }

}  // namespace bvhlab
