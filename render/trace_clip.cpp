#include "render/trace_clip.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>

#include <glad/gl.h>
#include <nlohmann/json.hpp>

#include "builders/epo.hpp"
#include "builders/update.hpp"
#include "datasets/animation.hpp"
#include "layout/layouts.hpp"
#include "layout/tree_hash.hpp"
#include "layout/triangle_formats.hpp"
#include "render/clip_update.hpp"
#include "render/exit_status.hpp"
#include "render/gl_context.hpp"
#include "render/ray_tracer_gl.hpp"
#include "render/trace_run.hpp"
#include "traversal/kernels.hpp"

namespace bvhlab {

namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

double medianOfResample(const std::vector<double>& v, std::mt19937_64& rng, std::vector<double>& scratch) {
  if (v.size() <= 1) return v.empty() ? 0.0 : v[0];
  std::uniform_int_distribution<size_t> pick(0, v.size() - 1);
  scratch.resize(v.size());
  for (double& x : scratch) x = v[pick(rng)];
  return medianOf(scratch);
}

}  // namespace

ClipTotal clipTotal(std::span<const ClipFrameSamples> frames, uint64_t seed) {
  ClipTotal t;
  bool anySpread = false;
  for (const ClipFrameSamples& f : frames) {
    t.updateMs += medianOf(f.update);
    t.uploadMs += medianOf(f.upload);
    t.traceMs += medianOf(f.trace);
    anySpread = anySpread || f.update.size() > 1 || f.upload.size() > 1 || f.trace.size() > 1;
  }
  t.totalMs = t.updateMs + t.uploadMs + t.traceMs;
  if (!anySpread || frames.empty()) return t;
  std::mt19937_64 rng(seed);
  std::vector<double> sums(kClipBootstrap), scratch;
  for (double& sum : sums) {
    sum = 0.0;
    for (const ClipFrameSamples& f : frames)
      sum += medianOfResample(f.update, rng, scratch) + medianOfResample(f.upload, rng, scratch) +
             medianOfResample(f.trace, rng, scratch);
  }
  std::sort(sums.begin(), sums.end());
  Interval ci;
  ci.estimate = t.totalMs;
  ci.low = sums[size_t(0.025 * (kClipBootstrap - 1))];
  ci.high = sums[size_t(0.975 * (kClipBootstrap - 1))];
  ci.coverage = 0.95;
  ci.n = frames.size();
  t.interval = ci;
  return t;
}

TraceClip::TraceClip(const TraceCommand& command) : c(command) {
  const RenderCommand& rc = c.render;
  s.workload = parseWorkload(c.rays);
  if (rc.frames < 1 || rc.warmup < 0) throw std::invalid_argument("--frames must be >= 1 and --warmup >= 0");
  s.setup = setupRender(rc);
  for (const std::string& w : s.setup.buildReview.warnings) std::cerr << "bvhlab: warning: " << w << '\n';
  plan = planClip(rc, s.setup.scene);
  packer = &findLayout(s.setup.shader.layout);
  triangleFormat = findTriangleFormat(s.setup.shader.triangles).name;
  s.tracer.kernel = s.setup.shader.kernel;
  s.tracer.storage = s.setup.shader.storage;
  s.tracer.robust = s.setup.shader.robust;
  s.tracer.anyHit = isAnyHit(s.workload);
  const UpdateSpec spec = parseUpdateSpec(rc.update);  // planClip checked it
  if (spec.name == "two-level") {
    twoLevel = std::make_unique<ClipTwoLevel>(rc, s.setup.build, packer->name, s.tracer.kernel, triangleFormat);
    s.tracer.twoLevel = true;
    cost = s.setup.build.cost;
  } else if ((gpuRebuild = ClipGpuRebuild::make(rc, s.setup.build, packer->name, triangleFormat, s.tracer.storage))) {
    cost = gpuRebuild->cost();
  } else {
    updater = std::make_unique<ClipUpdater>(rc, s.setup.build);
    cost = updater->cost();
  }
  scene = std::move(s.setup.scene);  // frame 0 as loaded; setFrame moves it on
  samples.resize(size_t(plan.count));
}

