// Experiment configs: a TOML file that describes a sweep (format: experiments/README.md), parsed,
// validated up front and expanded into a deterministic list of runs, each with a stable key.
#pragma once
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

namespace bvhlab {

// One axis a config may sweep. Runs expand with the first axis varying slowest.
struct AxisInfo {
  std::string_view plural;    // key in [axes] and [[sweep]]: "leaf_sizes"
  std::string_view singular;  // key in runs, result rows, [[exclude]] and the reference: "leaf_size"
  std::string_view flag;      // `bvhlab render` flag: "--leaf-size"
};
const std::vector<AxisInfo>& experimentAxes();
const AxisInfo* findAxis(std::string_view pluralOrSingular);

// One value on one axis.
struct AxisValue {
  std::string label;     // how rows, plots and [[exclude]] name it ("bunny00", "sah-binned[bins=8]", "4")
  nlohmann::json value;  // what the run key hashes and the executor reads (scene/builder: an object)
  std::filesystem::path file;  // scene only: the resolved file (the key hashes the path as written)
};

// Settings shared by every run of a config ([render]); all but the timeout are part of the run key.
struct RunRender {
  int width = 320, height = 180;
  int warmup = 2, frames = 10;  // frames = [measure] min_frames: timed rounds before the interval is checked
  // [measure]: a group of runs (experiments/README.md) renders rounds until every run's 95% interval
  // of the median frame time is within ±targetCiPct % of it, or maxFrames rounds.
  int maxFrames = 100;
  double targetCiPct = 2.0;
  double maxSeconds = 0.0;  // > 0: a group also stops once its rounds took this long (min_frames still first)
  int groupSize = 64;     // most runs measured together by one process (memory: one tree + program each)
  bool aaControl = true;  // measure one run of each group twice (the A/A control: the noise floor)
  // Runs of a group whose shaders are one text draw with one compiled program (render/program_cache.hpp):
  // a comparison between them does not see where the JIT placed each copy's code. false: each compiles its own.
  bool sharePrograms = true;
  // Each run drawn by this many separately compiled copies of its program; from 6, findings take
  // their intervals across the copies (code placements) rather than across rounds of one program.
  int programCopies = 1;
  bool interleave = true; // false: every run is its own `bvhlab render` process (isolation, no pairing)
  std::string backend = "osmesa";
  bool heatmaps = true;                       // ask for --visits-out next to every image
  std::map<std::string, std::string> env;     // extra environment for the renderer (LP_NUM_THREADS, ...)
  std::vector<std::string> args;              // extra renderer flags, appended verbatim
  double timeoutSeconds = 600.0;              // a run past this is killed and recorded as failed
  // camera_path: frames are timed along a recorded camera path (`bvhlab render --camera-path`).
  std::string cameraPath;                     // as written in the config ("" = the scene's camera)
  std::filesystem::path cameraPathFile;       // resolved against the config's folder (not in the key)
  std::string cameraPathHash;                 // FNV-1a 64 of the file: a re-recorded path is a new run
  // [trace]: runs on the `rays` axis run `bvhlab trace` (render/workloads.hpp) with these; part of
  // the key of those runs only.
  int traceCount = 65536;  // rays per workload
  uint64_t traceSeed = 1;
  double aoRadius = 0.1;   // ao ray length, fraction of the scene's diagonal
  // Embree's threads beside the kernel (`trace --embree-threads`; 0 = every core). With llvmpipe held
  // to one thread too (env LP_NUM_THREADS = "1"), each side runs on one core: the yardstick that holds
  // on a machine whose two virtual CPUs sometimes share a physical core (docs/layouts.md).
  int embreeThreads = 0;
  // Runs on the `updates` axis (`trace --update`): frames 0, clipStep, 2 clipStep, ... of the scene's
  // clip, at most clipFrames of them (0 = all), each update timed updateRepeats times.
  int clipFrames = 0, clipStep = 1, updateRepeats = 1;
  // [render] gpu_builds: a GPU builder's runs also time this many GL-timed builds (`--gpu-builds`,
  // render/gpu_build_timing.hpp: gpu_build_ms and its interval); 0 = none.
  int gpuBuilds = 0;
  // A timed sample of a GLSL trace lasts at least this long (`trace --min-sample-ms`): shorter
  // dispatches (a GPU) are repeated back to back after one untimed one, and the sample is their mean.
  // < 0: the tracer's default (10 ms on a GPU, 0 on a software renderer).
  double minSampleMs = -1.0;

