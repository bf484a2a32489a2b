#include "experiments/executor.hpp"

#include <cctype>
#include <charconv>
#include <sstream>

#include "experiments/process.hpp"
#include "experiments/provenance.hpp"
#include "experiments/sweep_dir.hpp"

namespace bvhlab {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::string number(double v) {
  char buf[32];
  auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);  // shortest round-trip form
  return std::string(buf, end);
}

std::string vec3Flag(const json& v) {
  return number(v.at(0).get<double>()) + "," + number(v.at(1).get<double>()) + "," + number(v.at(2).get<double>());
}

std::string scalarFlag(const json& v) {
  if (v.is_string()) return v.get<std::string>();
  if (v.is_number_integer()) return std::to_string(v.get<int64_t>());
  return v.dump();
}

// The line of a log that says what went wrong: the last one mentioning "error" (the renderer's
// "bvhlab: error: ..." or a GLSL compiler's "0:12(3): error: ..."), else the first non-empty one
// (CLI11 puts its complaint first and "Run with --help" last).
std::string summaryLine(const std::string& text) {
  std::istringstream in(text);
  std::string first, lastError;
  for (std::string line; std::getline(in, line);) {
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
    if (line.empty()) continue;
    if (first.empty()) first = line;
    std::string lower = line;
    for (char& c : lower) c = char(std::tolower(static_cast<unsigned char>(c)));
    if (lower.find("error") != std::string::npos) lastError = line;
  }
  return lastError.empty() ? first : lastError;
}

// The machine's load over a group (load average and stolen CPU time, sampled around its process) on
// every run it measured: the report warns when a busy machine widened the intervals.
void addMachineLoad(json& runs, const MachineLoad& start, const MachineLoad& end) {
  const json load = machineLoadDuring(start, end);
  for (auto& [key, entry] : runs.items()) {
    // A failed run has no result row to carry it; a deferred run ({"deferred": ...} alone) was not measured.
    if (!entry.is_object() || entry.contains("error") || entry.contains("deferred")) continue;
    for (const auto& [k, v] : load.items()) entry[k] = v;
  }
}

}  // namespace

namespace {

// `BINARY trace SCENE --json --rays W ...` for a run on the rays axis: its builder/kernel/leaf
// size/storage/robust axes as for render, rounds from [render]/[measure], the batch from [trace].
std::vector<std::string> traceCommandLine(const fs::path& binary, const RunSpec& spec, const AxisValue& scene) {
  const RunRender& r = spec.render;
  std::vector<std::string> argv = {binary.string(), "trace", scene.file.string(), "--json",
                                   "--count", std::to_string(r.traceCount), "--seed", std::to_string(r.traceSeed),
                                   "--ao-radius", number(r.aoRadius),
                                   "--frames", std::to_string(r.frames), "--warmup", std::to_string(r.warmup),
                                   "--max-frames", std::to_string(r.maxFrames),
                                   "--target-ci-pct", number(r.targetCiPct), "--backend", r.backend};
  if (r.maxSeconds > 0.0) argv.insert(argv.end(), {"--max-seconds", number(r.maxSeconds)});
  if (r.programCopies > 1) argv.insert(argv.end(), {"--program-copies", std::to_string(r.programCopies)});
  if (r.embreeThreads > 0) argv.insert(argv.end(), {"--embree-threads", std::to_string(r.embreeThreads)});
  if (r.minSampleMs >= 0.0) argv.insert(argv.end(), {"--min-sample-ms", number(r.minSampleMs)});
  if (spec.axis("update"))  // a clip: how much of it, and the update's repeats
    argv.insert(argv.end(), {"--clip-frames", std::to_string(r.clipFrames), "--clip-step", std::to_string(r.clipStep),
                             "--update-repeats", std::to_string(r.updateRepeats)});
  for (const char* key : {"eye", "target", "up"})
    if (scene.value.contains(key)) argv.insert(argv.end(), {std::string("--") + key, vec3Flag(scene.value[key])});
  if (scene.value.contains("fov")) argv.insert(argv.end(), {"--fov", number(scene.value["fov"].get<double>())});
  return argv;
}

}  // namespace

