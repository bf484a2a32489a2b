#include "experiments/sweep_dir.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <iostream>
#include <set>
#include <sstream>

#include "datasets/scene.hpp"  // InputError
#include "experiments/sweep_checks.hpp"
#include "experiments/findings.hpp"

namespace bvhlab {

namespace fs = std::filesystem;
using nlohmann::json;

void writeFileAtomic(const fs::path& file, std::string_view contents, bool durable) {
  if (file.has_parent_path()) fs::create_directories(file.parent_path());
  static std::atomic<unsigned> counter{0};
  const fs::path tmp = file.parent_path() / ("." + file.filename().string() + ".tmp." + std::to_string(::getpid()) +
                                             "." + std::to_string(counter++));
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw std::runtime_error("cannot write " + tmp.string() + ": " + std::strerror(errno));
  size_t done = 0;
  while (done < contents.size()) {
    const ssize_t n = ::write(fd, contents.data() + done, contents.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int err = errno;
      ::close(fd);
      ::unlink(tmp.c_str());
      throw std::runtime_error("cannot write " + tmp.string() + ": " + std::strerror(err));
    }
    done += size_t(n);
  }
  if ((durable && ::fsync(fd) != 0) || ::close(fd) != 0) {
    ::unlink(tmp.c_str());
    throw std::runtime_error("cannot flush " + tmp.string() + ": " + std::strerror(errno));
  }
  if (::rename(tmp.c_str(), file.c_str()) != 0) {
    const int err = errno;
    ::unlink(tmp.c_str());
    throw std::runtime_error("cannot rename " + tmp.string() + " to " + file.string() + ": " + std::strerror(err));
  }
}

json makePlan(const ExperimentConfig& config) {
  json runs = json::array();
  for (const RunSpec& run : config.runs) runs.push_back(run.toJson());
  json plan;
  plan["format"] = 1;
  plan["experiment"] = {{"name", config.name},
                        {"description", config.description},
                        {"seed_figures", config.seedFigures},
                        {"reference", config.reference.is_null() ? json::object() : config.reference},
                        {"sweeps", config.sweepNames},
                        {"axes", config.axisLabels},
                        {"findings", {{"baseline", config.findingsBaseline}}}};
  plan["config"] = {{"file", fs::absolute(config.file).lexically_normal().string()},
                    {"hash", config.hash},
                    {"text", config.text}};
  plan["runs"] = std::move(runs);
  return plan;
}

void writePlan(const SweepDir& dir, const json& plan) { writeFileAtomic(dir.plan(), plan.dump(1) + "\n", false); }

namespace {

json readJson(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw FileError(file.string() + ": cannot open");
  json value;
  try {
    value = json::parse(in);
  } catch (const json::parse_error& e) {
    throw InputError(file.string() + ": not valid JSON (" + e.what() + ")");
  }
  checkNesting(value, file.string());  // before anything copies or prints it (recursively)
  return value;
}

}  // namespace

json readPlan(const SweepDir& dir) {
  if (!fs::exists(dir.plan()))
    throw FileError(dir.plan().string() + ": missing (is " + dir.root.string() + " the output of `bvhlab run`?)");
  json plan = readJson(dir.plan());
  checkPlan(plan, dir.plan().string());
  return plan;
}

namespace {

// Every parseable record file under runs/, with the replicate its name gives.
template <class F>
void forEachRecord(const SweepDir& dir, F f) {
  std::error_code ec;
  if (!fs::is_directory(dir.runs(), ec)) return;
  for (const fs::directory_entry& e : fs::directory_iterator(dir.runs())) {
    const fs::path p = e.path();
    if (p.extension() != ".json" || p.filename().string().front() == '.') continue;  // skip temporaries
    const std::optional<int> replicate = replicateOfStem(p.stem().string());
    if (!replicate) continue;  // not a record of ours
    try {
      json record = readJson(p);
      checkRecord(record, p.string());
      const std::string key = record["key"].get<std::string>();  // before the move below
      f(key, *replicate, std::move(record));
    } catch (const std::exception& ex) {
      std::cerr << "bvhlab: warning: ignoring " << ex.what() << " (the run will be redone)\n";
    }
  }
}

}  // namespace

std::map<std::string, json> readRecords(const SweepDir& dir) {
  std::map<std::string, json> records;
  forEachRecord(dir, [&](const std::string& key, int replicate, json record) {
    if (replicate == 0) records[key] = std::move(record);
  });
  return records;
}

ReplicateRecords readReplicateRecords(const SweepDir& dir) {
  ReplicateRecords records;
  forEachRecord(dir, [&](const std::string& key, int replicate, json record) {
    if (replicate > 0) records[key][replicate] = std::move(record);
  });
  return records;
}

const std::vector<std::string>& resultColumns() {
  static const std::vector<std::string> columns = {
      "key", "index", "status", "sweeps", "reference_only", "reference_key",
      // axes (the config's value, else what the renderer reports it used)
      "scene", "scene_file", "builder", "bins", "layout", "triangle_format", "kernel", "leaf_size", "depth", "storage", "aa", "robust",
      "branching", "view", "uber", "texture_lod", "workload", "update",
      // render settings
      "width", "height", "frames", "warmup", "backend",
      // measurements
      "frame_ms", "frame_ms_ci_low", "frame_ms_ci_high", "ci_pct", "ci_target_met", "measure_stop", "frame_ms_min",
      "frame_ms_max", "fps", "aa_control_ratio", "aa_control_ci_low", "aa_control_ci_high",
      "aa_shared_control_ratio", "aa_shared_control_ci_low", "aa_shared_control_ci_high", "session", "program",
      "replicates",
      "bvh_stack_size",
      "build_ms", "gpu_build_ms", "gpu_build_ms_ci_low", "gpu_build_ms_ci_high", "gpu_pack", "sah_cost", "epo", "tree_hash", "references", "sah_before_optimize", "optimize_ms", "nodes",
      "leaves", "bvh_depth",
      "bytes", "bytes_per_triangle", "triangles", "node_visits_per_ray", "node_visits_p95", "triangle_tests_per_ray",
      "triangle_tests_p95", "box_tests_per_ray", "box_tests_p95", "ray_cost", "mesh_rays", "effective_depth", "image_mae", "image_psnr", "image_error_note",
      "image", "visits_image",
      // trace runs (rays axis): the batch, Embree on the same rays, agreement
      "rays", "mrays_per_s", "embree_ms", "embree_mrays_per_s", "ratio_to_embree", "ratio_ci_low", "ratio_ci_high",
      "embree_threads", "hit_mismatches", "hit_ties", "dispatches_per_sample",
      // provenance
      "gl_renderer", "config_name", "config_hash", "git_commit", "hostname", "cpu", "cores", "started_at",
      "wall_s", "error"};
  return columns;
}

namespace {

// The axes the renderer reports back (render JSON key = row column).
const char* const kReportedAxes[] = {"builder", "layout", "triangle_format", "kernel", "leaf_size", "depth", "storage", "aa",
                                     "robust",  "branching", "view", "uber", "texture_lod", "workload",
                                     "update"};

json flattenRecord(const json& record) {
  json row = json::object();
  const json& spec = record.at("params");
  const json empty = json::object();
  const json& result = record.contains("result") && record["result"].is_object() ? record["result"] : empty;
  row["key"] = record["key"];
  row["index"] = spec.at("index");
  row["status"] = record["status"];
  std::string sweeps;
  for (const json& s : spec.at("sweeps")) sweeps += (sweeps.empty() ? "" : ";") + s.get<std::string>();
  row["sweeps"] = sweeps;
  row["reference_only"] = spec.at("reference_only");
  row["reference_key"] = spec.at("reference_key");

  for (const json& a : spec.at("axes")) {
    const std::string axis = a.at("axis");
    if (axis == "scene") {
      row["scene"] = a.at("label");
      // As written in the config; a generated scene names the file the runner wrote.
      row["scene_file"] = a.at("value").contains("file") ? a["value"]["file"] : a.value("file", json());
    } else if (axis == "builder") {
      row["builder"] = a.at("label");
      if (a.at("value").contains("bins")) row["bins"] = a["value"]["bins"];
    } else {
      row[axis] = a.at("value");
    }
  }
  for (const char* axis : kReportedAxes)
    if (!row.contains(axis) && result.contains(axis)) row[axis] = result[axis];

  const json& r = spec.at("render");
  for (const char* k : {"width", "height", "frames", "warmup", "backend"}) row[k] = r.at(k);
  // An interleaved group renders min_frames..max_frames rounds: the row shows how many it took.
  if (result.contains("frames") && result["frames"].is_number_integer()) row["frames"] = result["frames"];

  for (const auto& [k, v] : result.items()) {
    if (k == "image" || k == "renderer" || k == "input") continue;
    if (!row.contains(k) || row[k].is_null()) row[k] = v;
  }
  if (result.contains("frame_ms") && result["frame_ms"].is_number() && result["frame_ms"].get<double>() > 0.0)
    row["fps"] = 1000.0 / result["frame_ms"].get<double>();
  row["image"] = record.value("image", json());
  row["visits_image"] = record.value("visits_image", json());
  row["gl_renderer"] = result.value("renderer", json());
  row["config_name"] = record.value("config_name", json());
  row["config_hash"] = record.value("config_hash", json());
  row["git_commit"] = record.value("git_commit", json());
  const json& machine = record.contains("machine") ? record["machine"] : empty;
  row["hostname"] = machine.value("hostname", json());
  row["cpu"] = machine.value("cpu", json());
  row["cores"] = machine.value("cores", json());
  row["started_at"] = record.value("started_at", json());
  row["wall_s"] = record.value("wall_s", json());
  row["error"] = record.value("error", json());
  return row;
}

std::string csvField(const json& v) {
  std::string s;
  if (v.is_null()) return "";
  if (v.is_string()) s = v.get<std::string>();
  else if (v.is_boolean()) s = v.get<bool>() ? "true" : "false";
  else s = v.dump();
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string quoted = "\"";
  for (char c : s) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

void addImageError(const SweepDir& dir, json& row, const std::map<std::string, json>& records,
                   ImageErrorCache* cache) {
  row["image_mae"] = nullptr;
  row["image_psnr"] = nullptr;
  row["image_error_note"] = nullptr;
  const std::string key = row["key"], ref = row["reference_key"];
  if (ref.empty() || row["status"] != "ok") return;
  if (ref == key) {
    row["image_mae"] = 0.0;
    row["image_error_note"] = "is the reference";
    return;
  }
  auto it = records.find(ref);
  if (it == records.end() || it->second.value("status", "") != "ok") {
    row["image_error_note"] = "reference run " + ref + (it == records.end() ? " not finished" : " failed");
    return;
  }
  if (row["image"].is_null() || it->second.value("image", json()).is_null()) {
    row["image_error_note"] = "no image";
    return;
  }
  json cached;
  if (cache && cache->count({key, ref})) {
    cached = cache->at({key, ref});
  } else {
    try {
      const ImageError e = compareImages(dir.root / row["image"].get<std::string>(),
                                         dir.root / it->second["image"].get<std::string>());
      cached = {{"mae", e.meanAbsError}, {"psnr", e.psnr() ? json(*e.psnr()) : json()}, {"note", nullptr}};
      if (!e.psnr()) cached["note"] = "identical to the reference";
    } catch (const std::exception& ex) {
      cached = {{"mae", nullptr}, {"psnr", nullptr}, {"note", ex.what()}};
    }
    if (cache) (*cache)[{key, ref}] = cached;
  }
  row["image_mae"] = cached["mae"];
  row["image_psnr"] = cached["psnr"];
  row["image_error_note"] = cached["note"];
}

}  // namespace

json writeResults(const SweepDir& dir, ImageErrorCache* cache) {
  return writeResults(dir, readPlan(dir), readRecords(dir), cache, readReplicateRecords(dir));
}

json writeResults(const SweepDir& dir, const json& plan, const std::map<std::string, json>& records,
                  ImageErrorCache* cache, const ReplicateRecords& replicates) {
  std::set<std::string> planned;
  json rows = json::array();
  size_t ok = 0, failed = 0, replicateRuns = 0;
  std::set<std::string> commits, renderers, configHashes;
  std::map<std::string, json> machines;
  for (const json& run : plan["runs"]) {
    const std::string key = run.at("key");
    planned.insert(key);
    auto it = records.find(key);
    if (it == records.end()) continue;
    json record = it->second;
    record["params"] = run;  // the plan's view (index, sweeps, reference) is authoritative
    json row = flattenRecord(record);
    addImageError(dir, row, records, cache);
    // Replicates 1.. of a finished run: pooled into its row (experiments/replicates.hpp).
    std::vector<json> replicateRows;
    if (auto rep = replicates.find(key); row["status"] == "ok" && rep != replicates.end()) {
      replicateRows.push_back(row);
      replicateRows.back()["replicate"] = 0;
      for (const auto& [r, rec] : rep->second) {
        if (rec.value("status", "") != "ok") continue;
        json copy = rec;
        copy["params"] = run;
        replicateRows.push_back(flattenRecord(copy));
        replicateRows.back()["replicate"] = r;
        ++replicateRuns;
      }
    }
    poolReplicateRows(row, replicateRows);
    (row["status"] == "ok" ? ok : failed)++;
    if (row["git_commit"].is_string()) commits.insert(row["git_commit"]);
    if (row["gl_renderer"].is_string()) renderers.insert(row["gl_renderer"]);
    if (row["config_hash"].is_string()) configHashes.insert(row["config_hash"]);
    if (row["hostname"].is_string()) machines[row["hostname"]] = record.value("machine", json());
    rows.push_back(std::move(row));
  }
  size_t stale = 0;
  for (const auto& [key, record] : records) stale += planned.count(key) ? 0 : 1;

  json summary = {{"planned", planned.size()},
                  {"ok", ok},
                  {"failed", failed},
                  {"pending", planned.size() - ok - failed},
                  {"stale", stale},
                  {"replicate_runs", replicateRuns}};

  // Columns: the fixed ones, then any other scalar keys the renderer reported, sorted.
  std::vector<std::string> columns = resultColumns();
  std::set<std::string> known(columns.begin(), columns.end()), extra;
  for (const json& row : rows)
    for (const auto& [k, v] : row.items())
      if (!known.count(k) && !v.is_structured()) extra.insert(k);
  columns.insert(columns.end(), extra.begin(), extra.end());

  json machineList = json::array();
  for (auto& [host, m] : machines) machineList.push_back(m);
  json results = {{"format", 1},
                  {"experiment", plan["experiment"]},
                  {"config", {{"file", plan["config"]["file"]}, {"hash", plan["config"]["hash"]}}},
                  {"summary", summary},
                  {"provenance",
                   {{"git_commits", commits},
                    {"gl_renderers", renderers},
                    {"machines", machineList},
                    {"config_hashes", configHashes}}},
                  {"columns", columns},
                  {"rows", rows}};
  writeFileAtomic(dir.root / "results.json", results.dump(1) + "\n", false);

  std::ostringstream csv;
  for (size_t i = 0; i < columns.size(); ++i) csv << (i ? "," : "") << columns[i];
  csv << "\n";
  for (const json& row : rows) {
    for (size_t i = 0; i < columns.size(); ++i) {
      if (i) csv << ',';
      if (auto it = row.find(columns[i]); it != row.end() && !it->is_structured()) csv << csvField(*it);
    }
    csv << "\n";
  }
  writeFileAtomic(dir.root / "results.csv", csv.str(), false);
  // The comparisons the report draws, with their intervals and verdicts (experiments/findings.hpp).
  writeFileAtomic(dir.root / "findings.json",
                  computeFindings(rows, plan["experiment"].value("axes", json::object()),
                                  plan["experiment"].value("findings", json::object()).value("baseline", json::object()))
                          .dump(1) +
                      "\n",
                  false);
  return summary;
}

}  // namespace bvhlab
