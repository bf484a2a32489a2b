#include "render/render_command.hpp"

#include <algorithm>
#include <cstdio>
#include <iostream>

#include <chrono>

#include <glad/gl.h>
#include <nlohmann/json.hpp>

#include "datasets/image_io.hpp"
#include "datasets/scene_io.hpp"
#include "render/fly_camera.hpp"
#include "render/gl_context.hpp"
#include "render/gpu_renderer.hpp"
#include "render/heatmap.hpp"
#include "render/smaa.hpp"
#include "shaders/tracer.hpp"
#include "traversal/kernels.hpp"

namespace bvhlab {

namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  size_t n = v.size();
  return n == 0 ? 0.0 : (n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]));
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  size_t i = std::min(v.size() - 1, size_t(p * double(v.size() - 1) + 0.5));
  return v[i];
}

}  // namespace

int runRender(const RenderCommand& cmd) {
  CameraPath path;
  if (!cmd.cameraPath.empty()) {
    if (cmd.eye || cmd.target || cmd.up || cmd.fov)
      throw std::invalid_argument("--camera-path sets the camera; drop --eye/--target/--up/--fov");
    path = loadCameraPath(cmd.cameraPath);  // before the scene: a bad path fails fast
  }
  Scene scene = loadInput(cmd.input);
  if (!path.empty()) scene.camera = path.front().camera;
  RenderSettings& s = scene.settings;
  if (cmd.width) s.width = *cmd.width;
  if (cmd.height) s.height = *cmd.height;
  if (cmd.depth) s.maxDepth = *cmd.depth;
  if (cmd.exposure) s.exposure = *cmd.exposure;
  // --eye/--target are world coordinates; a far scene is stored relative to Scene::origin.
  if (cmd.eye) scene.camera.eye = glm::vec3(*cmd.eye - scene.origin);
  if (cmd.target) scene.camera.target = glm::vec3(*cmd.target - scene.origin);
  if (cmd.up) scene.camera.up = *cmd.up;
  if (cmd.fov) scene.camera.fovDeg = *cmd.fov;
  if (s.width < 1 || s.height < 1 || s.width > 16384 || s.height > 16384)
    throw std::invalid_argument("--width/--height must be in 1..16384");
  if (s.maxDepth < 1 || s.maxDepth > 64) throw std::invalid_argument("--depth must be in 1..64");
  if (cmd.frames < 1 || cmd.warmup < 0) throw std::invalid_argument("--frames must be >= 1 and --warmup >= 0");
  if (cmd.leafSize < 1 || cmd.leafSize > int(kMaxLeafSize))
    throw std::invalid_argument("--leaf-size must be in 1.." + std::to_string(kMaxLeafSize));

  const bool visitsView = cmd.view == "visits";
  ShaderOptions so;
  so.maxDepth = s.maxDepth;
  so.view = visitsView ? View::Shaded : parseView(cmd.view);
  so.branching = parseBranching(cmd.branching);
  so.kernel = findKernel(cmd.kernel).name;
  so.storage = parseStorage(cmd.storage);
  so.reinhard = s.reinhard;
  so.uber = cmd.uber;
  so.robust = parseRobustness(cmd.robust);
  const Backend backend = parseBackend(cmd.backend);
  // "smaa-PRESET" is "smaa" with --smaa-preset PRESET, so an experiment axis can sweep the presets.
  const bool smaaNamed = cmd.aa.rfind("smaa-", 0) == 0;
  if (cmd.aa != "none" && cmd.aa != "smaa" && !smaaNamed && cmd.aa != "ssaa4" && cmd.aa != "ssaa16")
    throw std::invalid_argument("unknown --aa '" + cmd.aa +
                                "' (valid: none, smaa, smaa-low, smaa-medium, smaa-high, smaa-ultra, ssaa4, ssaa16)");
  so.ssaaGrid = cmd.aa == "ssaa4" ? 2 : cmd.aa == "ssaa16" ? 4 : 1;
  const bool smaaOn = cmd.aa == "smaa" || smaaNamed;
  const std::string smaaPreset = smaaNamed ? cmd.aa.substr(5) : cmd.smaaPreset;
  SmaaSettings smaaSettings = SmaaSettings::preset(parseSmaaPreset(smaaPreset));
  if (cmd.smaaEdges == "color")
    smaaSettings.edgeMode = SmaaEdgeMode::Color;
  else if (cmd.smaaEdges != "luma")
    throw std::invalid_argument("--smaa-edges: unknown mode '" + cmd.smaaEdges + "' (valid: luma, color)");
  if (smaaOn && cmd.cpu) throw std::invalid_argument("--aa smaa runs on the GPU only (no --cpu)");

  BuildOptions bo;
  bo.maxLeafSize = uint32_t(cmd.leafSize);
  bo.bins = uint32_t(std::max(0, cmd.bins));
  std::unique_ptr<PreparedScene> prepared = prepareScene(std::move(scene), cmd.builder, bo);
  const Scene& sc = prepared->scene;
  so.bvhStackSize = stackSizeFor(std::max<uint32_t>(1, prepared->packed.depth));

  FrameOptions fo;
  fo.width = sc.settings.width;
  fo.height = sc.settings.height;
  fo.camera = sc.camera;
  fo.exposure = sc.settings.exposure;

  nlohmann::json out;
  std::vector<uint8_t> image;
  std::vector<glm::uvec4> stats;
  std::vector<double> times, aaTimes;
  std::string renderer;
  const bool wantStats = cmd.json || visitsView || !cmd.visitsOutput.empty();

  if (cmd.cpu) {
    so.countStats = true;
    ReferenceImage ref = renderReference(sc, prepared->data, prepared->packed, so, fo);
    image = std::move(ref.rgba);
    stats = std::move(ref.stats);
    times.push_back(ref.ms);
    renderer = "bvhlab C++ mirror";
  } else {
    std::unique_ptr<GlContext> ctx = createContext(backend);
    renderer = ctx->renderer();
    {
      // Timed frames run WITHOUT the statistics instrumentation; counts come from a separate frame.
      GpuRenderer gpu(*prepared, so, fo);
      std::unique_ptr<SmaaPass> smaa;
      if (smaaOn) smaa = std::make_unique<SmaaPass>(fo.width, fo.height, smaaSettings);
      // One frame = the trace, plus the SMAA passes when on (each waited for with glFinish).
      // Returns the frame's ms; `aaMs` gets the SMAA part.
      auto frame = [&](double& aaMs) {
        double ms = gpu.drawFrame();
        aaMs = 0.0;
        if (!smaa) return ms;
        auto start = std::chrono::steady_clock::now();
        smaa->apply(gpu.colorTexture());
        glFinish();
        aaMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
        return ms + aaMs;
      };
      // Along a camera path, frame i (warm-up frames first) is drawn from pose i mod N.
      auto pose = [&](int i) {
        if (!path.empty()) gpu.setCamera(path[size_t(i) % path.size()].camera);
      };
      double aaMs = 0.0;
      for (int i = 0; i < cmd.warmup; ++i) pose(i), frame(aaMs);  // llvmpipe JIT-compiles at the first draw
      for (int i = 0; i < cmd.frames; ++i) {
        pose(i);
        times.push_back(frame(aaMs));
        if (smaa) aaTimes.push_back(aaMs);
      }
      if (!path.empty()) gpu.setCamera(path.front().camera), frame(aaMs);  // the saved image is pose 0's
      image = smaa ? smaa->readOutput() : gpu.readColor();
    }
    if (wantStats) {
      ShaderOptions counted = so;
      counted.countStats = true;
      GpuRenderer gpu(*prepared, counted, fo);
      gpu.drawFrame();
      stats = gpu.readStats();
    }
  }

  // Per-ray statistics: totals over the frame divided by rays traced into the mesh; p95 over pixels
  // of each pixel's own per-ray mean.
  uint64_t visits = 0, tests = 0, rays = 0, overflows = 0, nonfinite = 0;
  std::vector<double> pixelVisits, pixelTests;
  for (const glm::uvec4& p : stats) {
    uint32_t r = p.z & 0x7FFFFFFFu;
    overflows += (p.z >> 31);
    nonfinite += (p.w >> 31);  // radiance NaN or infinite before tone mapping (main.glsl's nonFinite)
    visits += p.x;
    tests += p.y;
    rays += r;
    if (r > 0) {
      pixelVisits.push_back(double(p.x) / r);
      pixelTests.push_back(double(p.y) / r);
    }
  }

  if (!cmd.visitsOutput.empty() || visitsView) {
    std::vector<uint8_t> heat = visitsHeatmap(stats, fo.width, fo.height);
    if (!cmd.visitsOutput.empty()) saveImageRgba8(cmd.visitsOutput, fo.width, fo.height, heat);
    if (visitsView) image = std::move(heat);
  }
  if (!cmd.output.empty()) saveImageRgba8(cmd.output, fo.width, fo.height, image);

  if (cmd.json) {
    const BuildStats& b = prepared->stats;
    out["input"] = cmd.input;
    out["image"] = cmd.output;
    out["frame_ms"] = median(times);
    out["frame_ms_min"] = *std::min_element(times.begin(), times.end());
    out["frame_ms_max"] = *std::max_element(times.begin(), times.end());
    out["frame_ms_all"] = times;
    out["frames"] = times.size();
    out["warmup"] = cmd.cpu ? 0 : cmd.warmup;
    out["width"] = fo.width;
    out["height"] = fo.height;
    out["depth"] = so.maxDepth;
    out["effective_depth"] = effectiveDepth(analyzeScene(sc), so.maxDepth, so.uber);
    out["backend"] = cmd.cpu ? "cpu" : backendName(backend);
    out["renderer"] = renderer;
    out["view"] = cmd.view;
    out["uber"] = so.uber;
    out["branching"] = branchingName(so.branching);
    out["storage"] = storageName(so.storage);
    out["aa"] = cmd.aa;
    out["robust"] = robustnessName(so.robust);
    if (!path.empty()) {
      out["camera_path"] = cmd.cameraPath;
      out["path_poses"] = path.size();
    }
    if (smaaOn) {
      out["smaa_preset"] = smaaPreset;
      out["smaa_edges"] = cmd.smaaEdges;
      out["aa_ms"] = median(aaTimes);
    }
    out["builder"] = cmd.builder;
    out["kernel"] = so.kernel;
    out["leaf_size"] = cmd.leafSize;
    out["triangles"] = prepared->soup.size();
    out["build_ms"] = b.buildMs;
    out["sah_cost"] = b.sahCost;
    out["nodes"] = b.nodes;
    out["leaves"] = b.leaves;
    out["bvh_depth"] = b.depth;
    out["bytes"] = b.bytes;
    out["mesh_rays"] = rays;
    out["node_visits_per_ray"] = rays ? double(visits) / double(rays) : 0.0;
    out["triangle_tests_per_ray"] = rays ? double(tests) / double(rays) : 0.0;
    out["node_visits_p95"] = percentile(pixelVisits, 0.95);
    out["triangle_tests_p95"] = percentile(pixelTests, 0.95);
    out["stack_overflow_pixels"] = overflows;
    out["nonfinite_pixels"] = nonfinite;
    std::cout << out.dump() << std::endl;
  }
  if (overflows > 0) {
    std::cerr << "bvhlab: error: traversal stack overflowed in " << overflows << " pixels\n";
    return 3;
  }
  return 0;
}

}  // namespace bvhlab
