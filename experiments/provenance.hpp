// Where a number came from: source commit, machine, time. Every result row carries these.
#pragma once
#include <filesystem>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

namespace bvhlab {

struct MachineInfo {
  std::string hostname;
  std::string cpu;  // "model name" from /proc/cpuinfo ("unknown" when absent)
  unsigned cores = 0;
  nlohmann::json toJson() const;
};
MachineInfo currentMachine();

// How busy the machine is: the 1-minute load average (/proc/loadavg) and the CPU time counters of
// /proc/stat's "cpu" line (all columns summed, and the hypervisor's "steal" column). A missing or
// unreadable file leaves `known` false.
struct MachineLoad {
  bool known = false;
  double loadAvg1m = 0.0;
  unsigned long long totalJiffies = 0, stealJiffies = 0;
};
MachineLoad machineLoadNow();

// What the machine did while a group was measured, as result fields: "load_avg_1m_start",
// "load_avg_1m_end" and "steal_pct" (CPU time stolen by the hypervisor over the interval, % of all
// CPU time); {} when either sample is unknown, null steal when no CPU time passed between them.
nlohmann::json machineLoadDuring(const MachineLoad& start, const MachineLoad& end);

// The bvhlab source tree: $BVHLAB_SOURCE_DIR, else the first directory holding
// experiments/report.py found walking up from this executable, then from the working directory.
std::optional<std::filesystem::path> findSourceDir();

// `git rev-parse HEAD` of `dir`, or "unknown" (not a checkout, git missing).
std::string gitCommit(const std::optional<std::filesystem::path>& dir);

// The current time, UTC, ISO 8601 to the second ("2024-05-01T12:00:00Z").
std::string utcNow();

}  // namespace bvhlab