std::vector<std::string> renderCommandLine(const fs::path& binary, const RunRequest& request) {
  const RunSpec& spec = request.spec;
  const AxisValue* scene = spec.axis("scene");
  if (!scene || scene->file.empty())
    throw std::invalid_argument("run " + spec.key + " has no scene file (a generated scene not written yet?)");
  const RunRender& r = spec.render;
  // A run on the rays axis traces its workload; every other run renders frames.
  const bool trace = spec.axis("workload") != nullptr;
  std::vector<std::string> argv;
  if (trace) {
    argv = traceCommandLine(binary, spec, *scene);
  } else {
    argv = {binary.string(), "render", scene->file.string(), "--json", "-o", request.image.string(),
            "--width", std::to_string(r.width), "--height", std::to_string(r.height),
            "--frames", std::to_string(r.frames), "--warmup", std::to_string(r.warmup), "--backend", r.backend};
    if (!request.visitsImage.empty()) argv.insert(argv.end(), {"--visits-out", request.visitsImage.string()});
    for (const char* key : {"eye", "target", "up"})
      if (scene->value.contains(key)) argv.insert(argv.end(), {std::string("--") + key, vec3Flag(scene->value[key])});
    if (scene->value.contains("fov")) argv.insert(argv.end(), {"--fov", number(scene->value["fov"].get<double>())});
    if (!r.cameraPathFile.empty()) argv.insert(argv.end(), {"--camera-path", r.cameraPathFile.string()});
  }

  if (r.gpuBuilds > 0) argv.insert(argv.end(), {"--gpu-builds", std::to_string(r.gpuBuilds)});
  for (const auto& [name, value] : spec.axes) {
    const AxisInfo* axis = findAxis(name);
    if (name == "scene") continue;
    if (name == "builder") {
      argv.insert(argv.end(), {"--builder", value.value.at("name").get<std::string>()});
      if (value.value.contains("bins")) argv.insert(argv.end(), {"--bins", scalarFlag(value.value["bins"])});
      if (value.value.contains("optimize")) argv.insert(argv.end(), {"--optimize", scalarFlag(value.value["optimize"])});
      if (value.value.contains("sbvh_alpha"))
        argv.insert(argv.end(), {"--sbvh-alpha", number(value.value["sbvh_alpha"].get<double>())});
      if (value.value.contains("sbvh_budget"))
        argv.insert(argv.end(), {"--sbvh-budget", number(value.value["sbvh_budget"].get<double>())});
      if (value.value.contains("ploc_radius"))
        argv.insert(argv.end(), {"--ploc-radius", scalarFlag(value.value["ploc_radius"])});
      if (value.value.contains("ploc_top_down"))
        argv.insert(argv.end(), {"--ploc-top-down", scalarFlag(value.value["ploc_top_down"])});
      if (value.value.contains("morton_size_bits"))
        argv.insert(argv.end(), {"--morton-size-bits", scalarFlag(value.value["morton_size_bits"])});
      if (value.value.contains("morton_grid"))
        argv.insert(argv.end(), {"--morton-grid", scalarFlag(value.value["morton_grid"])});
    } else if (name == "uber") {
      if (value.value.get<bool>()) argv.push_back("--uber");
    } else {
      argv.insert(argv.end(), {std::string(axis->flag), scalarFlag(value.value)});
    }
  }
  argv.insert(argv.end(), r.args.begin(), r.args.end());
  return argv;
}

RunExecutor subprocessExecutor(fs::path binary) {
  if (binary.empty()) binary = fs::read_symlink("/proc/self/exe");
  return [binary](RunRequest& request) -> json {
    const std::vector<std::string> argv = renderCommandLine(binary, request);
    request.command = shellQuote(argv);
    ProcessOptions options;
    options.env = request.spec.render.env;
    options.timeoutSeconds = request.spec.render.timeoutSeconds;
    const ProcessResult p = runProcess(argv, options);
    request.log = p.err;

    json result;
    std::string parseError;
    try {
      result = json::parse(p.out);
    } catch (const json::parse_error& e) {
      parseError = e.what();
    }
    if (p.timedOut)
      throw RunFailure("renderer timed out after " + number(request.spec.render.timeoutSeconds) + " s", result);
    if (!p.ok()) {
      const std::string why = summaryLine(p.err);
      throw RunFailure("renderer " + p.status() + (why.empty() ? "" : ": " + why),
                       result.is_object() ? result : json());
    }
    if (!result.is_object()) {
      std::string shown = p.out.substr(0, 200);
      throw RunFailure("renderer printed no JSON object on stdout" +
                       (parseError.empty() ? std::string() : " (" + parseError + ")") +
                       (shown.empty() ? std::string(": stdout was empty") : ": " + shown));
    }
    return result;
  };
}

