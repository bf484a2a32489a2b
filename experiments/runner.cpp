#include "experiments/runner.hpp"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <sstream>

#include "datasets/scene.hpp"  // InputError
#include "experiments/generated_scenes.hpp"
#include "experiments/process.hpp"
#include "experiments/provenance.hpp"
#include "experiments/sweep_dir.hpp"
#include "render/exit_status.hpp"

namespace bvhlab {

namespace fs = std::filesystem;
using nlohmann::json;

std::pair<int, int> parseShard(const std::string& text) {
  const size_t slash = text.find('/');
  int index = -1, count = 0;
  try {
    if (slash == std::string::npos) throw std::invalid_argument("no slash");
    size_t used = 0;
    index = std::stoi(text.substr(0, slash), &used);
    if (used != slash) throw std::invalid_argument("trailing characters");
    const std::string n = text.substr(slash + 1);
    count = std::stoi(n, &used);
    if (used != n.size()) throw std::invalid_argument("trailing characters");
  } catch (const std::exception&) {
    throw InputError("--shard: expected I/N (e.g. 0/4), got '" + text + "'");
  }
  if (count < 1 || index < 0 || index >= count)
    throw InputError("--shard: need 0 <= I < N, got '" + text + "'");
  return {index, count};
}

namespace {

// Keeps the last `limit` bytes of a log (a shader compile error is at the end of stderr).
std::string tail(const std::string& text, size_t limit = 8000) {
  if (text.size() <= limit) return text;
  return "[... " + std::to_string(text.size() - limit) + " bytes cut ...]\n" + text.substr(text.size() - limit);
}

std::string duration(double seconds) {
  const long s = long(seconds + 0.5);
  char buf[32];
  if (s >= 3600) std::snprintf(buf, sizeof buf, "%ldh%02ldm", s / 3600, (s / 60) % 60);
  else if (s >= 60) std::snprintf(buf, sizeof buf, "%ldm%02lds", s / 60, s % 60);
  else std::snprintf(buf, sizeof buf, "%lds", s);
  return buf;
}

// Progress on stderr: on a terminal one live line, rewritten; otherwise (CI, a log file) one line per
// finished run, so a long sweep shows it is alive.
class Progress {
 public:
  Progress(bool enabled, size_t total) : enabled_(enabled), tty_(::isatty(STDERR_FILENO)), total_(total) {}
  void update(size_t done, double secondsPerRun, size_t remaining, const std::string& what) {
    if (!enabled_) return;
    std::string eta = secondsPerRun > 0.0 ? " eta " + duration(secondsPerRun * double(remaining)) : "";
    std::string line = "[" + std::to_string(done) + "/" + std::to_string(total_) + "]" + eta + "  " + what;
    if (!tty_) {
      std::fprintf(stderr, "bvhlab run: %s\n", line.c_str());
      return;
    }
    if (line.size() > 110) line = line.substr(0, 107) + "...";
    std::fprintf(stderr, "\r\033[K%s", line.c_str());
    std::fflush(stderr);
    shown_ = true;
  }
  // One line per finished run when stderr is not a terminal: what it measured, with its interval.
  void finished(size_t done, const RunSpec& run, const json& result) {
    if (!enabled_ || tty_) return;
    char buf[160] = "";
    const auto number = [&](const char* k) { return result.contains(k) && result[k].is_number() ? result[k].get<double>() : -1.0; };
    // A clip run's "frames" is its per-frame array: the count it traced is clip.frames (and its
    // frame_ms the clip's total).
    const bool clip = result.contains("clip") && result["clip"].is_object() && result["clip"].contains("frames") &&
                      result["clip"]["frames"].is_number();
    const int frames = clip ? result["clip"]["frames"].get<int>() : int(number("frames"));
    const char* unit = clip ? "clip frames" : "frames";
    if (number("frame_ms_ci_low") >= 0.0)
      std::snprintf(buf, sizeof buf, "%.3g ms [%.3g, %.3g], %d %s", number("frame_ms"), number("frame_ms_ci_low"),
                    number("frame_ms_ci_high"), frames, unit);
    else if (number("frame_ms") >= 0.0)
      std::snprintf(buf, sizeof buf, "%.3g ms, %d %s", number("frame_ms"), frames, unit);
    std::fprintf(stderr, "bvhlab run: [%zu/%zu] ok %s: %s\n", done, total_, run.describe().c_str(), buf);
  }
  void finish() {
    if (shown_) std::fprintf(stderr, "\r\033[K");
    shown_ = false;
  }

