#include "render/trace_command.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <limits>
#include <memory>
#include <random>
#include <vector>

#include <nlohmann/json.hpp>

#include "render/exit_status.hpp"
#include "render/frame_stats.hpp"
#include "render/gl_context.hpp"
#include "render/ray_tracer_gl.hpp"
#include "render/trace_clip.hpp"
#include "render/trace_run.hpp"

namespace bvhlab {

void addTraceOptions(CLI::App& app, TraceCommand& c, RenderCliText& text) {
  RenderCommand& rc = c.render;
  rc.frames = 11;  // enough rounds for a 95% interval of the paired ratio (>= 6)
  app.option_defaults()->always_capture_default();
  app.add_option("input", rc.input, "scene .toml or mesh file")
      ->required()
      ->check(notADirectory("a scene .toml or a mesh file (OBJ/OFF/PLY/STL)"));
  app.add_option("--rays", c.rays, "workload: primary | shadow | specular | diffuse | ao");
  app.add_option("--count", c.count, "rays (secondary workloads: one per primary hit chosen)");
  app.add_option("--seed", c.seed, "seed of the secondary rays' random numbers");
  app.add_option("--ao-radius", c.aoRadius, "ao ray length, as a fraction of the scene's diagonal");
  app.add_flag("--json", rc.json, "print one JSON object");
  app.add_option("--frames", rc.frames, "timed rounds (one GLSL and one Embree trace each, in a shuffled order)");
  app.add_option("--warmup", rc.warmup, "untimed rounds first (llvmpipe compiles at the first dispatch)");
  app.add_option("--backend", rc.backend, "osmesa | egl");
  addTreeOptions(app, rc);
  app.add_option("--robust", rc.robust,
                 "triangle/box tests as render --robust (the offset is the generator's); Embree runs in robust mode with watertight triangles, in its default mode with fast ones");
  app.add_option("--max-frames", c.maxFrames, "go on past --frames until --target-ci-pct is met, up to this many (0 = fixed)");
  app.add_option("--target-ci-pct", c.targetCiPct, "stop when the GLSL time's 95% interval is within +-this % of its median");
  app.add_option("--max-seconds", c.maxSeconds, "stop the rounds after this long (0 = no limit)");
  app.add_option("--embree-threads", c.embreeThreads, "Embree's threads (0 = every core)");
  app.add_option("--program-copies", c.programCopies,
                 "trace with this many separately compiled copies of the kernel's program, each once per round; "
                 "from 6 the ratio to Embree's interval spans them")
      ->check(CLI::Range(1, 64));
  app.add_option("--min-sample-ms", c.minSampleMs,
                 "a timed sample lasts at least this long: shorter dispatches (a GPU) are repeated back to back after an "
                 "untimed one and averaged (-1 = 10 ms on a GPU, 0 on a software renderer)")
      ->check(CLI::Range(-1.0, 10000.0));
  addClipOptions(app, rc);
  app.add_flag("--epo", rc.epo, "with --update: each frame's EPO (a pass over the tree per frame)");
  app.add_option("--eye", text.eye, "camera position x,y,z");
  app.add_option("--target", text.target, "camera target x,y,z");
  app.add_option("--up", text.up, "camera up x,y,z");
  app.add_option("--fov", rc.fov, "vertical field of view in degrees");
}

TraceCommand parseTraceArgs(const std::vector<std::string>& args) {
  CLI::App app{"trace"};
  TraceCommand tc;
  RenderCliText text;
  addTraceOptions(app, tc, text);
  std::vector<std::string> reversed(args.rbegin(), args.rend());  // CLI11 parses a vector back to front
  try {
    app.parse(reversed);
  } catch (const CLI::ParseError& e) {
    throw std::invalid_argument(std::string("trace arguments: ") + e.what());
  }
  applyRenderCliText(tc.render, text);
  return tc;
}

int runTrace(const TraceCommand& c) {
  if (!c.render.update.empty()) return runTraceClip(c);
  const RenderCommand& rc = c.render;
  const TraceSetup s = setupTrace(c);
  for (const std::string& w : s.setup.buildReview.warnings) std::cerr << "bvhlab: warning: " << w << '\n';
  TraceYardstick y(c, s);

  std::unique_ptr<GlContext> ctx = createContext(s.setup.backend);
  // Copy 0 gives the hits and the counts; every copy is timed.
  std::vector<std::unique_ptr<GlRayTracer>> copies;
  for (int k = 0; k < c.programCopies; ++k) {
    copies.push_back(std::make_unique<GlRayTracer>(s.prepared->packed, s.tracer));
    copies.back()->setRays(y.rays().rays);
  }
  // The warm-up's shortest dispatch sets how many make a timed sample (--min-sample-ms); with a sample
  // length asked for, one more untimed pass after the warm-up (the first pass may hold a JIT compile).
  const double minSampleMs = resolveMinSampleMs(c.minSampleMs, ctx->renderer());
  double shortest = std::numeric_limits<double>::infinity();
  for (int i = 0; i < rc.warmup + (minSampleMs > 0.0 ? 1 : 0); ++i) {
    for (auto& copy : copies) shortest = std::min(shortest, copy->trace());
    if (i < rc.warmup) y.trace();
  }
  const int dispatches = dispatchesPerSample(minSampleMs, shortest);
  // Rounds: one trace of each copy and of Embree, in an order drawn per round (fixed seed), so drift
  // hits them alike and round i's times pair up.
  TraceRounds r;
  r.warmup = rc.warmup;
  r.targetCiPct = c.targetCiPct;
  r.minSampleMs = minSampleMs;
  r.dispatches = dispatches;
  if (copies.size() > 1) r.copyMs.resize(copies.size());
  std::mt19937_64 order(0x7261795f74726163ull);
  const int maxFrames = std::max(rc.frames, c.maxFrames);
  const auto started = std::chrono::steady_clock::now();
  r.stop = maxFrames > rc.frames ? "max_frames" : "fixed";
  for (int i = 0; i < maxFrames; ++i) {
    if (i >= rc.frames) {
      const auto ci = medianInterval(r.glMs);
      if (c.targetCiPct > 0.0 && ci && ci->estimate > 0.0 && 50.0 * (ci->high - ci->low) / ci->estimate <= c.targetCiPct) {
        r.stop = "target";
        break;
      }
      if (c.maxSeconds > 0.0 &&
          std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count() >= c.maxSeconds) {
        r.stop = "max_seconds";
        break;
      }
    }
    // Every copy and Embree once, in a shuffled order; the round's GLSL time is the median over the
    // copies (one copy: its time).
    std::vector<size_t> slots(copies.size() + 1);  // slot copies.size() is Embree
    for (size_t k = 0; k < slots.size(); ++k) slots[k] = k;
    shuffleRound(slots, order);
    std::vector<double> round;
    for (size_t slot : slots) {
      if (slot == copies.size()) {
        r.embreeMs.push_back(y.trace());
      } else {
        round.push_back(copies[slot]->trace(dispatches));
        if (copies.size() > 1) r.copyMs[slot].push_back(round.back());
      }
    }
    r.glMs.push_back(medianOf(round));
  }
  uint64_t overflows = 0;
  const nlohmann::json j = traceResult(c, s, y, *copies.front(), r, ctx->renderer(), overflows);
  if (rc.json) {
    std::cout << j.dump() << std::endl;
  } else {
    if (dispatches > 1)  // the time below is a mean per dispatch
      std::printf("(%d dispatches a timed sample, >= %.3g ms)\n", dispatches, minSampleMs);
    std::printf("%s: %zu %s rays, %s on %s over %s (leaf %u): %.2f ms (%.1f Mrays/s), Embree %.2f ms (%.1f Mrays/s, %u threads): "
                "%.2fx Embree's time; %.1f node visits + %.1f triangle tests per ray; %llu hit mismatches, %llu ties\n",
                rc.input.c_str(), y.rays().rays.size(), workloadName(s.workload), s.tracer.kernel.c_str(),
                s.prepared->packed.layout.c_str(), rc.builder.c_str(), s.setup.buildReview.leafSize, j["ms"].get<double>(),
                j["mrays_per_s"].get<double>(), j["embree_ms"].get<double>(), j["embree_mrays_per_s"].get<double>(),
                y.embree().threads(), j["ratio_to_embree"].get<double>(), j["node_visits_per_ray"].get<double>(),
                j["triangle_tests_per_ray"].get<double>(), (unsigned long long)j["hit_mismatches"].get<uint64_t>(),
                (unsigned long long)j["hit_ties"].get<uint64_t>());
    std::printf("bytes fetched per ray (C++ mirror, %zu rays): %.0f node + %.0f triangle + %.0f stack\n",
                j["bytes_rays"].get<size_t>(), j["node_bytes_per_ray"].get<double>(),
                j["triangle_bytes_per_ray"].get<double>(), j["stack_bytes_per_ray"].get<double>());
  }
  if (overflows > 0) {
    std::cerr << "bvhlab: error: traversal stack overflowed on " << overflows << " rays\n";
    return kExitFailure;  // a runtime failure: the counts are wrong
  }
  return 0;
}

}  // namespace bvhlab
