#include "render/render_job.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <glad/gl.h>

#include "datasets/image_io.hpp"
#include "datasets/scene_io.hpp"
#include "render/gpu_build_timing.hpp"
#include "render/frame_stats.hpp"
#include "render/heatmap.hpp"
#include "layout/layouts.hpp"
#include "layout/triangle_formats.hpp"
#include "traversal/kernels.hpp"

namespace bvhlab {

namespace {

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  size_t i = std::min(v.size() - 1, size_t(p * double(v.size() - 1) + 0.5));
  return v[i];
}

std::string vecText(const glm::dvec3& v) {
  return std::to_string(v.x) + "," + std::to_string(v.y) + "," + std::to_string(v.z);
}

}  // namespace

BuildOptions renderBuildOptions(const RenderCommand& cmd, OptionReview* review) {
  if (cmd.leafSize < 1 || cmd.leafSize > int(kMaxLeafSize))
    throw std::invalid_argument("--leaf-size must be in 1.." + std::to_string(kMaxLeafSize));
  if (cmd.bins < 0) throw std::invalid_argument("--bins must be >= 0 (0 = the builder's default)");
  if (!(cmd.sbvhAlpha >= 0.0f && cmd.sbvhAlpha <= 1.0f))
    throw std::invalid_argument("--sbvh-alpha must be in 0..1 (a fraction of the root's area)");
  if (!(cmd.sbvhBudget >= 1.0f && std::isfinite(cmd.sbvhBudget)))
    throw std::invalid_argument("--sbvh-budget must be a finite number >= 1 (leaf references per primitive)");
  if (cmd.plocRadius < 1 || cmd.plocRadius > int(kMaxPlocRadius))
    throw std::invalid_argument("--ploc-radius must be in 1.." + std::to_string(kMaxPlocRadius));
  if (cmd.plocTopDown < 0 || cmd.plocTopDown > int(kMaxPlocTopDown))
    throw std::invalid_argument("--ploc-top-down must be in 0.." + std::to_string(kMaxPlocTopDown) + " (got " +
                                std::to_string(cmd.plocTopDown) + ")");
  if (cmd.mortonSizeBits < 0 || cmd.mortonSizeBits > int(kMaxMortonSizeBits))
    throw std::invalid_argument("--morton-size-bits must be in 0.." + std::to_string(kMaxMortonSizeBits) + " (got " +
                                std::to_string(cmd.mortonSizeBits) + ")");
  BuildOptions b;
  b.maxLeafSize = uint32_t(cmd.leafSize);
  b.bins = uint32_t(cmd.bins);
  b.optimize = cmd.optimize;
  b.sbvhAlpha = cmd.sbvhAlpha;
  b.sbvhReferenceBudget = cmd.sbvhBudget;
  b.plocRadius = uint32_t(cmd.plocRadius);
  b.plocTopDown = uint32_t(cmd.plocTopDown);
  b.mortonSizeBits = uint32_t(cmd.mortonSizeBits);
  b.mortonGrid = parseMortonGrid(cmd.mortonGrid);
  OptionReview r = reviewBuildOptions(cmd.builder, b);  // bad values throw before the input is read
  if (review) *review = std::move(r);
  return b;
}

