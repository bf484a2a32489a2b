#include "render/render_clip.hpp"

#include <chrono>
#include <cstdio>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <glad/gl.h>

#include "datasets/animation.hpp"
#include "layout/layouts.hpp"
#include "layout/triangle_formats.hpp"
#include "render/clip_update.hpp"
#include "render/exit_status.hpp"
#include "render/frame_stats.hpp"
#include "render/program_cache.hpp"
#include "render/render_job.hpp"
#include "render/trace_clip.hpp"
#include "traversal/kernels.hpp"

namespace bvhlab {

namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

}  // namespace

nlohmann::json renderClip(const RenderCommand& cmd, uint64_t& overflows) {
  if (cmd.cpu) throw std::invalid_argument("--update: renders with GL (not with --cpu)");
  if (!cmd.cameraPath.empty()) throw std::invalid_argument("--update: the clip moves the camera; drop --camera-path");
  if (cmd.frames < 1 || cmd.warmup < 0) throw std::invalid_argument("--frames must be >= 1 and --warmup >= 0");
  RenderSetup setup = setupRender(cmd);
  for (const std::string& w : setup.buildReview.warnings) std::cerr << "bvhlab: warning: " << w << '\n';
  const ClipPlan plan = planClip(cmd, setup.scene);
  const LayoutInfo& packer = findLayout(setup.shader.layout);
  const std::string triangleFormat = findTriangleFormat(setup.shader.triangles).name;
  // Made before the strategy, so that a GPU rebuild's buffers go before the context does.
  std::unique_ptr<GlContext> ctx = createContext(setup.backend);
  // The strategy: a flat tree's copies, or a two-level tree's drawn by the kernel's two-level walk.
  std::unique_ptr<ClipUpdater> updater;
  std::unique_ptr<ClipTwoLevel> twoLevel;
  std::unique_ptr<ClipGpuRebuild> gpuRebuild;  // rebuild with a GPU builder: built, packed and drawn on the GPU
  if (parseUpdateSpec(cmd.update).name == "two-level") {
    twoLevel = std::make_unique<ClipTwoLevel>(cmd, setup.build, packer.name, setup.shader.kernel, triangleFormat);
    setup.shader.twoLevel = true;
  } else if ((gpuRebuild = ClipGpuRebuild::make(cmd, setup.build, packer.name, triangleFormat, setup.shader.storage))) {
  } else {
    updater = std::make_unique<ClipUpdater>(cmd, setup.build);
  }
  const CostModel cost = setup.build.cost;
  Scene scene = std::move(setup.scene);

  const std::string renderer = ctx->renderer();
  auto programs = std::make_unique<ProgramCache>();
  int stack = 0;
  overflows = 0;
  std::vector<ClipFrameSamples> samples(static_cast<size_t>(plan.count));
  nlohmann::json frameList = nlohmann::json::array();
  nlohmann::json last;
  for (int f = 0; f < plan.count; ++f) {
    const int sceneFrame = plan.sceneFrame(f);
    if (f > 0) setFrame(scene, sceneFrame);
    auto frame = std::make_shared<PreparedScene>();
    frame->scene = scene;
    frame->data = buildSceneData(frame->scene);
    frame->soup = gatherTriangles(frame->scene);
    frame->cost = cost;
    if (frame->soup.size() == 0) throw InputError(cmd.input + ": --update needs triangles (a mesh object)");
    ClipFrameSamples& sm = samples[size_t(f)];
    nlohmann::json parts;  // a two-level frame's own keys
    bool rebuilt = false, agree = true;
    double packMs = 0.0;
    ClipGpuRebuild::Step gpuStep;
    if (gpuRebuild) {  // the renderer binds the streams the passes left on the GPU; upload_ms is the triangles'
      gpuStep = gpuRebuild->update(frame->soup);
      sm.update = gpuStep.ms;
      rebuilt = true;
      agree = gpuStep.agree;
      const GpuClipFrame& built = gpuRebuild->frame();
      setClipFrameTree(*frame, built.tree, built.packed, cmd.builder);
      for (int k = 0; k < 3; ++k) frame->gpuStreams[size_t(k)] = built.streams[k];
    } else if (!twoLevel) {
      const ClipUpdater::Step step = updater->update(frame->soup);
      sm.update = step.ms;
      rebuilt = step.rebuilt;
      agree = step.agree;
      packMs = packClipFrame(*frame, updater->tree(), packer, triangleFormat, cmd.builder);
    } else {
      const ClipTwoLevel::Step step = twoLevel->update(frame->scene, sceneFrame);
      sm.update = step.ms;
      rebuilt = step.built;
      agree = step.agree;
      packMs = step.packMs;
      frame->packed = twoLevel->first().packed().streams;  // frame->bvh stays empty: no single tree
      frame->stats = twoLevelStats(twoLevel->first(), cmd.builder);
      putTwoLevelFrame(parts, step, twoLevel->first());
    }
    stack = std::max(stack, stackSizeFor(frame->packed));
    const size_t cached = programs->size();
    glFinish();
    const auto start = Clock::now();
    GpuJob job(cmd, setup, frame, programs.get(), stack);
    glFinish();
    // The renderer's upload (scene, textures; the tree's streams unless they are on the GPU), plus the pack
    // on the CPU or, on the GPU path, each build's upload of the triangles.
    const double rendererMs = msSince(start);
    if (gpuRebuild)
      for (double ms : gpuStep.uploadMs) sm.upload.push_back(ms + rendererMs);
    else
      sm.upload.push_back(packMs + rendererMs);
    const bool compiled = programs->size() > cached;

    FrameTimes times;
    double aaMs = 0.0;
    for (int i = 0; i < cmd.warmup; ++i) job.frame(i, aaMs);
    for (int i = 0; i < cmd.frames; ++i) {
      times.ms.push_back(job.frame(i, aaMs));
      if (setup.smaaOn) times.aaMs.push_back(aaMs);
    }
    sm.trace = times.ms;
    job.finish(true);
    overflows += stackOverflowPixels(job.stats);
    RenderCommand frameCmd = cmd;  // the image of the last frame only; no heatmaps
    if (f + 1 < plan.count) frameCmd.output.clear();
    frameCmd.visitsOutput.clear();
    const nlohmann::json r = finishRender(frameCmd, setup, *frame, job.frameOptions(), std::move(job.image), job.stats,
                                          job.boxTests, times, renderer, false);
    nlohmann::json j = std::move(parts);
    j["frame"] = sceneFrame;
    j["rebuilt"] = rebuilt;
    j["rotations"] = updater ? updater->rotations() : 0u;
    putClipTimes(j, "update_ms", sm.update);
    putClipTimes(j, "upload_ms", sm.upload);
    j["pack_ms"] = packMs;
    putClipTimes(j, "ms", sm.trace);
    if (gpuRebuild) {
      putClipTimes(j, "gpu_update_ms", gpuStep.gpuMs);
      nlohmann::json phases = nlohmann::json::object();
      for (const auto& [phase, ms] : gpuStep.phases) phases[phase] = ms;
      j["gpu_update_phases_ms"] = phases;
    }
    for (const char* k : {"sah_cost", "epo", "ray_cost", "node_visits_per_ray", "triangle_tests_per_ray", "tree_hash",
                          "nodes", "mesh_rays"})
      if (r.contains(k)) j[k] = r[k];
    if (twoLevel) j["epo"] = nullptr;  // EPO is a single tree's measure: a two-level frame has none
    j["programs_compiled"] = compiled;
    j["repeats_agree"] = agree;
    frameList.push_back(std::move(j));
    last = r;
  }

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
  int rebuilds = 0;
  for (const nlohmann::json& f : frameList) rebuilds += f["rebuilt"].get<bool>() ? 1 : 0;
  clip["rebuilds"] = rebuilds;
  clip["stack_overflow_pixels"] = overflows;

  nlohmann::json j;
  for (const char* k : {"input", "width", "height", "builder", "layout", "kernel", "storage", "robust", "triangles",
                        "leaf_size", "warnings", "backend", "renderer", "gpu"})
    if (last.contains(k)) j[k] = last[k];
  j["update"] = cmd.update;
  j["two_level"] = twoLevel != nullptr;
  j["update_on"] = gpuRebuild ? "gpu" : "cpu";  // as trace --update (render/trace_clip.hpp)
  j["update_repeats"] = cmd.updateRepeats;
  j["warmup"] = cmd.warmup;
  j["timed_frames"] = cmd.frames;
  j["upload_timing"] = "glFinish + steady_clock (the renderer's whole upload)";
  j["frame_ms"] = clip["total_ms"];
  j["frame_ms_ci_low"] = clip["total_ms_ci_low"];
  j["frame_ms_ci_high"] = clip["total_ms_ci_high"];
  j["frames"] = std::move(frameList);
  j["clip"] = clip;
  return j;
}

int runRenderClip(const RenderCommand& cmd) {
  uint64_t overflows = 0;
  const nlohmann::json j = renderClip(cmd, overflows);
  if (cmd.json) {
    std::cout << j.dump() << std::endl;
  } else {
    for (const nlohmann::json& f : j["frames"])
      std::printf("frame %d%s: update %.3f ms, upload %.3f ms, frame %.3f ms; SAH %.2f, ray cost %.2f\n",
                  f["frame"].get<int>(), f["rebuilt"].get<bool>() ? " (rebuilt)" : "", f["update_ms"].get<double>(),
                  f["upload_ms"].get<double>(), f["ms"].get<double>(), f["sah_cost"].get<double>(),
                  f["ray_cost"].get<double>());
    std::printf("%s, %s over %s: %d frames, %.2f ms in all\n", cmd.input.c_str(), cmd.update.c_str(),
                cmd.builder.c_str(), j["clip"]["frames"].get<int>(), j["clip"]["total_ms"].get<double>());
  }
  if (overflows > 0) {
    std::cerr << "bvhlab: error: traversal stack overflowed in " << overflows << " pixels\n";
    return kExitFailure;
  }
  return 0;
}

}  // namespace bvhlab