  nlohmann::json keyJson() const;
  // Runs with the same scene and equal groupJson() are timed together, frames interleaved.
  nlohmann::json groupJson() const;
};

struct RunSpec {
  std::size_t index = 0;  // position in the expansion: shards take index % N == I
  std::string key;        // 16 hex digits: FNV-1a 64 of keyJson(); stable across machines
  std::vector<std::pair<std::string, AxisValue>> axes;  // singular axis -> value, experimentAxes() order
  RunRender render;
  std::vector<std::string> sweeps;  // [[sweep]] names the run belongs to; empty for reference-only runs
  std::string referenceKey;         // run whose image is this run's reference image ("" = none)
  bool referenceOnly = false;       // added only to serve as a reference, not part of any sweep

  const AxisValue* axis(std::string_view singular) const;
  std::string describe() const;        // "bunny00 sah-binned stack-ordered leaf_size=4"
  nlohmann::json keyJson() const;      // {"axes": {singular: value}, "render": {...}}
  nlohmann::json toJson() const;       // everything, for plan.json
  static RunSpec fromJson(const nlohmann::json& j);
};

// A layout the renderer packs trees into, and the kernels that walk it (layout/layouts.hpp,
// traversal/kernels.hpp).
struct KnownLayout {
  std::string name;
  std::string defaultKernel;         // what a kernel value "default" (or no kernel axis) means with it
  std::vector<std::string> kernels;  // the kernels that walk it
};

// Names the renderer accepts, for validation. An empty list is not checked (registry not built in).
struct KnownNames {
  std::vector<std::string> builders;
  std::vector<std::string> kernels;   // every layout's
  std::vector<KnownLayout> layouts = {};  // empty: layout names and layout/kernel pairs are not checked
  std::string defaultLayout = "v1";   // the layout of a run that does not sweep `layouts`
  std::vector<std::string> triangleFormats = {};  // empty: not checked
  // Triangle format -> the robustness variants it cannot run (precomputed: those with the watertight
  // triangle test); such pairs are not part of a product.
  std::map<std::string, std::vector<std::string>> triangleFormatRefuses = {};
  std::string defaultRobust = "watertight";  // the variant of a run that does not sweep `robust`
  const KnownLayout* findLayout(const std::string& name) const;
};
KnownNames registeredNames();  // from bvhlab::builders(), layouts() and the kernel registry when present

// [experiment] replicates: at most this many passes over a sweep.
constexpr int kMaxReplicates = 1000;

struct ExperimentConfig {
  std::filesystem::path file;
  std::string text;  // the file as read
  std::string hash;  // FNV-1a 64 of text, 16 hex digits
  std::string name, description;
  bool seedFigures = false;       // report adds sections mirroring the seed report's Figs. 8-12
  int replicates = 1;             // [experiment] replicates: the sweep is measured this many times over
                                  // (each pass a new child process per group; experiments/replicates.hpp)
  RunRender render;
  nlohmann::json reference;       // [experiment.reference] as written: singular axis -> value, frames, warmup
  std::vector<std::string> sweepNames;
  std::map<std::string, std::vector<std::string>> axisLabels;  // singular -> labels in config order
  std::vector<RunSpec> runs;      // sweep runs, then reference-only runs; runs[i].index == i
  // [findings] baseline = { builder = "sah-binned", ... }: singular axis -> the label findings compare
  // every other value of that axis with (experiments/findings.hpp); axes not named take their first value.
  std::map<std::string, std::string> findingsBaseline;
};

// Throws InputError "FILE:LINE: KEY: what is wrong" for every problem found in the file.
ExperimentConfig parseExperimentConfig(std::string_view text, const std::filesystem::path& file,
                                       const KnownNames& names);
ExperimentConfig loadExperimentConfig(const std::filesystem::path& file, const KnownNames& names);
ExperimentConfig loadExperimentConfig(const std::filesystem::path& file);  // registeredNames()

// FNV-1a 64-bit hash as 16 lower-case hex digits (stable across platforms and runs).
std::string hashHex(std::string_view bytes);

}  // namespace bvhlab