RenderSetup setupRender(const RenderCommand& cmd, const Scene* loaded) {
  RenderSetup s;
  s.build = renderBuildOptions(cmd, &s.buildReview);
  // Layout and kernel names fail before the input is read; a kernel of another layout is refused here.
  s.shader.layout = findLayout(cmd.layout).name;
  s.shader.kernel = findKernel(s.shader.layout, cmd.kernel).name;
  // The triangle format too, with the pairing it cannot run (precomputed + a watertight test).
  s.shader.triangles = findTriangleFormat(cmd.triangles).name;
  checkTriangleFormat(s.shader.triangles, parseRobustness(cmd.robust));
  if (!cmd.cameraPath.empty()) {
    if (cmd.eye || cmd.target || cmd.up || cmd.fov)
      throw std::invalid_argument("--camera-path sets the camera; drop --eye/--target/--up/--fov");
    s.path = loadCameraPath(cmd.cameraPath);  // before the scene: a bad path fails fast
  }
  s.scene = loaded ? *loaded : loadInput(cmd.input);
  Scene& scene = s.scene;
  if (!s.path.empty()) scene.camera = s.path.front().camera;
  RenderSettings& rs = scene.settings;
  if (cmd.width) rs.width = *cmd.width;
  if (cmd.height) rs.height = *cmd.height;
  if (cmd.depth) rs.maxDepth = *cmd.depth;
  if (cmd.exposure) rs.exposure = *cmd.exposure;
  // --eye/--target are world coordinates; a far scene is stored relative to Scene::origin.
  if (cmd.eye) scene.camera.eye = glm::vec3(*cmd.eye - scene.origin);
  if (cmd.target) scene.camera.target = glm::vec3(*cmd.target - scene.origin);
  if (cmd.up) scene.camera.up = *cmd.up;
  if (cmd.fov) scene.camera.fovDeg = *cmd.fov;
  if (rs.width < 1 || rs.height < 1 || rs.width > 16384 || rs.height > 16384)
    throw std::invalid_argument("--width/--height must be in 1..16384");
  if (rs.maxDepth < 1 || rs.maxDepth > 64) throw std::invalid_argument("--depth must be in 1..64");
  if (cmd.frames < 1 || cmd.warmup < 0) throw std::invalid_argument("--frames must be >= 1 and --warmup >= 0");

  ShaderOptions& so = s.shader;
  so.maxDepth = rs.maxDepth;
  so.view = cmd.view == "visits" ? View::Shaded : parseView(cmd.view);
  so.branching = parseBranching(cmd.branching);
  so.storage = parseStorage(cmd.storage);
  so.reinhard = rs.reinhard;
  so.uber = cmd.uber;
  so.robust = parseRobustness(cmd.robust);
  try {
    so.textureLod = parseTextureLod(cmd.textureLod);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("--texture-lod: ") + e.what());
  }
  s.backend = parseBackend(cmd.backend);
  // "smaa-PRESET" is "smaa" with --smaa-preset PRESET, so an experiment axis can sweep the presets.
  const bool smaaNamed = cmd.aa.rfind("smaa-", 0) == 0;
  if (cmd.aa != "none" && cmd.aa != "smaa" && !smaaNamed && cmd.aa != "ssaa4" && cmd.aa != "ssaa16")
    throw std::invalid_argument("unknown --aa '" + cmd.aa +
                                "' (valid: none, smaa, smaa-low, smaa-medium, smaa-high, smaa-ultra, ssaa4, ssaa16)");
  so.ssaaGrid = cmd.aa == "ssaa4" ? 2 : cmd.aa == "ssaa16" ? 4 : 1;
  s.smaaOn = cmd.aa == "smaa" || smaaNamed;
  s.smaaPreset = smaaNamed ? cmd.aa.substr(5) : cmd.smaaPreset;
  s.smaa = SmaaSettings::preset(parseSmaaPreset(s.smaaPreset));
  try {
    s.smaa.edgeMode = parseSmaaEdgeMode(cmd.smaaEdges);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("--smaa-edges: ") + e.what());
  }
  // Geometry edges read the tracer's primary id: an extra R32UI target, written only then.
  so.primaryIdOut = s.smaaOn && s.smaa.edgeMode == SmaaEdgeMode::Geometry;
  if (s.smaaOn && cmd.cpu) throw std::invalid_argument("--aa smaa runs on the GPU only (no --cpu)");

  // Refused now, not after the frames are rendered.
  if (!cmd.output.empty()) imageFormatFor(cmd.output);
  if (!cmd.visitsOutput.empty()) imageFormatFor(cmd.visitsOutput);
  return s;
}

std::string treeKey(const RenderCommand& c) {
  // Fields joined by '|' (appended one by one: GCC 12 misreports chained `"|" + string` with -Wrestrict).
  std::string key;
  const auto field = [&key](const std::string& text) {
    if (!key.empty()) key += '|';
    key += text;
  };
  for (const std::string& f : {c.input, c.layout, c.triangles, c.builder, std::to_string(c.leafSize), std::to_string(c.bins), c.optimize,
                               std::to_string(c.sbvhAlpha), std::to_string(c.sbvhBudget), std::to_string(c.plocRadius), std::to_string(c.plocTopDown), std::to_string(c.mortonSizeBits), c.mortonGrid, c.cameraPath})
    field(f);
  for (const auto& v : {c.width, c.height, c.depth}) field(v ? std::to_string(*v) : "-");
  for (const auto& v : {c.eye, c.target}) field(v ? vecText(*v) : "-");
  field(c.up ? vecText(glm::dvec3(*c.up)) : "-");
  field(c.fov ? std::to_string(*c.fov) : "-");
  field(c.exposure ? std::to_string(*c.exposure) : "-");
  return key;
}

