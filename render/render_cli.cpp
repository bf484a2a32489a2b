#include "render/render_cli.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <stdexcept>

namespace bvhlab {

glm::dvec3 parseVec3(const std::string& s, const char* flag) {
  glm::dvec3 v;
  char c1, c2;
  std::istringstream in(s);
  if (!(in >> v.x >> c1 >> v.y >> c2 >> v.z) || c1 != ',' || c2 != ',' || !in.eof() || !std::isfinite(v.x) ||
      !std::isfinite(v.y) || !std::isfinite(v.z))
    throw std::invalid_argument(std::string(flag) + " expects three finite numbers x,y,z (got '" + s + "')");
  return v;
}

CLI::Validator notADirectory(const std::string& expected) {
  return CLI::Validator(
      [expected](std::string& path) {
        std::error_code ec;
        return std::filesystem::is_directory(path, ec) ? path + " is a directory; expected " + expected : std::string();
      },
      "", "not-a-directory");
}

void addClipOptions(CLI::App& app, RenderCommand& rc) {
  app.add_option("--update", rc.update,
                 "an animated scene's clip frame by frame, the tree kept up to date by this strategy: rebuild | refit | "
                 "refit+rebuild:K | refit+rebuild:sah>R | refit+rotate (docs/animation.md)");
  app.add_option("--update-repeats", rc.updateRepeats,
                 "with --update: timed updates per frame, by as many copies of the strategy, each from its own previous frame")
      ->check(CLI::Range(1, 64));
  app.add_option("--clip-frames", rc.clipFrames, "with --update: at most this many of the clip's frames (0 = all)")
      ->check(CLI::Range(0, 1 << 20));
  app.add_option("--clip-step", rc.clipStep, "with --update: every this-th frame of the clip (0, S, 2S, ...)")
      ->check(CLI::Range(1, 1 << 20));
}

void addTreeOptions(CLI::App& app, RenderCommand& rc) {
  app.add_option("--builder", rc.builder, "BVH builder (see `bvhlab builders`)");
  app.add_option("--layout", rc.layout, "texture layout of the tree (see `bvhlab layouts`)");
  app.add_option("--triangles", rc.triangles,
                 "triangle format: raw | precomputed (fast tests only) | indexed (see `bvhlab layouts`)");
  app.add_option("--kernel", rc.kernel,
                 "traversal kernel of that layout (see `bvhlab kernels`; default: the layout's, stack-ordered for v1)");
  app.add_option("--leaf-size", rc.leafSize, "max triangles per BVH leaf");
  app.add_option("--bins", rc.bins, "bins for sah-binned and sbvh (0 = default)");
  app.add_option("--optimize", rc.optimize, "post-pass after the builder: reinsert (Bittner et al. 2013)");
  app.add_option("--sbvh-alpha", rc.sbvhAlpha, "sbvh: overlap threshold for spatial splits (fraction of the root area)");
  app.add_option("--sbvh-budget", rc.sbvhBudget, "sbvh: at most this many leaf references per primitive, >= 1 (1: no spatial splits)");
  app.add_option("--ploc-radius", rc.plocRadius, "ploc: nearest-neighbour search radius");
  app.add_option("--ploc-top-down", rc.plocTopDown,
                 "ploc: split the last n/F clusters top-down by binned SAH, 0..1024 (0 = cluster to the end)");
  app.add_option("--morton-size-bits", rc.mortonSizeBits,
                 "ploc, lbvh: primitive-size bits in the Morton codes, 0..9 (0 = position only)");
  app.add_option("--morton-grid", rc.mortonGrid,
                 "ploc, lbvh: the Morton codes' grid: cube (one cell size on every axis) | axes (each axis over its own extent)");
  app.add_option("--storage", rc.storage, "tbo | tex2d | ssbo");
  app.add_option("--gpu-builds", rc.gpuBuilds,
                 "a GPU builder with --json: GL-timed builds after a warm-up, recorded as gpu_build_ms with its "
                 "interval (0 = none)")
      ->check(CLI::Range(0, 1000));
}

void addRenderOptions(CLI::App& app, RenderCommand& rc, RenderCliText& text) {
  app.option_defaults()->always_capture_default();  // --help shows every default
  app.add_option("input", rc.input, "scene .toml or mesh file")
      ->required()
      ->check(notADirectory("a scene .toml or a mesh file (OBJ/OFF/PLY/STL)"));
  app.add_option("-o,--output", rc.output, "write the image here (PNG)");
  app.add_flag("--json", rc.json, "print one JSON object with timings and statistics");
  app.add_option("--width", rc.width, "image width");
  app.add_option("--height", rc.height, "image height");
  app.add_option("--depth", rc.depth, "max path depth (the report's recursion depth)");
  app.add_option("--frames", rc.frames, "timed frames after warm-up (median reported)");
  app.add_option("--warmup", rc.warmup, "untimed warm-up frames (llvmpipe compiles at the first draw)");
  app.add_option("--backend", rc.backend, "osmesa | egl");
  app.add_option("--view", rc.view, "shaded | normal | depth | primid | visits");
  app.add_option("--visits-out", rc.visitsOutput, "also write the node-visit heatmap here");
  app.add_flag("--uber", rc.uber, "compile every module in (no specialisation)");
  addTreeOptions(app, rc);
  addClipOptions(app, rc);
  app.add_option("--branching", rc.branching, "full (both Fresnel branches) | report (Algorithm 1)");
  app.add_option("--eye", text.eye, "camera position x,y,z");
  app.add_option("--target", text.target, "camera target x,y,z");
  app.add_option("--up", text.up, "camera up x,y,z");
  app.add_option("--fov", rc.fov, "vertical field of view in degrees");
  app.add_option("--exposure", rc.exposure, "exposure multiplier");
  app.add_option("--aa", rc.aa, "anti-aliasing: none | smaa | smaa-low|medium|high|ultra | ssaa4 | ssaa16");
  app.add_option("--smaa-preset", rc.smaaPreset, "SMAA quality: low | medium | high | ultra");
  app.add_option("--smaa-edges", rc.smaaEdges, "SMAA edge detection: luma (default) | color | geometry (luma, between different primitives only)");
  app.add_option("--texture-lod", rc.textureLod,
                 "texture level of detail: none (level 0) | cones (ray cones) | cones-aniso (ray cones, anisotropic)");
  app.add_option("--robust", rc.robust,
                 "fast | tri | box | ulp | tri+box | tri+ulp | box+ulp | watertight (default: watertight triangles, "
                 "Ize boxes, ULP offsets; fast = the seed's)");
  app.add_flag("--cpu", rc.cpu, "render with the C++ mirror instead of OpenGL");
  app.add_option("--camera-path", rc.cameraPath, "time frames along a recorded camera path (image: pose 0)");
}

void applyRenderCliText(RenderCommand& rc, const RenderCliText& text) {
  if (!text.eye.empty()) rc.eye = parseVec3(text.eye, "--eye");
  if (!text.target.empty()) rc.target = parseVec3(text.target, "--target");
  if (!text.up.empty()) rc.up = glm::vec3(parseVec3(text.up, "--up"));
}

RenderCommand parseRenderArgs(const std::vector<std::string>& args) {
  CLI::App app{"render"};
  RenderCommand rc;
  RenderCliText text;
  addRenderOptions(app, rc, text);
  std::vector<std::string> reversed(args.rbegin(), args.rend());  // CLI11 parses a vector back to front
  try {
    app.parse(reversed);
  } catch (const CLI::ParseError& e) {
    throw std::invalid_argument(std::string("render arguments: ") + e.what());
  }
  applyRenderCliText(rc, text);
  return rc;
}

}  // namespace bvhlab
