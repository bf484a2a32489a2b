// The run settings of an experiment config (experiments/config_settings.hpp).
#include "experiments/config_settings.hpp"

#include <fstream>
#include <limits>
#include <sstream>

#include "datasets/scene.hpp"  // InputError
#include "render/fly_camera.hpp"

namespace bvhlab::config_detail {

namespace fs = std::filesystem;

void readRenderSection(ConfigReader& r, const toml::node& section, RunRender& out, SettingNodes& nodes) {
  const std::string name = "render";
  for (auto&& [rk, rv] : r.table(section, name)) {
    const std::string key = "render." + std::string(rk.str());
    // The size bound is the texture limit measured on llvmpipe (NOTES.md).
    if (rk == "width") out.width = int(r.integer(rv, key, 1, 16384));
    else if (rk == "height") out.height = int(r.integer(rv, key, 1, 16384));
    else if (rk == "warmup") out.warmup = int(r.integer(rv, key, 0, 1000000));
    else if (rk == "frames") {
      nodes.frames = &rv;
      out.frames = int(r.integer(rv, key, 1, 1000000));
    }
    else if (rk == "backend") out.backend = r.oneOf(rv, key, kBackends, "backend");
    else if (rk == "heatmaps") out.heatmaps = r.boolean(rv, key);
    else if (rk == "gpu_builds") out.gpuBuilds = int(r.integer(rv, key, 0, 1000));
    else if (rk == "timeout_s") {
      out.timeoutSeconds = r.number(rv, key);
      if (!(out.timeoutSeconds > 0.0)) r.fail(rv.source(), key, "must be > 0 seconds");
    } else if (rk == "env") {
      for (auto&& [name, value] : r.table(rv, key))
        out.env[std::string(name.str())] = r.string(value, key + "." + std::string(name.str()));
    } else if (rk == "camera_path") {
      out.cameraPath = r.string(rv, key);
      if (out.cameraPath.empty()) r.fail(rv.source(), key, "empty path");
      const fs::path resolved =
          (fs::path(out.cameraPath).is_absolute() ? fs::path(out.cameraPath) : r.dir() / out.cameraPath)
              .lexically_normal();
      std::ifstream in(resolved, std::ios::binary);
      if (!in) r.fail(rv.source(), key, "camera path '" + out.cameraPath + "' not found (looked at " +
                                            resolved.string() + ")");
      std::ostringstream bytes;
      bytes << in.rdbuf();
      try {
        parseCameraPath(bytes.str(), resolved.string());  // validated now, not when the run starts
      } catch (const InputError& e) {
        r.fail(rv.source(), key, e.what());
      }
      out.cameraPathFile = resolved;
      out.cameraPathHash = hashHex(bytes.str());
      nodes.cameraPath = &rv;
    } else if (rk == "args") {
      const toml::array* a = rv.as_array();
      if (!a) r.fail(rv.source(), key, "expected an array of strings, got " + typeName(rv));
      for (const toml::node& arg : *a) out.args.push_back(r.string(arg, key));
    } else
      r.fail(rk.source(), key,
             "unknown key; [render] has width, height, warmup, frames, backend, heatmaps, timeout_s, env, args, "
             "camera_path, gpu_builds");
  }
}

void readMeasureSection(ConfigReader& r, const toml::node& section, RunRender& out, SettingNodes& nodes) {
  const std::string name = "measure";
  for (auto&& [mk, mv] : r.table(section, name)) {
    const std::string key = "measure." + std::string(mk.str());
    if (mk == "min_frames") {
      nodes.measureMinNode = &mv;
      nodes.measureMin = int(r.integer(mv, key, 1, 1000000));
    } else if (mk == "max_frames") {
      nodes.maxFrames = &mv;
      out.maxFrames = int(r.integer(mv, key, 1, 1000000));
    } else if (mk == "target_ci_pct") {
      out.targetCiPct = r.number(mv, key);
      if (!(out.targetCiPct > 0.0 && out.targetCiPct <= 100.0)) r.fail(mv.source(), key, "must be in (0, 100]");
    } else if (mk == "max_seconds") {
      out.maxSeconds = r.number(mv, key);
      if (!(out.maxSeconds > 0.0)) r.fail(mv.source(), key, "must be > 0 seconds");
    } else if (mk == "group_size") {
      out.groupSize = int(r.integer(mv, key, 1, 100000));
    } else if (mk == "aa_control") {
      out.aaControl = r.boolean(mv, key);
    } else if (mk == "share_programs") {
      out.sharePrograms = r.boolean(mv, key);
    } else if (mk == "program_copies") {
      nodes.programCopies = &mv;
      out.programCopies = int(r.integer(mv, key, 1, 64));
    } else if (mk == "interleave") {
      out.interleave = r.boolean(mv, key);
    } else {
      r.fail(mk.source(), key,
             "unknown key; [measure] has min_frames, max_frames, target_ci_pct, max_seconds, group_size, "
             "aa_control, share_programs, program_copies, interleave");
    }
  }
}

void readTraceSection(ConfigReader& r, const toml::node& section, RunRender& out) {
  const std::string name = "trace";
  for (auto&& [tk, tv] : r.table(section, name)) {
    const std::string key = "trace." + std::string(tk.str());
    // Bounds: render/workloads.hpp's kMaxTraceRays (2^24) and its (0, 1] ao radius.
    if (tk == "count") out.traceCount = int(r.integer(tv, key, 1, int64_t(1) << 24));
    else if (tk == "seed") out.traceSeed = uint64_t(r.integer(tv, key, 0, std::numeric_limits<int64_t>::max()));
    else if (tk == "ao_radius") {
      out.aoRadius = r.number(tv, key);
      if (!(out.aoRadius > 0.0 && out.aoRadius <= 1.0)) r.fail(tv.source(), key, "must be in (0, 1]");
    } else if (tk == "clip_frames") {
      out.clipFrames = int(r.integer(tv, key, 0, 1 << 20));
    } else if (tk == "clip_step") {
      out.clipStep = int(r.integer(tv, key, 1, 1 << 20));
    } else if (tk == "update_repeats") {
      out.updateRepeats = int(r.integer(tv, key, 1, 64));
    } else if (tk == "embree_threads") {
      out.embreeThreads = int(r.integer(tv, key, 0, 256));
    } else if (tk == "min_sample_ms") {
      out.minSampleMs = r.number(tv, key);
      if (!(out.minSampleMs >= 0.0 && out.minSampleMs <= 10000.0)) r.fail(tv.source(), key, "must be in [0, 10000] ms");
    } else {
      r.fail(tk.source(), key, "unknown key; [trace] has count, seed, ao_radius, embree_threads, min_sample_ms, clip_frames, "
                          "clip_step, update_repeats");
    }
  }
}

void checkRunSettings(ConfigReader& r, RunRender& render, const SettingNodes& nodes) {
  // [measure] min_frames is [render] frames by another name: one value, given in one place.
  if (nodes.measureMin) {
    if (nodes.frames && *nodes.measureMin != render.frames)
      r.fail(nodes.measureMinNode->source(), "measure.min_frames",
             "[render] frames = " + std::to_string(render.frames) + " says otherwise; give it in one place");
    render.frames = *nodes.measureMin;
  }
  if (!nodes.maxFrames) render.maxFrames = std::max(render.maxFrames, render.frames);
  if (render.maxFrames < render.frames)
    r.fail(nodes.maxFrames->source(), "measure.max_frames",
           std::to_string(render.maxFrames) + " is below min_frames " + std::to_string(render.frames));

  if (nodes.programCopies && render.programCopies > 1 && !render.interleave)
    r.fail(nodes.programCopies->source(), "measure.program_copies",
           "needs interleave = true (program copies are drawn in one `bvhlab measure` process)");
}

}  // namespace bvhlab::config_detail