GpuJob::GpuJob(const RenderCommand& cmd, const RenderSetup& setup, std::shared_ptr<const PreparedScene> prepared,
               ProgramCache* programs, int stackSize)
    : prepared_(std::move(prepared)), shader_(setup.shader), path_(setup.path), programs_(programs) {
  const Scene& sc = prepared_->scene;
  shader_.bvhStackSize = std::max(stackSizeFor(prepared_->packed), stackSize);
  frame_.width = sc.settings.width;
  frame_.height = sc.settings.height;
  frame_.camera = sc.camera;
  frame_.exposure = sc.settings.exposure;
  gpu_ = std::make_unique<GpuRenderer>(*prepared_, shader_, frame_, programs_);
  programIndex_ = gpu_->programIndex();
  if (setup.smaaOn) smaa_ = std::make_unique<SmaaPass>(frame_.width, frame_.height, setup.smaa);
}

double GpuJob::frame(int index, double& aaMs) {
  if (!path_.empty()) gpu_->setCamera(path_[size_t(index) % path_.size()].camera);
  const double ms = gpu_->drawFrame();
  aaMs = 0.0;
  if (!smaa_) return ms;
  const auto start = std::chrono::steady_clock::now();
  smaa_->apply(gpu_->colorTexture(), gpu_->primaryIdTexture());
  glFinish();
  aaMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return ms + aaMs;
}

void GpuJob::finish(bool wantStats) {
  double aaMs = 0.0;
  if (!path_.empty()) frame(0, aaMs);  // the saved image is pose 0's
  image = smaa_ ? smaa_->readOutput() : gpu_->readColor();
  gpu_.reset();
  smaa_.reset();
  if (wantStats) {
    ShaderOptions counted = shader_;
    counted.countStats = true;
    FrameOptions fo = frame_;
    if (!path_.empty()) fo.camera = path_.front().camera;
    GpuRenderer gpu(*prepared_, counted, fo, programs_);
    gpu.drawFrame();
    stats = gpu.readStats();
    boxTests = gpu.readBoxTests();
  }
}

uint64_t stackOverflowPixels(const std::vector<glm::uvec4>& stats) {
  uint64_t n = 0;
  for (const glm::uvec4& p : stats) n += (p.z >> 31);
  return n;
}

