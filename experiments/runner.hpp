// The experiment runner: `bvhlab run CONFIG`, `bvhlab merge DIR...`, `bvhlab report DIR`.
// A config (experiments/README.md) expands into runs; each run is executed by a RunExecutor
// (normally `bvhlab render` as a child process), recorded atomically in DIR/runs/KEY.json before the
// next starts, and DIR/results.{json,csv} are regenerated after every run. Re-running resumes.
#pragma once
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "experiments/config.hpp"
#include "experiments/executor.hpp"

namespace bvhlab {

struct RunOptions {
  std::filesystem::path config;
  std::filesystem::path outDir;  // "" = results/<experiment name> under the working directory
  int shardIndex = 0;            // run i belongs to this invocation when i % shardCount == shardIndex
  int shardCount = 1;
  bool retryFailed = true;       // failed runs are redone on the next invocation (false: kept as failed)
  bool report = true;            // write DIR/report.html at the end (needs /usr/bin/python3 + matplotlib)
  std::filesystem::path binary;  // renderer; "" = this executable (also runs `hard-cases` for robust
                                 // sweeps, even with an injected executor when set explicitly)
  GroupExecutor groupExecutor;   // empty = executor run by run if set, else subprocessGroupExecutor(binary)
  RunExecutor executor;          // a per-run executor (tests): groups run sequentially, unpaired
  std::optional<KnownNames> names;  // names to validate against; empty = registeredNames()
  bool progress = true;          // progress on stderr: a live line on a terminal, else one line per run
  int replicates = 0;            // passes over the sweep (experiments/replicates.hpp); 0 = the config's
};

// Parses "I/N" (0 <= I < N); throws InputError naming the flag.
std::pair<int, int> parseShard(const std::string& text);

struct SweepOutcome {
  std::filesystem::path dir;
  size_t shardRuns = 0;  // runs of the plan in this shard
  size_t executed = 0;   // runs executed now (a run measured in R replicates counts R times)
  size_t skipped = 0;    // runs (per replicate) already finished (resumed)
  size_t failed = 0;     // runs executed now that failed
  nlohmann::json summary;  // writeResults()'s summary of the whole directory
  int interrupted = 0;     // the signal that stopped the sweep (InterruptGuard in runCommand), or 0
};

// The library entry points (throw InputError for a bad config or directory).
SweepOutcome runSweep(const RunOptions& options);
// Combines shard directories into `out` (deduplicated by run key and replicate; a finished run beats
// a failed one) and regenerates results. All inputs must come from the same config (same hash).
// `asReplicates`: the inputs are repetitions of one sweep (e.g. `bvhlab run` of one config at two
// times): each input's replicates are appended after the previous inputs' (input 0 keeps 0..R0-1,
// input 1 gets R0.., ...), so findings pool them (experiments/replicates.hpp). `out` must then be a
// new directory.
nlohmann::json mergeSweeps(const std::vector<std::filesystem::path>& dirs, const std::filesystem::path& out,
                           bool asReplicates = false);
// Runs experiments/report.py on `dir` (results.json -> report.html). Throws std::runtime_error with
// the script's complaint when it fails (e.g. matplotlib missing).
std::filesystem::path writeReport(const std::filesystem::path& dir);

// CLI wrappers: print errors on stderr, return the process exit status (render/exit_status.hpp: 0 ok,
// 1 failure or a file that cannot be read, 2 bad input).
// A sweep whose runs were all attempted returns 0 even if some runs failed: failures are data,
// recorded with their error and listed in the report.
int runCommand(const RunOptions& options);
int mergeCommand(const std::vector<std::filesystem::path>& dirs, const std::filesystem::path& out,
                 bool asReplicates = false);
int reportCommand(const std::filesystem::path& dir);

}  // namespace bvhlab
