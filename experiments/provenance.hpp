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

// The bvhlab source tree: $BVHLAB_SOURCE_DIR, else the first directory holding
// experiments/report.py found walking up from this executable, then from the working directory.
std::optional<std::filesystem::path> findSourceDir();

// `git rev-parse HEAD` of `dir`, or "unknown" (not a checkout, git missing).
std::string gitCommit(const std::optional<std::filesystem::path>& dir);

// The current time, UTC, ISO 8601 to the second ("2024-05-01T12:00:00Z").
std::string utcNow();

}  // namespace bvhlab
