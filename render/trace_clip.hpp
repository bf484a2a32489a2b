// `bvhlab trace --update SPEC` on an animated scene (datasets/animation.hpp): the clip traced frame
// by frame, the tree kept up to date by an update strategy (builders/update.hpp).
//
// Per frame f, in order: the scene set to f; its triangles gathered; the tree updated by the strategy
// (timed on the CPU: update_ms); packed into the run's layout and triangle format and re-uploaded
// (upload_ms: the pack on the CPU plus the buffer re-upload, bracketed by glFinish and timed by
// steady_clock — the re-upload deletes and recreates immutable buffers, which a GL_TIME_ELAPSED
// query would not bracket whole on every driver); then the frame's ray batch traced --warmup times
// untimed and --frames times timed (ms: their median with its 95% interval, as a static trace's ms),
// and once more with the counters (ray_cost, node_visits_per_ray, triangle_tests_per_ray).
//
// The frame's rays come from that frame's scene: Embree (robust mode) over the frame's triangles
// generates the workload as a static trace does, and its answers are compared with the kernel's
// (hit_mismatches). Ray generation and the Embree build are not timed.
//
// --update-repeats N: N copies of the strategy run side by side over the clip; each copy's update of
// frame f starts from its own state after frame f - 1 (the same state for a deterministic strategy),
// so the N times are N measurements of the same update. Copy 0's tree is the one traced.
//
// --update two-level[:...] (layout/two_level_update.hpp): the two-level tree is updated instead (its
// BLASes per the policy, the TLAS rebuilt), update_ms = its BLAS and TLAS parts (blas_update_ms,
// tlas_update_ms), upload_ms = the BLAS pack (when a BLAS changed) plus the re-upload of every stream,
// traced by the kernel's two-level walk (v1 and bvh2-cb layouts, raw triangles). Hits are mapped back
// to the flat scene's triangles for the comparison with Embree; node_visits_per_ray counts TLAS and
// BLAS visits together, tlas_node_visits_per_ray and blas_node_visits_per_ray apart.
//
// --update rebuild with a GPU builder (lbvh-gpu, ploc-gpu) into layout v1 or bvh2-cb with raw triangles
// and --storage tbo or ssbo (render/gpu_clip_build.hpp; "update_on": "gpu"): each build uploads the
// frame's triangles to the GPU (upload_ms) and builds and packs the tree there (update_ms: wall-clock
// from its first buffer allocation to its last pass done; gpu_update_ms: the same passes by GL
// timestamps, gpu_update_phases_ms per phase), and the tracer binds the streams the passes left on the
// GPU. Nothing is packed or re-uploaded on the CPU (pack_ms 0). The tree and its streams are downloaded
// untimed for the frame's SAH, tree_hash and stack depth. Elsewhere ("update_on": "cpu") a GPU
// builder's tree is downloaded, packed and uploaded as every builder's.
//
// The clip's total_ms is the sum over frames of the medians of update_ms, upload_ms and ms; its
// interval is a bootstrap (kClipBootstrap resamples, fixed seed): every frame's samples of each part
// are resampled independently, the medians summed, and the 2.5% and 97.5% quantiles of the sums
// taken. Summing per-frame intervals instead would state a coverage nobody can vouch for (the union
// bound over dozens of frames gives none).
#pragma once
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <span>
#include <vector>

#include <nlohmann/json.hpp>

#include "layout/layouts.hpp"
#include "layout/two_level_update.hpp"
#include "render/clip_update.hpp"
#include "render/gl_context.hpp"
#include "render/frame_stats.hpp"
#include "render/ray_tracer_gl.hpp"
#include "render/trace_command.hpp"
#include "render/trace_run.hpp"

namespace bvhlab {

// One frame's timed samples, per part (ms).
struct ClipFrameSamples {
  std::vector<double> update, upload, trace;
};

constexpr int kClipBootstrap = 2000;  // resamples: the quantiles' Monte Carlo error ~1% of the interval

// The clip's total: sum over frames of the parts' medians, with its bootstrap interval (nullopt when
// every part of every frame has a single sample: nothing to resample).
struct ClipTotal {
  double totalMs = 0.0, updateMs = 0.0, uploadMs = 0.0, traceMs = 0.0;
  std::optional<Interval> interval;
};
ClipTotal clipTotal(std::span<const ClipFrameSamples> frames, uint64_t seed = 0x636c6970u);

// One clip run, a frame at a time: set up on the CPU at construction (the scene loaded, the spec
// and the clip checked; throws as runTraceClip), then step(f) for f in [0, frames()) in order with a
// GL context current (the same one for every step), then result().
class TraceClip {
 public:
  explicit TraceClip(const TraceCommand& c);
  int frames() const { return plan.count; }
  const TraceCommand& command() const { return c; }
  Backend backend() const { return s.setup.backend; }
  // The clip's f-th frame: update, pack + upload, warm-up and timed traces, the counted pass.
  // renderer: the current context's (it sets the sample length, resolveMinSampleMs).
  void step(int f, const std::string& renderer);
  // The object `trace --json --update` prints; `overflows` as traceClip's.
  nlohmann::json result(const std::string& renderer, uint64_t& overflows) const;
  // Frees the GL objects (before the context goes).
  void release() {
    gl.reset();
    gpuRebuild.reset();
  }

 private:
  TraceCommand c;
  TraceSetup s;
  ClipPlan plan;
  std::unique_ptr<ClipUpdater> updater;
  // `--update two-level...`: one updater per --update-repeats copy (copy 0's tree is traced) instead
  // of `updater`.
  std::unique_ptr<ClipTwoLevel> twoLevel;  // with --update two-level[:...] (else updater)
  // `--update rebuild` with a GPU builder packing the layout on the GPU (else updater).
  std::unique_ptr<ClipGpuRebuild> gpuRebuild;
  double gpuUpdateMsTotal = 0.0;  // the GL-timed builds, per frame's median, summed
  const LayoutInfo* packer = nullptr;
  std::string triangleFormat;
  CostModel cost;
  Scene scene;
  std::unique_ptr<GlRayTracer> gl;
  int dispatches = 0;  // set from frame 0's warm-up
  std::vector<ClipFrameSamples> samples;
  nlohmann::json frameList = nlohmann::json::array();
  uint64_t overflowsTotal = 0, mismatchesTotal = 0;
  size_t triangles = 0;
};

// Several clips stepped in lockstep in one GL context (`measure` groups of clip runs): frame f of
// every clip, in an order drawn per frame (fixed seed), before frame f + 1 of any, so load that drifts
// over the run reaches every clip's frame f alike and per-frame times pair up across clips. Clips of
// different lengths step while they have frames. Returns each clip's result (as traceClip's) with
// "interleaved_with": the number of other clips stepped beside it; `overflows` per clip.
std::vector<nlohmann::json> traceClipsInterleaved(std::vector<std::unique_ptr<TraceClip>>& clips,
                                                  std::vector<uint64_t>& overflows);

// Runs the clip (c.update set) in a GL context of its own and returns the object `trace --json
// --update` prints; `overflows`: rays whose traversal stack overflowed, over every frame (the caller
// fails the run on any). Throws as runTraceClip.
nlohmann::json traceClip(const TraceCommand& c, uint64_t& overflows);
// Runs the clip (c.update set) and prints it. Returns the process exit code; throws std::invalid_argument (exit 2)
// for a bad spec (naming --update) and for a scene without a clip of more than one frame.
int runTraceClip(const TraceCommand& c);

}  // namespace bvhlab
