// Trace groups: `bvhlab measure GROUP.json` with "command": "trace" times several traced runs
// (`bvhlab trace`'s arguments each) in ONE process, their rounds interleaved as `measure` interleaves
// frames: each round traces every run's batch once with its kernel, and every distinct batch once with
// Embree, in a fresh shuffled order. So round i of run A pairs with round i of run B, and two layouts,
// kernels or builders are compared directly (the findings' paired ratio), not through their ratios to
// an Embree that moved between processes (layouts-one-core.toml; the runs are in the git history of docs/layouts.md).
//
// Runs whose batches are bit for bit the same (same input, workload, count, seed, camera; same Embree
// mode and threads) share one Embree yardstick: each run's ratio_to_embree pairs its rounds with its
// yardstick's rounds of the same session. A run's JSON is `trace --json`'s object plus "session",
// "rounds", "yardstick" (the index of its yardstick: equal means the same rays) and, for the first run
// with the A/A control, aa_control_* (its kernel traced a second time by a separately compiled program).
// With program_copies K, every run is traced by K separately compiled copies of its program, each once
// a round (a run's round time is their median; `frame_ms_copies` keeps each copy's rounds, so findings
// take a comparison's interval across the copies from 6 of them, as for rendered groups).
#pragma once
#include <nlohmann/json.hpp>

#include "render/measure_command.hpp"

namespace bvhlab {

// `spec` is the group file (render/measure_command.hpp) as readGroupSpec read it; each run's "args"
// are `bvhlab trace`'s arguments. A run that cannot be set up, built,
// compiled or traced gets an "error" entry, as in `measure`.
nlohmann::json traceGroup(const GroupSpec& spec);

}  // namespace bvhlab
