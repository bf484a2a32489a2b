// The on-disk state of one sweep (layout documented in experiments/README.md):
//   DIR/plan.json            the expanded config: every run, its key and index, the config text + hash
//   DIR/runs/KEY.json        one finished run (status ok or failed), written atomically
//   DIR/runs/KEY.rR.json     the same run in replicate R >= 1 (experiments/replicates.hpp)
//   DIR/images/KEY.png       its image; DIR/images/KEY.visits.png its visit heatmap
//   DIR/results.json, .csv   one row per finished run of the plan, regenerated from the two above
//   DIR/findings.json        the comparisons the report draws (experiments/findings.hpp), derived too
//   DIR/report.html          experiments/report.py's rendering of results.json
// Only runs/ and images/ are state; everything else is derived and may be deleted.
#pragma once
#include <filesystem>
#include <map>
#include <string>
#include <string_view>
#include <utility>

#include <nlohmann/json.hpp>

#include "experiments/config.hpp"
#include "experiments/image_error.hpp"
#include "experiments/replicates.hpp"

namespace bvhlab {

struct SweepDir {
  std::filesystem::path root;

  std::filesystem::path plan() const { return root / "plan.json"; }
  std::filesystem::path runs() const { return root / "runs"; }
  std::filesystem::path images() const { return root / "images"; }
  // Replicate 0 is the run's own record and image; replicate R >= 1 gets KEY.rR.
  std::filesystem::path record(const std::string& key, int replicate = 0) const {
    return runs() / (replicateStem(key, replicate) + ".json");
  }
  std::filesystem::path image(const std::string& key, int replicate = 0) const {
    return images() / (replicateStem(key, replicate) + ".png");
  }
  std::filesystem::path visitsImage(const std::string& key, int replicate = 0) const {
    return images() / (replicateStem(key, replicate) + ".visits.png");
  }
};

// Writes a temporary file beside `file` and renames it over `file`: a reader (or a run after a
// kill) sees the old contents or the new, never a partial file. `durable` also fsyncs the data
// before the rename, so a power cut cannot leave the new name on an empty file (run records need
// it; derived files do not).
void writeFileAtomic(const std::filesystem::path& file, std::string_view contents, bool durable = true);

// plan.json: written by `run` before the first run starts.
nlohmann::json makePlan(const ExperimentConfig& config);
void writePlan(const SweepDir& dir, const nlohmann::json& plan);
nlohmann::json readPlan(const SweepDir& dir);  // throws InputError when missing or unreadable

// Finished runs by key (replicate 0). A record that cannot be parsed (a partial file from a crash on
// a file system without atomic rename) is reported on stderr and ignored: its run counts as not
// finished.
std::map<std::string, nlohmann::json> readRecords(const SweepDir& dir);
// Replicates 1.. of finished runs: key -> replicate -> record (the same rules).
using ReplicateRecords = std::map<std::string, std::map<int, nlohmann::json>>;
ReplicateRecords readReplicateRecords(const SweepDir& dir);

// Image errors are cached per (run key, reference key) within one process.
using ImageErrorCache = std::map<std::pair<std::string, std::string>, nlohmann::json>;

// Regenerates results.json, results.csv and findings.json from plan.json and runs/. Returns the summary object
// (planned, ok, failed, pending, stale; replicate_runs: ok records of replicates 1..).
nlohmann::json writeResults(const SweepDir& dir, ImageErrorCache* cache = nullptr);
// The same from a plan and records already in memory (the runner calls this after every run).
nlohmann::json writeResults(const SweepDir& dir, const nlohmann::json& plan,
                            const std::map<std::string, nlohmann::json>& records, ImageErrorCache* cache,
                            const ReplicateRecords& replicates = {});

// results.csv columns, in order (renderer keys not listed here follow, sorted).
const std::vector<std::string>& resultColumns();

}  // namespace bvhlab