void TraceClip::step(int f, const std::string& renderer) {
  const RenderCommand& rc = c.render;
  const double minSampleMs = resolveMinSampleMs(c.minSampleMs, renderer);
  const int sceneFrame = plan.sceneFrame(f);
  if (f > 0) setFrame(scene, sceneFrame);
  // The frame's scene as a yardstick sees it (no tree: the strategy keeps that).
  auto frame = std::make_shared<PreparedScene>();
  frame->scene = scene;
  frame->soup = gatherTriangles(frame->scene);
  frame->cost = cost;
  const TriangleSoup& soup = frame->soup;
  if (soup.size() == 0) throw InputError(rc.input + ": no triangles to trace rays against");
  triangles = soup.size();
  TraceSetup fs = s;
  fs.prepared = frame;
  TraceYardstick y(c, fs);
  y.trace();  // the answers to compare with (untimed)

  // The update: every copy of the strategy once, each timed; then the pack (CPU), timed once.
  ClipFrameSamples& sm = samples[size_t(f)];
  nlohmann::json j;
  bool rebuilt = false, agree = true;
  double sah0 = 0.0, packMs = 0.0;
  PackedBvh flatPacked;
  const Bvh* tree = nullptr;
  ClipGpuRebuild::Step gpuStep;
  if (gpuRebuild) {  // built and packed on the GPU; its streams stay there (packMs 0: the pack is in update_ms)
    gpuStep = gpuRebuild->update(soup);
    sm.update = gpuStep.ms;
    rebuilt = true;
    agree = gpuStep.agree;
    sah0 = gpuStep.sah;
    tree = &gpuRebuild->frame().tree;
  } else if (!twoLevel) {
    const ClipUpdater::Step step = updater->update(soup);
    sm.update = step.ms;
    rebuilt = step.rebuilt;
    agree = step.agree;
    sah0 = step.sah;
    tree = &updater->tree();
    const auto start = Clock::now();
    flatPacked = packer->pack(*tree, soup);
    packTriangles(flatPacked, soup, triangleFormat);
    packMs = msSince(start);
  } else {
    const ClipTwoLevel::Step step = twoLevel->update(scene, sceneFrame);
    sm.update = step.ms;
    rebuilt = step.built;
    agree = step.agree;
    sah0 = step.sah;
    packMs = step.packMs;
    putTwoLevelFrame(j, step, twoLevel->first());
  }
  const PackedBvh& packed =
      twoLevel ? twoLevel->first().packed().streams : gpuRebuild ? gpuRebuild->frame().packed : flatPacked;

  // The re-upload (GL), timed with the pack as upload_ms; repeated as often as the update is.
  Clock::time_point start;
  bool recompiled = false;
  if (!gl || stackSizeFor(packed) > gl->stackSize()) {  // a deeper tree needs a longer stack: new programs
    gl = std::make_unique<GlRayTracer>(packed, s.tracer);
    recompiled = true;
  }
  std::vector<double> glUpload;
  if (gpuRebuild) {  // the triangles' upload was each build's; the tracer binds the streams the GPU made
    gl->setTreeBuffers(packed, gpuRebuild->frame().streams);
    sm.upload = gpuStep.uploadMs;
    glUpload = gpuStep.uploadMs;
  }
  for (int k = 0; k < (gpuRebuild ? 0 : rc.updateRepeats); ++k) {
    glFinish();
    start = Clock::now();
    gl->setTree(packed);
    glFinish();
    glUpload.push_back(msSince(start));
    sm.upload.push_back(packMs + glUpload.back());
  }
  gl->setRays(y.rays().rays);

  // The trace: warm-up (untimed), then --frames timed passes.
  double shortest = std::numeric_limits<double>::infinity();
  const int warm = rc.warmup + (minSampleMs > 0.0 && dispatches == 0 ? 1 : 0);
  for (int i = 0; i < warm; ++i) shortest = std::min(shortest, gl->trace());
  if (dispatches == 0) dispatches = dispatchesPerSample(minSampleMs, shortest);
  for (int i = 0; i < rc.frames; ++i) sm.trace.push_back(gl->trace(dispatches));
  std::vector<BatchHit> hits;
  std::vector<glm::uvec4> tlasCounts;
  const std::vector<glm::uvec4> counts = gl->traceCounted(&hits, &tlasCounts);
  uint64_t visits = 0, tests = 0, boxTests = 0, overflows = 0, found = 0;
  for (const glm::uvec4& k : counts) {
    visits += k.x;
    tests += k.y;
    boxTests += k.w;
    overflows += k.z != 0u;
  }
  uint64_t tlasVisits = 0, instanceTests = 0, tlasBoxTests = 0;
  for (const glm::uvec4& k : tlasCounts) {
    tlasVisits += k.x;
    instanceTests += k.y;
    tlasBoxTests += k.w;
  }
  if (twoLevel && !s.tracer.anyHit) {  // (instance, its triangle) -> the flat scene's triangle
    const std::vector<uint32_t> instances = gl->instances();
    for (size_t i = 0; i < hits.size(); ++i)
      if (hits[i].hit) hits[i].prim = twoLevel->first().flatTriangle(instances[i], hits[i].prim);
  }
  for (const BatchHit& h : hits) found += h.hit;
  const HitAgreement agreement = compareHits(hits, y.hits(), y.anyHit(), y.rays().rays);
  overflowsTotal += overflows;
  mismatchesTotal += agreement.mismatches;
  const double n = double(std::max<size_t>(1, y.rays().rays.size()));

  j["frame"] = sceneFrame;
  j["rebuilt"] = rebuilt;
  j["rotations"] = updater ? updater->rotations() : 0u;
  putClipTimes(j, "update_ms", sm.update);
  putClipTimes(j, "upload_ms", sm.upload);
  j["pack_ms"] = packMs;
  j["gl_upload_ms_all"] = glUpload;
  putClipTimes(j, "ms", sm.trace);
  if (gpuRebuild) {
    putClipTimes(j, "gpu_update_ms", gpuStep.gpuMs);
    nlohmann::json phases = nlohmann::json::object();
    for (const auto& [phase, ms] : gpuStep.phases) phases[phase] = ms;
    j["gpu_update_phases_ms"] = phases;
    gpuUpdateMsTotal += medianOf(gpuStep.gpuMs);
  }
  j["sah_cost"] = sah0;
  // EPO is a single tree's measure: a two-level frame has none.
  if (rc.epo) j["epo"] = tree ? nlohmann::json(endPointOverlap(*tree, soup.v0, soup.v1, soup.v2, cost)) : nlohmann::json();
  j["node_visits_per_ray"] = double(visits + tlasVisits) / n;
  j["triangle_tests_per_ray"] = double(tests) / n;
  j["box_tests_per_ray"] = double(boxTests + tlasBoxTests) / n;
  if (twoLevel) {
    j["tlas_node_visits_per_ray"] = double(tlasVisits) / n;
    j["blas_node_visits_per_ray"] = double(visits) / n;
    j["instance_tests_per_ray"] = double(instanceTests) / n;
  }
  j["ray_cost"] = cost.traversalCost * double(visits + tlasVisits) / n + cost.intersectionCost * double(tests) / n;
  j["rays"] = y.rays().rays.size();
  j["hits"] = found;
  j["hit_mismatches"] = agreement.mismatches;
  j["hit_ties"] = agreement.ties;
  j["stack_overflow_rays"] = overflows;
  j["tree_hash"] = packedTreeHash(packed);
  j["nodes"] = tree ? tree->nodes.size() : twoLevel->first().nodeCount();
  j["programs_compiled"] = recompiled;
  j["repeats_agree"] = agree;  // every copy of the strategy rebuilt alike and reached the same SAH
  frameList.push_back(std::move(j));
}

