// `bvhlab measure GROUP.json`: times a group of renders that share a scene, a resolution and a ray
// workload in ONE process, frames interleaved round-robin (each round draws one frame of every run,
// in a fresh shuffled order), so drift of the machine (clock, other load, thermal state) hits every
// run of the group alike and frame i of run A pairs with frame i of run B. The experiment runner
// calls it once per group; a crash ends only that group.
//
// The group file (JSON):
//   {"session": "id", "min_frames": 10, "max_frames": 60, "target_ci_pct": 2.0, "max_seconds": 0,
//    "aa_control": true,
//    "runs": [{"key": "K", "args": ["scene.toml", "--json", "-o", "K.png", "--builder", "median", ...]}]}
// `args` are exactly `bvhlab render`'s arguments (parsed by the same CLI). Rounds go on until every
// run's 95% interval of the median frame time is within ±target_ci_pct % of it, or max_frames
// rounds, or (max_seconds > 0) once the rounds have taken that long; at least min_frames rounds. With aa_control, the first run is drawn a second time as an
// A/A control: its own GL program and frames, paired with the original's.
//
// "command": "trace" makes it a trace group: every run's `args` are `bvhlab trace`'s arguments
// (render/trace_group.hpp); "render" (the default) is what the rest of this comment describes.
//
// Prints one JSON object: {"session", "rounds", "stop": "target"|"max_frames"|"max_seconds"|"fixed",
// "renderer", "wall_s", "runs": {"K": render's JSON object (+ session, rounds, aa_control_* for the
// controlled run) or {"error": "...", "result": partial object}}}.
#pragma once
#include <string>

#include <nlohmann/json.hpp>

#include "render/group_spec.hpp"

namespace bvhlab {

struct MeasureCommand {
  std::string spec;  // the group file
};

// The measurement itself (the CLI prints what it returns) of a group file read by readGroupSpec
// (render/group_spec.hpp, which refuses a bad one); a run that cannot be set up, built, compiled or
// drawn gets an "error" entry instead.
nlohmann::json measureGroup(const GroupSpec& spec);

int runMeasure(const MeasureCommand& cmd);

}  // namespace bvhlab
