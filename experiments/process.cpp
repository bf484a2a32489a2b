#include "experiments/process.hpp"

#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fcntl.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <stdexcept>

extern char** environ;

namespace bvhlab {

std::string ProcessResult::status() const {
  if (timedOut) return "timed out (killed)";
  if (signal != 0) return "killed by signal " + std::to_string(signal) + " (" + strsignal(signal) + ")";
  return "exit code " + std::to_string(exitCode);
}

std::string shellQuote(const std::vector<std::string>& argv) {
  std::string out;
  for (const std::string& a : argv) {
    if (!out.empty()) out += ' ';
    const bool plain = !a.empty() && a.find_first_not_of(
                                         "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789"
                                         "-_./=,:+@%") == std::string::npos;
    if (plain) {
      out += a;
      continue;
    }
    out += '\'';
    for (char c : a) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    out += '\'';
  }
  return out;
}

namespace {

// Closes a file descriptor once.
struct Fd {
  int fd = -1;
  ~Fd() { reset(); }
  void reset() {
    if (fd >= 0) ::close(fd);
    fd = -1;
  }
};

}  // namespace

namespace {

// The child runProcess waits for, and the interrupting signal: plain values a signal handler may use.
volatile sig_atomic_t gChild = 0;
volatile sig_atomic_t gSignal = 0;
struct sigaction gPreviousInt, gPreviousTerm;

extern "C" void onInterrupt(int sig) {
  gSignal = sig;
  if (gChild > 0) ::kill(pid_t(gChild), SIGKILL);  // async-signal-safe; the render has nothing to flush
}

}  // namespace

InterruptGuard::InterruptGuard() {
  gSignal = 0;
  struct sigaction sa {};
  sa.sa_handler = onInterrupt;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;  // no SA_RESTART: poll/waitpid return EINTR and the loops look again
  ::sigaction(SIGINT, &sa, &gPreviousInt);
  ::sigaction(SIGTERM, &sa, &gPreviousTerm);
}

InterruptGuard::~InterruptGuard() {
  ::sigaction(SIGINT, &gPreviousInt, nullptr);
  ::sigaction(SIGTERM, &gPreviousTerm, nullptr);
}

int InterruptGuard::interrupted() { return int(gSignal); }

ProcessResult runProcess(const std::vector<std::string>& argv, const ProcessOptions& options) {
  if (argv.empty()) throw std::invalid_argument("runProcess: empty argv");

  // Environment: ours with the overrides replaced/added.
  std::vector<std::string> envStrings;
  for (char** e = environ; *e; ++e) {
    std::string entry(*e);
    const std::string name = entry.substr(0, entry.find('='));
    if (!options.env.count(name)) envStrings.push_back(std::move(entry));
  }
  for (const auto& [name, value] : options.env) envStrings.push_back(name + "=" + value);
  std::vector<char*> envp, args;
  for (std::string& s : envStrings) envp.push_back(s.data());
  envp.push_back(nullptr);
  std::vector<std::string> argvCopy = argv;
  for (std::string& s : argvCopy) args.push_back(s.data());
  args.push_back(nullptr);

  Fd outPipe[2], errPipe[2];
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  if (options.capture) {
    int p[2];
    if (pipe2(p, O_CLOEXEC) != 0) throw std::runtime_error(std::string("pipe: ") + std::strerror(errno));
    outPipe[0].fd = p[0], outPipe[1].fd = p[1];
    if (pipe2(p, O_CLOEXEC) != 0) throw std::runtime_error(std::string("pipe: ") + std::strerror(errno));
    errPipe[0].fd = p[0], errPipe[1].fd = p[1];
    posix_spawn_file_actions_adddup2(&actions, outPipe[1].fd, STDOUT_FILENO);
    posix_spawn_file_actions_adddup2(&actions, errPipe[1].fd, STDERR_FILENO);
  }
  pid_t pid = 0;
  const int rc = argv[0].find('/') == std::string::npos
                     ? posix_spawnp(&pid, args[0], &actions, nullptr, args.data(), envp.data())
                     : posix_spawn(&pid, args[0], &actions, nullptr, args.data(), envp.data());
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) throw std::runtime_error("cannot start '" + argv[0] + "': " + std::strerror(rc));
  gChild = pid;
  struct ClearChild {
    ~ClearChild() { gChild = 0; }
  } clearChild;
  if (gSignal != 0) ::kill(pid, SIGKILL);  // interrupted while it was being started
  outPipe[1].reset();
  errPipe[1].reset();

  ProcessResult result;
  using Clock = std::chrono::steady_clock;
  const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                           std::chrono::duration<double>(options.timeoutSeconds));
  auto remainingMs = [&]() -> int {
    if (options.timeoutSeconds <= 0.0) return -1;
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
    return left > 0 ? int(std::min<long long>(left, 1000)) : 0;
  };

  // Drain both pipes until EOF (a full pipe would block the child) or the deadline.
  if (options.capture) {
    pollfd fds[2] = {{outPipe[0].fd, POLLIN, 0}, {errPipe[0].fd, POLLIN, 0}};
    std::string* sinks[2] = {&result.out, &result.err};
    int open = 2;
    char buf[65536];
    while (open > 0) {
      const int wait = remainingMs();
      if (wait == 0) {
        result.timedOut = true;
        break;
      }
      const int n = ::poll(fds, 2, wait);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) break;
      for (int i = 0; i < 2; ++i) {
        if (fds[i].fd < 0 || !(fds[i].revents & (POLLIN | POLLHUP | POLLERR))) continue;
        const ssize_t got = ::read(fds[i].fd, buf, sizeof buf);
        if (got > 0) {
          sinks[i]->append(buf, size_t(got));
        } else if (got == 0 || errno != EINTR) {
          fds[i].fd = -1;
          --open;
        }
      }
    }
  }

  int status = 0;
  while (true) {
    if (result.timedOut) {
      ::kill(pid, SIGKILL);  // the child we started, only
      ::waitpid(pid, &status, 0);
      break;
    }
    const pid_t w = ::waitpid(pid, &status, options.timeoutSeconds > 0.0 ? WNOHANG : 0);
    if (w == pid) break;
    if (w < 0 && errno != EINTR) throw std::runtime_error(std::string("waitpid: ") + std::strerror(errno));
    if (w == 0) {
      if (remainingMs() == 0) result.timedOut = true;
      else ::usleep(10000);  // 10 ms: polling granularity of the timeout, small against any render
    }
  }
  if (!result.timedOut) {
    if (WIFEXITED(status)) result.exitCode = WEXITSTATUS(status);
    if (WIFSIGNALED(status)) result.signal = WTERMSIG(status);
  }
  return result;
}

}  // namespace bvhlab
