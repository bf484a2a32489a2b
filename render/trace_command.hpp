// `bvhlab trace`: a ray workload (render/workloads.hpp) traced by a GLSL kernel over the
// chosen builder's tree and, in the same process with the frames interleaved, by Embree over the same
// triangles; timings with intervals, counts per ray, and the answers compared ray by ray.
#pragma once
#include <cstdint>
#include <string>

#include <CLI/CLI.hpp>

#include "render/render_cli.hpp"
#include "render/render_command.hpp"

namespace bvhlab {

struct TraceCommand {
  RenderCommand render;  // input, builder and its options, kernel, robust, storage, camera, backend, frames
  std::string rays = "primary";
  uint32_t count = 1u << 17;
  uint64_t seed = 1;
  float aoRadius = 0.1f;
  unsigned embreeThreads = 0;
  // Adaptive rounds as `measure` has them: after --frames rounds, go on until the GLSL time's 95%
  // interval is within +-targetCiPct % of its median, or maxFrames rounds, or maxSeconds.
  int maxFrames = 0;  // 0 = --frames (a fixed count)
  double targetCiPct = 0.0, maxSeconds = 0.0;  // 0 = hardware concurrency (llvmpipe uses every core too)
  // The kernel traced by this many separately compiled copies of its program (each compiled copy has
  // its own speed on llvmpipe: experiments/README.md, "One program per shader text"); from 6, the
  // ratio to Embree gets its interval across the copies.
  int programCopies = 1;
  // A timed sample lasts at least this long: a dispatch shorter than that (a GPU, where one is shorter
  // than the clocks' ramp-up and glFinish's round trip) is repeated back to back after one untimed
  // one, as many times as the warm-up's shortest time says, and the sample is their mean.
  // < 0: kAutoMinSampleMs (render/trace_run.hpp) on a GPU, 0 (one dispatch a sample) on a software renderer.
  double minSampleMs = -1.0;
};

void addTraceOptions(CLI::App& app, TraceCommand& cmd, RenderCliText& text);
// Prints one line (or the JSON object with --json). Returns the process exit code.
int runTrace(const TraceCommand& cmd);

}  // namespace bvhlab