nlohmann::json TraceClip::result(const std::string& renderer, uint64_t& overflows) const {
  const RenderCommand& rc = c.render;
  overflows = overflowsTotal;
  const ClipTotal total = clipTotal(samples);
  nlohmann::json clip;
  clip["frames"] = plan.count;
  clip["fps"] = clipFps(scene);
  clip["scene_frames"] = plan.sceneFrames;
  clip["step"] = plan.step;
  clip["total_ms"] = total.totalMs;
  clip["total_ms_ci_low"] = total.interval ? nlohmann::json(total.interval->low) : nlohmann::json();
  clip["total_ms_ci_high"] = total.interval ? nlohmann::json(total.interval->high) : nlohmann::json();
  clip["total_ms_interval"] = "bootstrap";
  clip["update_ms_total"] = total.updateMs;
  clip["upload_ms_total"] = total.uploadMs;
  clip["trace_ms_total"] = total.traceMs;
  // With the GPU rebuild: the GL-timed builds' medians summed (update_ms_total is their wall-clock).
  clip["gpu_update_ms_total"] = gpuRebuild ? nlohmann::json(gpuUpdateMsTotal) : nlohmann::json();
  // Per traced frame: the sum of its parts' medians (what findings pair clips over: frame f with frame f).
  nlohmann::json frameTotals = nlohmann::json::array();
  for (const ClipFrameSamples& f : samples) frameTotals.push_back(medianOf(f.update) + medianOf(f.upload) + medianOf(f.trace));
  clip["frame_total_ms"] = frameTotals;
  // Per traced frame, two of its parts (findings compare them paired over frames, as the totals): the
  // update's median and the ray cost.
  nlohmann::json frameUpdates = nlohmann::json::array(), frameRayCosts = nlohmann::json::array();
  for (const ClipFrameSamples& f : samples) frameUpdates.push_back(medianOf(f.update));
  for (const nlohmann::json& f : frameList) frameRayCosts.push_back(f["ray_cost"]);
  clip["frame_update_ms"] = frameUpdates;
  clip["frame_ray_cost"] = frameRayCosts;
  clip["rebuilds"] = std::count_if(frameList.begin(), frameList.end(), [](const nlohmann::json& j) { return j["rebuilt"].get<bool>(); });
  clip["hit_mismatches"] = mismatchesTotal;
  clip["stack_overflow_rays"] = overflowsTotal;

  nlohmann::json j;
  j["input"] = rc.input;
  j["update"] = rc.update;
  j["update_repeats"] = rc.updateRepeats;
  j["workload"] = workloadName(s.workload);
  j["any_hit"] = s.tracer.anyHit;
  j["seed"] = c.seed;
  j["builder"] = rc.builder;
  j["layout"] = packer->name;
  j["triangle_format"] = triangleFormat;
  j["kernel"] = s.tracer.kernel;
  j["storage"] = storageName(s.tracer.storage);
  j["robust"] = robustnessName(s.tracer.robust);
  j["leaf_size"] = s.setup.buildReview.leafSize;
  j["warnings"] = s.setup.buildReview.warnings;
  j["triangles"] = triangles;
  j["warmup"] = rc.warmup;
  j["timed_rounds"] = rc.frames;
  j["dispatches_per_sample"] = dispatches;
  j["upload_timing"] = "glFinish + steady_clock";
  // Where the tree was updated: "gpu" (built and packed by compute passes, traced from the streams
  // they left on the GPU: render/gpu_clip_build.hpp) or "cpu" (updated, packed and uploaded).
  j["update_on"] = gpuRebuild ? "gpu" : "cpu";
  // One run's numbers as the experiment tables read them (results.csv: one row per run): the clip's
  // total as its time, and the per-frame means of the tree's SAH and ray cost.
  double sahMean = 0.0, rayCostMean = 0.0;
  for (const nlohmann::json& f : frameList) {
    sahMean += f["sah_cost"].get<double>() / double(frameList.size());
    rayCostMean += f["ray_cost"].get<double>() / double(frameList.size());
  }
  j["frame_ms"] = clip["total_ms"];
  j["frame_ms_ci_low"] = clip["total_ms_ci_low"];
  j["frame_ms_ci_high"] = clip["total_ms_ci_high"];
  j["sah_cost"] = sahMean;
  j["ray_cost"] = rayCostMean;
  j["hit_mismatches"] = mismatchesTotal;
  j["frames"] = frameList;
  j["clip"] = clip;
  j["backend"] = backendName(s.setup.backend);
  j["renderer"] = renderer;
  j["gpu"] = !isSoftwareRenderer(renderer);
  return j;
}


