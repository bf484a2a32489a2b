#include "experiments/replicates.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>

namespace bvhlab {

using nlohmann::json;

namespace {
constexpr const char* kReplicateInfix = ".r";
constexpr double kInfinity = std::numeric_limits<double>::infinity();
}  // namespace

std::string replicateStem(const std::string& key, int replicate) {
  return replicate == 0 ? key : key + kReplicateInfix + std::to_string(replicate);
}

std::optional<int> replicateOfStem(const std::string& stem) {
  const size_t dot = stem.rfind(kReplicateInfix);
  if (dot == std::string::npos) return stem.find('.') == std::string::npos ? std::optional<int>(0) : std::nullopt;
  const std::string digits = stem.substr(dot + 2);
  const auto digit = [](unsigned char c) { return std::isdigit(c) != 0; };
  if (digits.empty() || digits.size() > 4 || !std::all_of(digits.begin(), digits.end(), digit)) return std::nullopt;
  const int r = std::stoi(digits);
  return r >= 1 ? std::optional<int>(r) : std::nullopt;
}

void poolReplicateRows(json& row, const std::vector<json>& replicateRows) {
  row["replicates"] = 1;
  if (replicateRows.size() < 2) return;
  std::vector<double> medians;
  double low = kInfinity, high = -kInfinity;
  bool haveInterval = true;
  json rows = json::array();
  for (size_t r = 0; r < replicateRows.size(); ++r) {
    const json& x = replicateRows[r];
    const json ms = x.value("frame_ms", json());
    if (!ms.is_number()) return;  // a replicate without a time: nothing honest to pool
    medians.push_back(ms.get<double>());
    const json lo = x.value("frame_ms_ci_low", json()), hi = x.value("frame_ms_ci_high", json());
    if (lo.is_number() && hi.is_number()) {
      low = std::min(low, lo.get<double>());
      high = std::max(high, hi.get<double>());
    } else {
      haveInterval = false;
    }
    rows.push_back(x);
  }
  row["replicates"] = replicateRows.size();
  row["replicate_rows"] = std::move(rows);
  row["frame_ms_replicates"] = medians;
  const double pooled = medianOf(medians);
  row["frame_ms"] = pooled;
  row["frame_ms_ci_low"] = haveInterval ? json(low) : json();
  row["frame_ms_ci_high"] = haveInterval ? json(high) : json();
  row["fps"] = pooled > 0.0 ? json(1000.0 / pooled) : json();
}

std::optional<PooledRatio> poolReplicateRatios(const std::vector<ReplicateRatio>& replicates) {
  std::vector<double> estimates, logEstimates;
  PooledRatio out;
  out.ratio.low = kInfinity;
  out.ratio.high = -kInfinity;
  out.test.pSlower = out.test.pFaster = 0.0;
  for (const ReplicateRatio& r : replicates) {
    if (!r.ratio) continue;  // too few frames in that replicate: it says nothing
    estimates.push_back(r.ratio->estimate);
    logEstimates.push_back(std::log(r.ratio->estimate));
    out.ratio.low = std::min(out.ratio.low, r.ratio->low);
    out.ratio.high = std::max(out.ratio.high, r.ratio->high);
    out.band = std::max(out.band, r.band);
    out.hasBand = out.hasBand && r.hasBand;
    // Every replicate must reject on the same side: the largest one-sided p of each side.
    out.test.pSlower = std::max(out.test.pSlower, r.test.pSlower);
    out.test.pFaster = std::max(out.test.pFaster, r.test.pFaster);
  }
  if (estimates.size() < 2) return std::nullopt;
  if (const auto across = medianInterval(estimates)) {  // kMinValuesForInterval or more
    out.ratio = *across;
    out.band = 0.0;
    out.hasBand = true;  // the replicates' spread is a band measured across processes
    out.test = signBandTest(logEstimates, 0.0);
    out.over = "replicates";
    return out;
  }
  out.ratio.estimate = medianOf(estimates);
  out.ratio.n = estimates.size();
  out.ratio.coverage = kConfidence;  // each replicate's interval is a 95% one; the hull contains them all
  out.over = "replicates (hull)";
  return out;
}

}  // namespace bvhlab
