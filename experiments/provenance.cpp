#include "experiments/provenance.hpp"

#include <unistd.h>

#include <cstdlib>
#include <ctime>
#include <fstream>
#include <thread>

#include "experiments/process.hpp"

namespace bvhlab {

namespace fs = std::filesystem;

nlohmann::json MachineInfo::toJson() const {
  return {{"hostname", hostname}, {"cpu", cpu}, {"cores", cores}};
}

MachineInfo currentMachine() {
  MachineInfo m;
  char host[256] = {};
  m.hostname = ::gethostname(host, sizeof host - 1) == 0 ? host : "unknown";
  m.cpu = "unknown";
  std::ifstream cpuinfo("/proc/cpuinfo");
  for (std::string line; std::getline(cpuinfo, line);) {
    if (line.rfind("model name", 0) != 0) continue;
    const size_t colon = line.find(':');
    if (colon == std::string::npos) continue;
    const size_t start = line.find_first_not_of(" \t", colon + 1);
    if (start != std::string::npos) m.cpu = line.substr(start);
    break;
  }
  m.cores = std::thread::hardware_concurrency();
  return m;
}

MachineLoad machineLoadNow() {
  MachineLoad m;
  std::ifstream loadavg("/proc/loadavg");
  std::ifstream stat("/proc/stat");
  std::string cpu;
  if (!(loadavg >> m.loadAvg1m) || !(stat >> cpu) || cpu != "cpu") return m;
  // user nice system idle iowait irq softirq steal guest guest_nice: steal is the 8th column. Guest
  // time is already counted in user/nice, so the total sums the first eight columns only.
  unsigned long long column = 0;
  int n = 0;
  for (; n < 8 && (stat >> column); ++n) {
    m.totalJiffies += column;
    if (n == 7) m.stealJiffies = column;
  }
  // Kernels before 2.6.11 have no steal column: 7 columns read, steal unknown -> 0 stolen.
  m.known = n >= 7;
  return m;
}

nlohmann::json machineLoadDuring(const MachineLoad& start, const MachineLoad& end) {
  if (!start.known || !end.known) return nlohmann::json::object();
  nlohmann::json out = {{"load_avg_1m_start", start.loadAvg1m}, {"load_avg_1m_end", end.loadAvg1m}};
  const bool forward = end.totalJiffies > start.totalJiffies && end.stealJiffies >= start.stealJiffies;
  out["steal_pct"] = forward ? nlohmann::json(100.0 * double(end.stealJiffies - start.stealJiffies) /
                                              double(end.totalJiffies - start.totalJiffies))
                             : nlohmann::json();
  return out;
}

namespace {

std::optional<fs::path> searchUp(fs::path dir) {
  std::error_code ec;
  for (; !dir.empty(); dir = dir.parent_path()) {
    if (fs::is_regular_file(dir / "experiments" / "report.py", ec)) return dir;
    if (dir == dir.root_path()) break;
  }
  return std::nullopt;
}

}  // namespace

std::optional<fs::path> findSourceDir() {
  if (const char* env = std::getenv("BVHLAB_SOURCE_DIR"); env && *env) return fs::path(env);
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec)
    if (auto dir = searchUp(exe.parent_path())) return dir;
  const fs::path cwd = fs::current_path(ec);
  if (!ec)
    if (auto dir = searchUp(cwd)) return dir;
  return std::nullopt;
}

std::string gitCommit(const std::optional<fs::path>& dir) {
  if (!dir) return "unknown";
  try {
    ProcessOptions options;
    options.timeoutSeconds = 30.0;
    const ProcessResult r = runProcess({"git", "-C", dir->string(), "rev-parse", "HEAD"}, options);
    std::string commit = r.out.substr(0, r.out.find_first_of("\r\n"));
    if (r.ok() && commit.size() >= 7) return commit;
  } catch (const std::exception&) {
    // git not installed: the commit is unknown, which the rows say.
  }
  return "unknown";
}

std::string utcNow() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

}  // namespace bvhlab
