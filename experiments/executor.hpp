// Executing one run. The runner never renders itself: it hands each run to an executor, normally
// `bvhlab render ... --json` in a child process, so a crash or a shader that fails to compile ends
// that run only. Tests inject a fake executor.
#pragma once
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "experiments/config.hpp"

namespace bvhlab {

struct RunRequest {
  const RunSpec& spec;
  std::filesystem::path image;        // where the rendered PNG goes
  std::filesystem::path visitsImage;  // where the visit heatmap goes ("" = none wanted)
  // Filled by the executor, kept in the run's record (ok or failed):
  std::string command;  // what it ran, shell-quoted
  std::string log;      // what the renderer wrote on stderr
};

// Returns the renderer's JSON object. Any exception marks the run failed with its message;
// RunFailure also carries whatever JSON the renderer printed before failing.
using RunExecutor = std::function<nlohmann::json(RunRequest&)>;

struct RunFailure : std::runtime_error {
  RunFailure(const std::string& what, nlohmann::json partial = nullptr)
      : std::runtime_error(what), partialResult(std::move(partial)) {}
  nlohmann::json partialResult;
};

// `BINARY render SCENE --json -o IMAGE ...` for the request (flags: experiments/README.md), or for a
// run on the rays axis `BINARY trace SCENE --json --rays WORKLOAD ...` (no image).
std::vector<std::string> renderCommandLine(const std::filesystem::path& binary, const RunRequest& request);

// Runs renderCommandLine() as a child process with the run's env and timeout. A non-zero exit, a
// signal, a timeout or stdout that is not one JSON object throws RunFailure (message: the status
// and the telling line of stderr: the last mentioning "error", else the first). `binary` empty = this executable (/proc/self/exe).
RunExecutor subprocessExecutor(std::filesystem::path binary = {});

// ---- groups: runs timed together, frames interleaved (render/measure_command.hpp) -----------------
// The runner hands every pending run of a shard to a GroupExecutor, grouped by scene and render
// settings (RunRender::groupJson), at most [measure] group_size runs per group.
struct GroupRequest {
  std::vector<RunRequest> runs;
  std::string session;              // a new id per group execution: frames pair only within a session
  std::filesystem::path workDir;    // where the executor may write its group file
  // Filled by the executor, kept in every run's record:
  std::string command;
  std::string log;
};

// Returns an object with one entry per run key: the renderer's JSON object for that run, or
// {"error": "why", "result": whatever it measured}. A run missing from the object failed with
// "no result". Throwing fails every run of the group with the message (a crash, a timeout).
using GroupExecutor = std::function<nlohmann::json(GroupRequest&)>;

// The group file `bvhlab measure` reads (format in render/measure_command.hpp).
nlohmann::json measureSpec(const std::filesystem::path& binary, const GroupRequest& request);

// `BINARY measure GROUPFILE` as a child process; the timeout is the runs' timeout_s times their count.
GroupExecutor subprocessGroupExecutor(std::filesystem::path binary = {});
// Runs a group one run at a time through a RunExecutor (no interleaving, no pairing): what an
// injected per-run executor (tests) gets.
GroupExecutor sequentialGroupExecutor(RunExecutor run);

}  // namespace bvhlab
