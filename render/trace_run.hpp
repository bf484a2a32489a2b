// The parts of one traced run (render/trace_command.hpp), shared by `bvhlab trace` and by trace groups
// (`bvhlab measure` with "command": "trace", render/trace_group.hpp): the run set up and its tree
// built; its ray batch and the Embree yardstick over the same triangles; and the JSON object that
// `trace --json` prints, made from the run's timed rounds.
#pragma once
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "render/prepared_scene.hpp"
#include "render/ray_tracer_gl.hpp"
#include "render/render_job.hpp"
#include "render/trace_command.hpp"
#include "render/workloads.hpp"
#include "traversal/embree_tracer.hpp"

namespace bvhlab {

// `bvhlab trace`'s arguments (without "trace"), parsed by its own CLI; throws std::invalid_argument.
TraceCommand parseTraceArgs(const std::vector<std::string>& args);

// A run checked (bad workload names and round counts fail first), its scene loaded (or `loaded`
// reused) and its tree built and packed, or taken from `trees` (keyed by treeKey(), filled here).
struct TraceSetup {
  RenderSetup setup;  // its scene moved into `prepared`
  std::shared_ptr<const PreparedScene> prepared;
  Workload workload = Workload::Primary;
  RayTracerOptions tracer;  // kernel, storage, robustness, any hit
};
TraceSetup setupTrace(const TraceCommand& c, const Scene* loaded = nullptr,
                      std::map<std::string, std::shared_ptr<const PreparedScene>>* trees = nullptr);

// The run's ray batch and the yardstick that traces it. The workload's secondary rays start from
// Embree's robust-mode hits whatever --robust says, so every setting traces the same rays; the
// yardstick then runs Embree in the mode that matches the kernel's triangle test (robust against
// watertight, its default test against the fast one: each costs its tracer about the same,
// docs/layouts.md), a second scene only when they differ.
class TraceYardstick {
 public:
  TraceYardstick(const TraceCommand& c, const TraceSetup& s);
  // Everything the batch and its tracer follow from, without building anything: the triangles'
  // positions (hashed), the scene's camera and lights, the workload request, any-hit, the Embree mode
  // and threads. The generator is deterministic, so two runs with equal keys get the same batch bit
  // for bit, and a trace group gives the second the first's yardstick instead of building another
  // Embree scene (seconds at 10M triangles). Unequal keys may still give the same rays (a seed that
  // primary rays ignore): sameAs() decides those after construction.
  static std::string key(const TraceCommand& c, const TraceSetup& s);
  const RayWorkload& rays() const { return rays_; }
  const EmbreeTracer& embree() const { return matching_ ? *matching_ : *generator_; }
  bool anyHit() const { return anyHit_; }
  // One timed pass over the batch (ms); its answers in hits().
  double trace();
  const std::vector<BatchHit>& hits() const { return hits_; }
  // Traces exactly what `other` traces: the same triangles, rays, any-hit mode, Embree mode and threads.
  bool sameAs(const TraceYardstick& other) const;

 private:
  std::unique_ptr<EmbreeTracer> generator_;
  std::optional<EmbreeTracer> matching_;
  RayWorkload rays_;
  bool anyHit_ = false;
  size_t triangles_ = 0;
  std::string input_;
  std::vector<BatchHit> hits_;
};

// Two tracers' answers to the same rays, ray by ray (closest hits on different triangles at the same
// distance, within tieTolerance, are ties; any-hit answers compare hit or miss only).
struct HitAgreement {
  uint64_t mismatches = 0;  // hit vs miss, or different triangles at different distances
  uint64_t ties = 0;        // different triangles at the same distance
  uint64_t hitMiss = 0;     // of the mismatches: one found a hit, the other none
};
// `rays`: the rays both answered (std::invalid_argument when the three lengths differ).
HitAgreement compareHits(const std::vector<BatchHit>& a, const std::vector<BatchHit>& b, bool anyHit,
                         const std::vector<BatchRay>& rays);
// How far apart two closest hits' distances along `ray` may be and still be a tie: 2^-16 of t, or 16
// ulps (float) of the coordinates' magnitude along the ray, whichever is larger (render/trace_run.cpp).
double tieTolerance(const BatchRay& ray, double ta, double tb);

// The default sample length on a GPU: 10 ms is 20 dispatches of the bunny's 1M primary rays on an
// H200 (0.4-0.5 ms each), so the untimed leading dispatch and the one glFinish are small beside it.
constexpr double kAutoMinSampleMs = 10.0;
// The sample length a run uses: `requested` when >= 0, else the default for the renderer.
double resolveMinSampleMs(double requested, const std::string& renderer);
// Dispatches per timed sample for a sample of at least `minSampleMs` when one takes `shortestMs`
// (the warm-up's shortest); 1 when minSampleMs is 0 or a dispatch is already that long; at most 1000.
int dispatchesPerSample(double minSampleMs, double shortestMs);

// What a run measured: round i gave glMs[i] (with program copies, the median over them; each copy's
// own in copyMs) and, for its yardstick, embreeMs[i].
struct TraceRounds {
  std::vector<double> glMs, embreeMs;
  std::vector<std::vector<double>> copyMs;  // empty with one copy
  std::string stop = "fixed";               // fixed | target | max_frames | max_seconds
  double targetCiPct = 0.0;                 // 0: none
  int warmup = 0;
  double minSampleMs = 0.0;  // the sample length used (resolved: no -1 here)
  int dispatches = 1;        // dispatches per timed sample; glMs are per dispatch
};

// Bytes fetched per ray (node, triangle, stack: glsl::Counters), counted by the C++ mirror of
// `kernel` ("" = the layout's default) over every stride-th ray of `rays`, the stride the smallest
// that keeps the sample at most maxRays (0: every ray). sum and sumSq per kind, in that order.
struct BytesFetched {
  size_t rays = 0, stride = 1;
  double sum[3] = {0.0, 0.0, 0.0}, sumSq[3] = {0.0, 0.0, 0.0};
};
BytesFetched mirrorBytesFetched(const PackedBvh& packed, const std::string& kernel, Robustness robust, bool anyHit,
                                const std::vector<BatchRay>& rays, size_t maxRays);
// The most rays trace's mirror pass counts bytes over (a strided sample past it): a fraction of a
// second on one core for the bunny's diffuse rays (test_bytes_fetched traces 50,000 through two
// mirrors), and per-ray means whose intervals are far narrower than the differences between layouts.
constexpr size_t kBytesMirrorRays = size_t(1) << 16;

// The object `trace --json` prints. Traces once more with the counters (`gl` must be copy 0, whose
// last timed pass gave the answers compared with the yardstick's). `overflows`: rays whose stack
// overflowed (the caller fails the run on any).
nlohmann::json traceResult(const TraceCommand& c, const TraceSetup& s, const TraceYardstick& y, GlRayTracer& gl,
                           const TraceRounds& rounds, const std::string& renderer, uint64_t& overflows);

}  // namespace bvhlab