nlohmann::json traceClip(const TraceCommand& c, uint64_t& overflows) {
  TraceClip clip(c);
  std::unique_ptr<GlContext> ctx = createContext(clip.backend());
  for (int f = 0; f < clip.frames(); ++f) clip.step(f, ctx->renderer());
  nlohmann::json j = clip.result(ctx->renderer(), overflows);
  j["interleaved_with"] = 0;
  clip.release();
  return j;
}

std::vector<nlohmann::json> traceClipsInterleaved(std::vector<std::unique_ptr<TraceClip>>& clips,
                                                  std::vector<uint64_t>& overflows) {
  std::vector<nlohmann::json> out;
  overflows.assign(clips.size(), 0);
  if (clips.empty()) return out;
  std::unique_ptr<GlContext> ctx = createContext(clips.front()->backend());
  const std::string renderer = ctx->renderer();
  int longest = 0;
  for (const auto& clip : clips) longest = std::max(longest, clip->frames());
  std::mt19937_64 order(0x636c6970735f6f72ull);
  std::vector<size_t> slots(clips.size());
  for (int f = 0; f < longest; ++f) {
    for (size_t k = 0; k < slots.size(); ++k) slots[k] = k;
    shuffleRound(slots, order);
    for (size_t k : slots)
      if (f < clips[k]->frames()) clips[k]->step(f, renderer);
  }
  for (size_t k = 0; k < clips.size(); ++k) {
    out.push_back(clips[k]->result(renderer, overflows[k]));
    out.back()["interleaved_with"] = clips.size() - 1;
  }
  for (auto& clip : clips) clip->release();
  return out;
}