json measureSpec(const fs::path& binary, const GroupRequest& request) {
  if (request.runs.empty()) throw std::invalid_argument("an empty group");
  const RunRender& r = request.runs.front().spec.render;
  // Runs on the rays axis make a trace group (the runner groups them apart from rendered runs).
  const bool trace = request.runs.front().spec.axis("workload") != nullptr;
  json runs = json::array();
  for (const RunRequest& run : request.runs) {
    if ((run.spec.axis("workload") != nullptr) != trace) throw std::invalid_argument("a group mixes traced and rendered runs");
    std::vector<std::string> argv = renderCommandLine(binary, run);
    argv.erase(argv.begin(), argv.begin() + 2);  // the binary and "render" or "trace": measure takes their arguments
    runs.push_back({{"key", run.spec.key}, {"args", argv}});
  }
  json spec = {{"session", request.session},         {"min_frames", r.frames},
               {"max_frames", r.maxFrames},          {"target_ci_pct", r.targetCiPct},
               {"max_seconds", r.maxSeconds},        {"aa_control", r.aaControl},
               {"share_programs", r.sharePrograms},   {"program_copies", r.programCopies},
               {"runs", runs}};
  if (trace) spec["command"] = "trace";
  return spec;
}

GroupExecutor subprocessGroupExecutor(fs::path binary) {
  if (binary.empty()) binary = fs::read_symlink("/proc/self/exe");
  return [binary](GroupRequest& request) -> json {
    const json spec = measureSpec(binary, request);
    const fs::path file = request.workDir / ("group-" + request.session + ".json");
    writeFileAtomic(file, spec.dump(1) + "\n", false);
    const std::vector<std::string> argv = {binary.string(), "measure", file.string()};
    request.command = shellQuote(argv);
    const RunRender& r = request.runs.front().spec.render;
    ProcessOptions options;
    options.env = r.env;
    options.timeoutSeconds = r.timeoutSeconds * double(request.runs.size());
    const MachineLoad loadBefore = machineLoadNow();
    const ProcessResult p = runProcess(argv, options);
    const MachineLoad loadAfter = machineLoadNow();
    request.log = p.err;
    std::error_code ec;
    fs::remove(file, ec);

    json result;
    try {
      result = json::parse(p.out);
    } catch (const json::parse_error&) {
    }
    if (p.timedOut) throw RunFailure("measure timed out after " + number(options.timeoutSeconds) + " s");
    if (!p.ok()) {
      const std::string why = summaryLine(p.err);
      throw RunFailure("measure " + p.status() + (why.empty() ? "" : ": " + why));
    }
    if (!result.is_object() || !result.contains("runs") || !result["runs"].is_object())
      throw RunFailure("measure printed no result object" +
                       (p.out.empty() ? std::string(": stdout was empty") : ": " + p.out.substr(0, 200)));
    addMachineLoad(result["runs"], loadBefore, loadAfter);
    return result["runs"];
  };
}

GroupExecutor sequentialGroupExecutor(RunExecutor run) {
  return [run](GroupRequest& request) -> json {
    json out = json::object();
    for (RunRequest& r : request.runs) {
      try {
        const MachineLoad before = machineLoadNow();
        json result = run(r);
        if (result.is_object()) {
          json one = {{r.spec.key, result}};
          addMachineLoad(one, before, machineLoadNow());
          result = std::move(one[r.spec.key]);
        }
        if (!result.is_object()) throw RunFailure("the executor returned no JSON object");
        out[r.spec.key] = std::move(result);
      } catch (const RunFailure& f) {
        out[r.spec.key] = {{"error", f.what()}, {"result", f.partialResult}};
      } catch (const std::exception& e) {
        out[r.spec.key] = {{"error", e.what()}};
      }
    }
    return out;
  };
}

}  // namespace bvhlab