nlohmann::json finishRender(const RenderCommand& cmd, const RenderSetup& setup, const PreparedScene& prepared,
                            const FrameOptions& fo, std::vector<uint8_t> image, const std::vector<glm::uvec4>& stats,
                            const std::vector<uint32_t>& boxTests, const FrameTimes& times, const std::string& renderer,
                            bool cpu) {
  const ShaderOptions& so = setup.shader;
  // Per-ray statistics: totals over the frame divided by rays traced into the mesh; p95 over pixels
  // of each pixel's own per-ray mean.
  uint64_t visits = 0, tests = 0, boxes = 0, rays = 0, nonfinite = 0;
  std::vector<double> pixelVisits, pixelTests, pixelBoxes;
  for (size_t i = 0; i < stats.size(); ++i) {
    const glm::uvec4& p = stats[i];
    const uint32_t r = p.z & 0x7FFFFFFFu;
    const uint32_t b = i < boxTests.size() ? boxTests[i] : 0u;
    nonfinite += (p.w >> 31);  // radiance NaN or infinite before tone mapping (main.glsl's nonFinite)
    visits += p.x;
    tests += p.y;
    boxes += b;
    rays += r;
    if (r > 0) {
      pixelVisits.push_back(double(p.x) / r);
      pixelTests.push_back(double(p.y) / r);
      pixelBoxes.push_back(double(b) / r);
    }
  }
  const bool visitsView = cmd.view == "visits";
  if (!cmd.visitsOutput.empty() || visitsView) {
    std::vector<uint8_t> heat = visitsHeatmap(stats, fo.width, fo.height);
    if (!cmd.visitsOutput.empty()) saveImageRgba8(cmd.visitsOutput, fo.width, fo.height, heat);
    if (visitsView) image = std::move(heat);
  }
  if (!cmd.output.empty()) saveImageRgba8(cmd.output, fo.width, fo.height, image);

  nlohmann::json out;
  const BuildStats& b = prepared.stats;
  const std::vector<double>& ms = times.ms;
  out["input"] = cmd.input;
  out["image"] = cmd.output;
  out["frame_ms"] = medianOf(ms);
  out["frame_ms_min"] = ms.empty() ? 0.0 : *std::min_element(ms.begin(), ms.end());
  out["frame_ms_max"] = ms.empty() ? 0.0 : *std::max_element(ms.begin(), ms.end());
  // The median's 95% order-statistic interval (render/frame_stats.hpp); null below 6 frames.
  const auto ci = medianInterval(ms);
  out["frame_ms_ci_low"] = ci ? nlohmann::json(ci->low) : nlohmann::json();
  out["frame_ms_ci_high"] = ci ? nlohmann::json(ci->high) : nlohmann::json();
  out["ci_pct"] = ci && ci->estimate > 0.0 ? nlohmann::json(50.0 * (ci->high - ci->low) / ci->estimate)
                                           : nlohmann::json();
  out["ci_target_pct"] = times.targetCiPct > 0.0 ? nlohmann::json(times.targetCiPct) : nlohmann::json();
  out["ci_target_met"] = times.targetCiPct > 0.0 && ci && out["ci_pct"].get<double>() <= times.targetCiPct;
  out["measure_stop"] = times.stop;
  out["frame_ms_all"] = ms;
  out["frames"] = ms.size();
  out["warmup"] = cpu ? 0 : cmd.warmup;
  out["width"] = fo.width;
  out["height"] = fo.height;
  out["depth"] = so.maxDepth;
  out["effective_depth"] = effectiveDepth(analyzeScene(prepared.scene), so.maxDepth, so.uber);
  out["backend"] = cpu ? "cpu" : backendName(setup.backend);
  out["renderer"] = renderer;
  out["gpu"] = !cpu && !isSoftwareRenderer(renderer);  // false on llvmpipe (EGL without a GPU lands there too)
  out["view"] = cmd.view;
  out["uber"] = so.uber;
  out["branching"] = branchingName(so.branching);
  out["storage"] = storageName(so.storage);
  out["aa"] = cmd.aa;
  out["robust"] = robustnessName(so.robust);
  out["texture_lod"] = textureLodName(so.textureLod);
  if (!setup.path.empty()) {
    out["camera_path"] = cmd.cameraPath;
    out["path_poses"] = setup.path.size();
  }
  if (setup.smaaOn) {
    out["smaa_preset"] = setup.smaaPreset;
    out["smaa_edges"] = cmd.smaaEdges;
    out["aa_ms"] = medianOf(times.aaMs);
  }
  out["builder"] = cmd.builder;
  out["layout"] = so.layout;
  out["triangle_format"] = so.triangles;  // "triangles" is the triangle count
  out["kernel"] = so.kernel;
  out["leaf_size"] = setup.buildReview.leafSize;  // what the leaves were limited to (a builder may cap it)
  out["leaf_size_requested"] = cmd.leafSize;
  out["warnings"] = setup.buildReview.warnings;
  out["triangles"] = prepared.soup.size();
  out["build_ms"] = b.buildMs;
  addGpuBuildTiming(out, prepared, cmd.builder, setup.build, cmd.gpuBuilds);
  out["sah_cost"] = b.sahCost;
  out["nodes"] = b.nodes;
  out["leaves"] = b.leaves;
  out["bvh_depth"] = b.depth;
  out["bytes"] = b.bytes;
  out["bytes_per_triangle"] = prepared.soup.size() ? double(b.bytes) / double(prepared.soup.size()) : 0.0;
  out["references"] = b.references;
  out["optimize"] = cmd.optimize.empty() ? nlohmann::json() : nlohmann::json(cmd.optimize);
  out["sah_before_optimize"] = b.sahBeforeOptimize;
  out["optimize_ms"] = b.optimizeMs;
  out["tree_hash"] = prepared.treeHash();
  out["epo"] = prepared.endPointOverlap();
  out["mesh_rays"] = rays;
  const double visitsPerRay = rays ? double(visits) / double(rays) : 0.0;
  const double testsPerRay = rays ? double(tests) / double(rays) : 0.0;
  out["node_visits_per_ray"] = visitsPerRay;
  out["triangle_tests_per_ray"] = testsPerRay;
  // A wide node visit tests several boxes (cwbvh, bvh4, bvh8), so visits alone undercount their work.
  out["box_tests_per_ray"] = rays ? double(boxes) / double(rays) : 0.0;
  // The clock-free cost of the traced rays under the builders' own cost model (Ct, Ci).
  const CostModel cost = setup.build.cost;
  out["ray_cost"] = cost.traversalCost * visitsPerRay + cost.intersectionCost * testsPerRay;
  out["node_visits_p95"] = percentile(pixelVisits, 0.95);
  out["triangle_tests_p95"] = percentile(pixelTests, 0.95);
  out["box_tests_p95"] = percentile(pixelBoxes, 0.95);
  out["stack_overflow_pixels"] = stackOverflowPixels(stats);
  out["nonfinite_pixels"] = nonfinite;
  return out;
}

}  // namespace bvhlab
