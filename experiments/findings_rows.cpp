#include "experiments/findings_rows.hpp"

#include <algorithm>
#include <cmath>

#include "experiments/config.hpp"

namespace bvhlab::findings_detail {

using nlohmann::json;

const std::vector<std::string>& comparedAxes() {
  static const std::vector<std::string> axes = [] {
    std::vector<std::string> out;
    for (const AxisInfo& a : experimentAxes())
      if (a.singular != "scene") out.emplace_back(a.singular);
    return out;
  }();
  return axes;
}

std::string label(const json& row, const std::string& axis) {
  auto it = row.find(axis);
  if (it == row.end() || it->is_null()) return "";
  if (it->is_string()) return it->get<std::string>();
  if (it->is_boolean()) return it->get<bool>() ? "true" : "false";
  if (it->is_number_integer()) return std::to_string(it->get<int64_t>());
  return it->dump();
}

json axisValues(const json& row) {
  json out = json::object();
  for (const std::string& a : comparedAxes())
    if (std::string v = label(row, a); !v.empty()) out[a] = std::move(v);
  return out;
}

std::optional<double> number(const json& row, const std::string& key) {
  auto it = row.find(key);
  if (it == row.end() || !it->is_number()) return std::nullopt;
  const double v = it->get<double>();
  if (!std::isfinite(v)) return std::nullopt;
  return v;
}

std::vector<double> numbers(const json& row, const std::string& key) {
  std::vector<double> out;
  if (auto it = row.find(key); it != row.end() && it->is_array())
    for (const json& v : *it)
      if (v.is_number()) out.push_back(v.get<double>());
  return out;
}

std::vector<double> frames(const json& row) { return numbers(row, "frame_ms_all"); }

// frame_ms_all[i] / embree_ms_all[i]: Embree ran interleaved in the same process, so this cancels what
// the machine did to the whole process (load, clock).
std::vector<double> embreeNormalised(const json& row) {
  const std::vector<double> glsl = frames(row), embree = numbers(row, "embree_ms_all");
  if (embree.size() != glsl.size()) return {};
  std::vector<double> out;
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

std::vector<const json*> replicatesOf(const json& row) {
  std::vector<const json*> out;
  if (auto it = row.find("replicate_rows"); it != row.end() && it->is_array())
    for (const json& r : *it) out.push_back(&r);
  if (out.empty()) out.push_back(&row);
  return out;
}

uint64_t seedOf(const std::string& text) {
  uint64_t h = 0xcbf29ce484222325ull;  // FNV-1a 64 offset basis and prime (Fowler/Noll/Vo)
  for (unsigned char c : text) {
    h ^= c;
    h *= 0x100000001b3ull;
  }
  return h;
}

std::optional<PairedMeasure> pairedMeasure(std::span<const double> a, std::span<const double> b, uint64_t seed) {
  const auto block = pairedRatioBlock(a, b, seed);
  const auto iid = pairedRatio(a, b);
  if (!block || !iid) return std::nullopt;
  PairedMeasure out;
  out.ratio = *block;
  out.ratio.low = std::min(block->low, iid->low);
  out.ratio.high = std::max(block->high, iid->high);
  const size_t n = std::min(a.size(), b.size());
  for (size_t i = 0; i < n; ++i)  // the pairs pairedRatio keeps
    if (a[i] > 0.0 && b[i] > 0.0 && std::isfinite(a[i]) && std::isfinite(b[i]))
      out.logRatios.push_back(std::log(a[i]) - std::log(b[i]));
  return out;
}

BandTest pairedBandTest(const PairedMeasure& m, double band) {
  const BandTest normal = normalBandTest(std::log(m.ratio.estimate), m.ratio.logSe, band);
  const BandTest sign = signBandTest(m.logRatios, band);
  return {std::max(normal.pSlower, sign.pSlower), std::max(normal.pFaster, sign.pFaster)};
}

std::optional<Interval> controlRatio(const json& row, const std::string& prefix) {
  const std::vector<double> control = numbers(row, prefix + "_frame_ms_all");
  // The control repeats the run's own program copy: with program copies, copy 0's frames.
  const std::vector<std::vector<double>> copies = programCopies(row);
  const std::vector<double> original = copies.empty() ? frames(row) : copies.front();
  if (!control.empty() && control.size() == original.size()) {
    const auto m = pairedMeasure(original, control, seedOf(label(row, "key") + "/" + prefix + "/" + label(row, "replicate")));
    return m ? std::optional<Interval>(m->ratio) : std::nullopt;
  }
  const auto ratio = number(row, prefix + "_ratio"), lo = number(row, prefix + "_ci_low"),
             hi = number(row, prefix + "_ci_high");
  if (!ratio || !lo || !hi) return std::nullopt;
  return Interval{*ratio, *lo, *hi, kConfidence, original.size()};
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

// The band of an A/A interval: how far it reaches from 1, on the log scale.
double extentOf(const Interval& aa) { return std::max(std::abs(std::log(aa.low)), std::abs(std::log(aa.high))); }

// a/b across program copies: per copy, the paired ratio of the two runs' frames drawn with that copy;
// the median of those ratios with its order-statistic interval over the copies, and their logs (for
// the sign test, the interval's dual). nullopt unless both runs have the same number of copies, at
// least kMinValuesForInterval, with paired frames each.
std::optional<AcrossCopies> ratioAcrossCopies(const json& a, const json& b) {
  const auto ca = programCopies(a), cb = programCopies(b);
  if (ca.size() < kMinValuesForInterval || ca.size() != cb.size()) return std::nullopt;
  AcrossCopies out;
  std::vector<double> perCopy;
  for (size_t j = 0; j < ca.size(); ++j) {
    if (ca[j].size() != cb[j].size()) return std::nullopt;
    const auto r = pairedRatio(ca[j], cb[j]);
    if (!r) return std::nullopt;
    perCopy.push_back(r->estimate);
    out.logRatios.push_back(std::log(r->estimate));
  }
  const auto m = medianInterval(perCopy);
  if (!m) return std::nullopt;
  out.ratio = *m;
  return out;
}

}  // namespace bvhlab::findings_detail
