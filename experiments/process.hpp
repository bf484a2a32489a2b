// Child processes: the renderer runs (one per run of a sweep), git and the report script.
#pragma once
#include <map>
#include <string>
#include <vector>

namespace bvhlab {

struct ProcessResult {
  int exitCode = -1;       // valid when the process exited normally
  int signal = 0;          // the signal that ended it, or 0
  bool timedOut = false;   // killed by us after the timeout
  std::string out, err;    // captured stdout/stderr (empty when not captured)
  bool ok() const { return !timedOut && signal == 0 && exitCode == 0; }
  std::string status() const;  // "exit code 3", "killed by signal 11 (Segmentation fault)", "timed out after ..."
};

struct ProcessOptions {
  std::map<std::string, std::string> env;  // added to (or replacing in) this process's environment
  double timeoutSeconds = 0.0;             // 0 = none; otherwise the child is sent SIGKILL
  bool capture = true;                     // false: the child inherits our stdout/stderr
};

// Runs argv[0] (searched on PATH when it has no slash) and waits for it. Throws std::runtime_error
// when the process cannot be started at all (not found, not executable).
ProcessResult runProcess(const std::vector<std::string>& argv, const ProcessOptions& options = {});

// While one exists, SIGINT and SIGTERM to this process kill the child runProcess is waiting for
// (so a stopped sweep leaves no render running, writing images for a run without a record) and
// are remembered: interrupted() tells the caller to stop at the next safe point. The previous
// handlers come back when it is destroyed.
class InterruptGuard {
 public:
  InterruptGuard();
  ~InterruptGuard();
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;
  static int interrupted();  // the signal received (SIGINT/SIGTERM), or 0
};

// Quotes argv for a POSIX shell, for logs and error messages ("bvhlab render 'a b.toml' --json").
std::string shellQuote(const std::vector<std::string>& argv);

}  // namespace bvhlab