int runTraceClip(const TraceCommand& c) {
  uint64_t overflowsTotal = 0;
  const nlohmann::json j = traceClip(c, overflowsTotal);
  if (c.render.json) {
    std::cout << j.dump() << std::endl;
  } else {
    for (const nlohmann::json& f : j["frames"])
      std::printf("frame %d%s: update %.3f ms, upload %.3f ms, trace %.3f ms; SAH %.2f, ray cost %.2f\n",
                  f["frame"].get<int>(), f["rebuilt"].get<bool>() ? " (rebuilt)" : "", f["update_ms"].get<double>(),
                  f["upload_ms"].get<double>(), f["ms"].get<double>(), f["sah_cost"].get<double>(),
                  f["ray_cost"].get<double>());
    std::printf("%s, %s over %s: %d frames, %.2f ms in all (update %.2f + upload %.2f + trace %.2f)\n",
                c.render.input.c_str(), c.render.update.c_str(), c.render.builder.c_str(), j["clip"]["frames"].get<int>(),
                j["clip"]["total_ms"].get<double>(), j["clip"]["update_ms_total"].get<double>(),
                j["clip"]["upload_ms_total"].get<double>(), j["clip"]["trace_ms_total"].get<double>());
  }
  if (overflowsTotal > 0) {
    std::cerr << "bvhlab: error: traversal stack overflowed on " << overflowsTotal << " rays\n";
    return kExitFailure;
  }
  return 0;
}

}  // namespace bvhlab