 private:
  bool enabled_, tty_;
  size_t total_;
  bool shown_ = false;
};

// A new id for each group execution (frames pair only within one): 16 hex digits from the clock,
// the process id and a counter, so two shards started in the same second still differ.
std::string newSessionId() {
  static unsigned counter = 0;
  const auto now = std::chrono::system_clock::now().time_since_epoch().count();
  return hashHex(std::to_string(now) + "/" + std::to_string(::getpid()) + "/" + std::to_string(counter++));
}

// ---- the hard-case suite next to a robustness sweep --------------------------------------------------
// When the sweep's runs (reference-only ones aside) take more than one value on the robust axis, the
// sweep also records what those variants do on the hard-case suite (`bvhlab hard-cases`, one child
// process for all of them) in DIR/hard_cases.json, which the report's robustness table reads:
//   {"status": "ok"|"failed", "variants": [names], "command", "log" (stderr tail), "error" (failed),
//    "result": the command's JSON (render/hard_cases_command.hpp), "started_at", "wall_s",
//    "git_commit", "machine", "config_hash"}
// A failure is recorded, not fatal; it is retried on the next invocation like a failed run.

const char* const kHardCasesFile = "hard_cases.json";

std::vector<std::string> sweptRobustness(const ExperimentConfig& config) {
  std::vector<std::string> names;
  for (const RunSpec& run : config.runs) {
    const AxisValue* robust = run.axis("robust");
    if (run.referenceOnly || !robust) continue;
    if (std::find(names.begin(), names.end(), robust->label) == names.end()) names.push_back(robust->label);
  }
  return names;
}

// The kernel and builder the robust sweep renders with (its first run's; the command's defaults when
// the config leaves them to the renderer).
std::vector<std::string> hardCasesSettings(const ExperimentConfig& config) {
  std::vector<std::string> args;
  for (const RunSpec& run : config.runs) {
    if (run.referenceOnly || !run.axis("robust")) continue;
    if (const AxisValue* k = run.axis("kernel")) args.insert(args.end(), {"--kernel", k->label});
    if (const AxisValue* b = run.axis("builder"); b && b->value.contains("name"))
      args.insert(args.end(), {"--builder", b->value["name"].get<std::string>()});
    break;
  }
  return args;
}

void recordHardCases(const ExperimentConfig& config, const SweepDir& dir, const RunOptions& options,
                     const std::string& commit, const json& machine) {
  const std::vector<std::string> variants = sweptRobustness(config);
  if (variants.size() < 2) return;
  const fs::path file = dir.root / kHardCasesFile;
  if (fs::exists(file)) {
    try {
      std::ifstream in(file);
      const json old = json::parse(in);
      if (old.value("variants", json()) == json(variants) &&
          (old.value("status", "") == "ok" || !options.retryFailed))
        return;
    } catch (const std::exception&) {
      // unreadable: redo it
    }
  }
  const fs::path binary = options.binary.empty() ? fs::read_symlink("/proc/self/exe") : options.binary;
  std::vector<std::string> argv = {binary.string(), "hard-cases", "--json", "-", "--gpu", "--backend",
                                   config.render.backend};
  for (const std::string& a : hardCasesSettings(config)) argv.push_back(a);
  for (const std::string& v : variants) argv.insert(argv.end(), {"--robust", v});

  json record = {{"variants", variants},     {"command", shellQuote(argv)}, {"started_at", utcNow()},
                 {"git_commit", commit},     {"machine", machine},          {"config_hash", config.hash}};
  const auto start = std::chrono::steady_clock::now();
  try {
    ProcessOptions po;
    po.env = config.render.env;
    po.timeoutSeconds = config.render.timeoutSeconds;
    const ProcessResult p = runProcess(argv, po);
    record["log"] = tail(p.err);
    if (!p.ok()) throw std::runtime_error("bvhlab hard-cases " + p.status());
    json result = json::parse(p.out);  // throws on anything but one JSON document
    if (!result.is_object() || !result.contains("variants"))
      throw std::runtime_error("bvhlab hard-cases printed no result object");
    record["status"] = "ok";
    record["result"] = std::move(result);
  } catch (const std::exception& e) {
    record["status"] = "failed";
    record["error"] = e.what();
    std::cerr << "bvhlab run: hard cases failed (recorded in " << file.string() << "): " << e.what() << "\n";
  }
  record["wall_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  writeFileAtomic(file, record.dump(1) + "\n");
}

}  // namespace

SweepOutcome runSweep(const RunOptions& options) {
  if (options.shardCount < 1 || options.shardIndex < 0 || options.shardIndex >= options.shardCount)
    throw InputError("--shard: need 0 <= I < N");
  ExperimentConfig config = options.names ? loadExperimentConfig(options.config, *options.names)
                                          : loadExperimentConfig(options.config);
  SweepDir dir{options.outDir.empty() ? fs::path("results") / config.name : options.outDir};
  fs::create_directories(dir.runs());
  fs::create_directories(dir.images());
  materializeGeneratedScenes(config, dir.root);

  // The plan is rewritten on every invocation: an edited config keeps the runs whose keys survive.
  if (fs::exists(dir.plan())) {
    const json old = readPlan(dir);
    if (old["config"]["hash"] != config.hash)
      std::cerr << "bvhlab run: note: " << config.file.string() << " changed since " << dir.plan().string()
                << " was written; finished runs whose parameters are unchanged are kept\n";
  }
  const json plan = makePlan(config);
  writePlan(dir, plan);

  const std::optional<fs::path> sourceDir = findSourceDir();
  const std::string commit = gitCommit(sourceDir);
  const json machine = currentMachine().toJson();
  RunExecutor executor = options.executor ? options.executor : subprocessExecutor(options.binary);

  SweepOutcome outcome;
  outcome.dir = dir.root;
  std::vector<const RunSpec*> mine;
  for (const RunSpec& run : config.runs)
    if (run.index % size_t(options.shardCount) == size_t(options.shardIndex)) mine.push_back(&run);
  outcome.shardRuns = mine.size();

  std::map<std::string, json> records = readRecords(dir);
  ReplicateRecords replicateRecords = readReplicateRecords(dir);
  const int replicates = options.replicates > 0 ? options.replicates : config.replicates;
  // A run's record in replicate r (nullptr: not measured there yet).
  const auto recordOf = [&](const std::string& key, int r) -> const json* {
    if (r == 0) {
      auto it = records.find(key);
      return it == records.end() ? nullptr : &it->second;
    }
    auto it = replicateRecords.find(key);
    if (it == replicateRecords.end()) return nullptr;
    auto jt = it->second.find(r);
    return jt == it->second.end() ? nullptr : &jt->second;
  };
  ImageErrorCache cache;
  // Interleaved groups go to `bvhlab measure` (or an injected group executor); a per-run executor
  // (tests) or [measure] interleave = false gets groups of one run, each its own process.
  const GroupExecutor interleaved = options.groupExecutor ? options.groupExecutor : subprocessGroupExecutor(options.binary);
  const GroupExecutor oneByOne =
      sequentialGroupExecutor(options.executor ? options.executor : subprocessExecutor(options.binary));
  // Traced runs (the rays axis) go to trace groups (`measure` with "command": "trace") like rendered ones.
  const auto alone = [&](const RunSpec& run) { return (options.executor && !options.groupExecutor) || !run.render.interleave; };

  Progress progress(options.progress, mine.size() * size_t(replicates));
  double spentSeconds = 0.0;
  size_t done = 0;
  // Replicate 0 is the sweep; replicates 1.. measure every group again, each pass after the whole
  // previous one, each group in a new child process (experiments/replicates.hpp).
  for (int replicate = 0; replicate < replicates && !outcome.interrupted; ++replicate) {
    // Pending runs, grouped: runs with the same scene and render settings are timed by one process,
    // frames interleaved, at most group_size at a time (experiments/README.md, "Measurement").
    std::vector<std::vector<const RunSpec*>> groups;
    std::map<std::string, size_t> openGroup;  // group signature -> index of its last (not full) group
    for (const RunSpec* run : mine) {
      const json* record = recordOf(run->key, replicate);
      if (record && ((*record)["status"] == "ok" || !options.retryFailed)) {
        ++outcome.skipped;
        ++done;
        continue;
      }
      // A run that failed (or is missing) in replicate 0 is not measured again in the others.
      if (replicate > 0) {
        const json* first = recordOf(run->key, 0);
        if (!first || (*first)["status"] != "ok") {
          ++done;
          continue;
        }
      }
      const AxisValue* scene = run->axis("scene");
      const std::string signature = std::string(run->axis("workload") ? "trace " : "render ") +
                                    (scene ? scene->value.dump() : std::string()) + run->render.groupJson().dump();
      auto g = openGroup.find(signature);
      if (g == openGroup.end() || groups[g->second].size() >= size_t(run->render.groupSize) || alone(*run)) {
        groups.emplace_back();
        g = openGroup.insert_or_assign(signature, groups.size() - 1).first;
      }
      groups[g->second].push_back(run);
    }

    for (size_t gi = 0; gi < groups.size(); ++gi) {
      if ((outcome.interrupted = InterruptGuard::interrupted())) break;
      const std::vector<const RunSpec*>& group = groups[gi];
      const size_t remaining = mine.size() * size_t(replicates) - done;
      progress.update(done, outcome.executed ? spentSeconds / double(outcome.executed) : 0.0, remaining,
                      (replicates > 1 ? "replicate " + std::to_string(replicate + 1) + "/" + std::to_string(replicates) + ", "
                                      : std::string()) +
                          "group " + std::to_string(gi + 1) + "/" + std::to_string(groups.size()) + ": " +
                          std::to_string(group.size()) + " runs, " + group.front()->describe());

      GroupRequest request;
      request.session = newSessionId();
      request.workDir = dir.root;
      for (const RunSpec* run : group) {
        request.runs.push_back(RunRequest{*run, dir.image(run->key, replicate),
                                          run->render.heatmaps ? dir.visitsImage(run->key, replicate) : fs::path(), "",
                                          ""});
        std::error_code ec;
        fs::remove(request.runs.back().image, ec);  // a stale image from an earlier attempt must not pass as this run's
        if (!request.runs.back().visitsImage.empty()) fs::remove(request.runs.back().visitsImage, ec);
      }
      const std::string startedAt = utcNow();
      const auto start = std::chrono::steady_clock::now();
      json results;
      std::string groupError;
      try {
        results = (alone(*group.front()) ? oneByOne : interleaved)(request);
        if (!results.is_object()) throw RunFailure("the group executor returned no JSON object");
      } catch (const std::exception& e) {
        groupError = e.what();
      }
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      // Stopped by SIGINT/SIGTERM: the group's child was killed mid-measurement; its runs stay pending.
      if ((outcome.interrupted = InterruptGuard::interrupted())) break;

      std::vector<const RunSpec*> deferred;  // handed back by a trace group (memory): traced in a later group
      for (const RunRequest& req : request.runs) {
        const RunSpec* run = &req.spec;
        if (groupError.empty() && results.contains(run->key) && results[run->key].is_object() &&
            results[run->key].contains("deferred") && results[run->key].size() == 1) {
          deferred.push_back(run);
          continue;
        }
        json record = {{"key", run->key},
                       {"params", run->toJson()},
                       {"config_name", config.name},
                       {"config_hash", config.hash},
                       {"git_commit", commit},
                       {"machine", machine},
                       {"started_at", startedAt},
                       {"session", request.session},
                       {"group_runs", request.runs.size()}};
        if (replicate > 0) record["replicate"] = replicate;
        const json* entry = groupError.empty() && results.contains(run->key) ? &results[run->key] : nullptr;
        if (!groupError.empty()) {
          record["status"] = "failed";
          record["error"] = groupError + (request.runs.size() > 1 ? " (the whole group of " +
                                                                        std::to_string(request.runs.size()) + " runs)"
                                                                  : std::string());
        } else if (!entry || !entry->is_object()) {
          record["status"] = "failed";
          record["error"] = "the group's result has no entry for this run";
        } else if (entry->contains("error")) {
          record["status"] = "failed";
          record["error"] = (*entry)["error"].is_string() ? (*entry)["error"].get<std::string>() : (*entry)["error"].dump();
          if (entry->contains("result") && (*entry)["result"].is_object()) record["result"] = (*entry)["result"];
        } else {
          record["status"] = "ok";
          record["result"] = *entry;
        }
        // The group's wall time is shared by its runs; each run's share is what the ETA needs.
        record["wall_s"] = seconds / double(request.runs.size());
        record["group_wall_s"] = seconds;
        record["command"] = req.command.empty() ? request.command : req.command;
        record["log"] = tail(req.log.empty() ? request.log : req.log);
        std::error_code ec;
        record["image"] = fs::exists(req.image, ec) ? json("images/" + req.image.filename().string()) : json();
        record["visits_image"] = !req.visitsImage.empty() && fs::exists(req.visitsImage, ec)
                                     ? json("images/" + req.visitsImage.filename().string())
                                     : json();
        writeFileAtomic(dir.record(run->key, replicate), record.dump(1) + "\n");
        (replicate == 0 ? records[run->key] : replicateRecords[run->key][replicate]) = record;
        ++outcome.executed;
        ++done;
        if (record["status"] != "ok") {
          ++outcome.failed;
          progress.finish();
          std::cerr << "bvhlab run: run " << run->index << " (" << run->describe() << ")"
                    << (replicate > 0 ? " in replicate " + std::to_string(replicate) : std::string()) << " failed: "
                    << record["error"].get<std::string>() << "\n";
        } else {
          progress.finished(done, *run, record["result"]);
        }
      }
      spentSeconds += seconds;
      outcome.summary = writeResults(dir, plan, records, &cache, replicateRecords);
      // A group traces at least its first run, so a deferred rest is smaller: this ends.
      if (!deferred.empty() && deferred.size() < request.runs.size()) groups.push_back(std::move(deferred));
    }
  }
  progress.finish();
  // Once per sweep (shard 0 of a sharded one), and only when there is a real renderer to ask: the runs
  // go to child processes, or an injected executor (tests) comes with an explicit binary.
  if ((!options.executor || !options.binary.empty()) && options.shardIndex == 0 && !outcome.interrupted)
    recordHardCases(config, dir, options, commit, machine);
  outcome.summary = writeResults(dir, plan, records, &cache, replicateRecords);
  return outcome;
}

json mergeSweeps(const std::vector<fs::path>& dirs, const fs::path& out, bool asReplicates) {
  if (dirs.empty()) throw InputError("merge: no input directories");
  SweepDir target{out};
  std::vector<SweepDir> inputs;
  // An existing output directory takes part like an input (merging into it is incremental).
  std::error_code ec;
  if (fs::exists(target.plan())) {
    if (asReplicates)
      throw InputError("merge --replicates: " + out.string() +
                       " already holds a sweep; merge replicates into a new directory (merging them twice would "
                       "count them twice)");
    inputs.push_back(target);
  }
  for (const fs::path& d : dirs)
    if (!fs::exists(target.plan()) || !fs::equivalent(d, out, ec)) inputs.push_back(SweepDir{d});

  json plan;
  std::string planFrom;
  for (const SweepDir& in : inputs) {
    json p = readPlan(in);
    if (plan.is_null()) {
      plan = std::move(p);
      planFrom = in.root.string();
    } else if (p["config"]["hash"] != plan["config"]["hash"]) {
      throw InputError("merge: " + in.root.string() + " comes from a different config (hash " +
                       p["config"]["hash"].get<std::string>() + ") than " + planFrom + " (hash " +
                       plan["config"]["hash"].get<std::string>() + ")");
    }
  }

  // Best record per (key, replicate): ok beats failed; among equals the first input wins. As
  // replicates, input i's replicate r becomes replicate offset_i + r.
  std::map<std::pair<std::string, int>, std::pair<json, const SweepDir*>> best;
  int offset = 0;
  for (const SweepDir& in : inputs) {
    std::vector<std::pair<int, std::pair<std::string, json>>> found;
    for (auto& [key, record] : readRecords(in)) found.push_back({0, {key, std::move(record)}});
    for (auto& [key, byReplicate] : readReplicateRecords(in))
      for (auto& [r, record] : byReplicate) found.push_back({r, {key, std::move(record)}});
    int count = 0;
    for (auto& [r, entry] : found) {
      auto& [key, record] = entry;
      count = std::max(count, r + 1);
      const int replicate = asReplicates ? offset + r : r;
      auto it = best.find({key, replicate});
      if (it == best.end() || (it->second.first["status"] != "ok" && record["status"] == "ok"))
        best[{key, replicate}] = {std::move(record), &in};
    }
    if (asReplicates) offset += count;
  }
  if (asReplicates && offset > kMaxReplicates)
    throw InputError("merge --replicates: " + std::to_string(offset) + " replicates, more than " +
                     std::to_string(kMaxReplicates));

  fs::create_directories(target.runs());
  fs::create_directories(target.images());
  writePlan(target, plan);
  for (auto& [id, entry] : best) {
    const auto& [key, replicate] = id;
    auto& [record, from] = entry;
    if (from->root == target.root || fs::equivalent(from->root, target.root, ec)) continue;
    // Images keep their names unless the replicate was renumbered.
    for (const char* field : {"image", "visits_image"})
      if (record.contains(field) && record[field].is_string()) {
        const fs::path rel = record[field].get<std::string>();
        const bool visits = std::string(field) == "visits_image";
        const fs::path to = (visits ? target.visitsImage(key, replicate) : target.image(key, replicate));
        if (fs::exists(from->root / rel)) {
          fs::copy_file(from->root / rel, to, fs::copy_options::overwrite_existing);
          record[field] = "images/" + to.filename().string();
        }
      }
    if (replicate > 0) record["replicate"] = replicate;
    else record.erase("replicate");
    writeFileAtomic(target.record(key, replicate), record.dump(1) + "\n");
  }
  // The hard-case results come with the shard that ran them (shard 0): the first input with an ok one.
  for (const SweepDir& in : inputs) {
    const fs::path from = in.root / kHardCasesFile;
    if (in.root == target.root || !fs::exists(from)) continue;
    std::ifstream f(from);
    std::stringstream text;
    text << f.rdbuf();
    bool ok = false;
    try {
      ok = json::parse(text.str()).value("status", "") == "ok";
    } catch (const std::exception&) {
    }
    if (!ok && fs::exists(target.root / kHardCasesFile)) continue;
    writeFileAtomic(target.root / kHardCasesFile, text.str());
    if (ok) break;
  }
  return writeResults(target);
}

fs::path writeReport(const fs::path& dir) {
  const std::optional<fs::path> source = findSourceDir();
  if (!source)
    throw std::runtime_error("cannot find experiments/report.py (set BVHLAB_SOURCE_DIR to the bvhlab source tree)");
  const char* python = std::getenv("BVHLAB_PYTHON");
  // Debian's python3 has python3-matplotlib; a pyenv/venv python3 on PATH usually does not.
  const std::string interpreter = python && *python ? python : "/usr/bin/python3";
  ProcessOptions options;
  options.timeoutSeconds = 600.0;
  const ProcessResult r = runProcess({interpreter, (*source / "experiments" / "report.py").string(), dir.string()},
                                     options);
  if (!r.ok())
    throw std::runtime_error("report.py " + r.status() + ": " + tail(r.err + r.out, 2000));
  if (!r.err.empty()) std::cerr << r.err;
  return dir / "report.html";
}

int runCommand(const RunOptions& options) {
  try {
    const InterruptGuard guard;  // Ctrl-C / kill stop the running group's child too
    const SweepOutcome o = runSweep(options);
    const json& s = o.summary;
    if (o.interrupted) {
      std::string again = "bvhlab run " + options.config.string();
      if (!options.outDir.empty()) again += " --out " + options.outDir.string();
      if (options.shardCount > 1)
        again += " --shard " + std::to_string(options.shardIndex) + "/" + std::to_string(options.shardCount);
      std::cerr << "bvhlab run: interrupted (" << strsignal(o.interrupted) << "); the running group was stopped, "
                << s.value("ok", 0) << " finished runs are kept in " << o.dir.string() << "; resume with: " << again
                << "\n";
      return 128 + o.interrupted;
    }
    std::cerr << "bvhlab run: " << o.executed << " runs executed (" << o.failed << " failed), " << o.skipped
              << " already finished; " << o.dir.string() << ": " << s["ok"] << " ok, " << s["failed"]
              << " failed, " << s["pending"] << " pending of " << s["planned"] << "\n";
    if (options.report) {
      try {
        std::cerr << "bvhlab run: report " << writeReport(o.dir).string() << "\n";
      } catch (const std::exception& e) {
        std::cerr << "bvhlab run: warning: no report: " << e.what() << "\n";
      }
    }
    return 0;
  } catch (const std::exception& e) {
    return reportError(e);  // 2 for bad input, 1 for a file that cannot be read or a failure
  }
}

int mergeCommand(const std::vector<fs::path>& dirs, const fs::path& out, bool asReplicates) {
  try {
    const json s = mergeSweeps(dirs, out, asReplicates);
    std::cerr << "bvhlab merge: " << out.string() << ": " << s["ok"] << " ok, " << s["failed"] << " failed, "
              << s["pending"] << " pending of " << s["planned"] << "\n";
    try {
      std::cerr << "bvhlab merge: report " << writeReport(out).string() << "\n";
    } catch (const std::exception& e) {
      std::cerr << "bvhlab merge: warning: no report: " << e.what() << "\n";
    }
    return 0;
  } catch (const std::exception& e) {
    return reportError(e);  // 2 for bad input, 1 for a file that cannot be read or a failure
  }
}

int reportCommand(const fs::path& dir) {
  try {
    writeResults(SweepDir{dir});  // picks up runs finished since the last regeneration
    std::cout << writeReport(dir).string() << "\n";
    return 0;
  } catch (const std::exception& e) {
    return reportError(e);  // 2 for bad input, 1 for a file that cannot be read or a failure
  }
}

}  // namespace bvhlab
