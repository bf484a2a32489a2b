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

// `BINARY render SCENE --json -o IMAGE ...` for the request (flags: experiments/README.md).
std::vector<std::string> renderCommandLine(const std::filesystem::path& binary, const RunRequest& request);

// Runs renderCommandLine() as a child process with the run's env and timeout. A non-zero exit, a
// signal, a timeout or stdout that is not one JSON object throws RunFailure (message: the status
// and the telling line of stderr: the last mentioning "error", else the first). `binary` empty = this executable (/proc/self/exe).
RunExecutor subprocessExecutor(std::filesystem::path binary = {});

}  // namespace bvhlab
