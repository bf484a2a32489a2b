// bvhlab — command line. Each subcommand is a thin shell over a library call; every error ends in
// "bvhlab: error: ..." on stderr and exit status 2 (usage) or 1 (runtime failure): render/exit_status.hpp.
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <sstream>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "builders/builder.hpp"
#include "builders/epo.hpp"
#include "datasets/scene.hpp"
#include "datasets/scene_io.hpp"
#include "experiments/findings_command.hpp"
#include "experiments/provenance.hpp"
#include "experiments/runner.hpp"
#include "builders/gpu/gpu_builders.hpp"
#include "builders/gpu/gpu_pack.hpp"
#include "layout/layout.hpp"
#include "layout/layouts.hpp"
#include "layout/triangle_formats.hpp"
#include "layout/tree_hash.hpp"
#include "render/exit_status.hpp"
#include "render/gpu_renderer.hpp"
#include "render/hard_cases_command.hpp"
#include "render/measure_command.hpp"
#include "render/render_cli.hpp"
#include "render/render_command.hpp"
#include "render/render_job.hpp"
#include "render/trace_command.hpp"
#include "render/viewer.hpp"
#include "traversal/kernels.hpp"

using namespace bvhlab;

namespace {

struct BuildCommand {
  std::string mesh, builder = "sah-binned", optimize, layout = kDefaultLayout, triangles = kDefaultTriangleFormat;
  int leafSize = 4, bins = 0, plocRadius = 16, plocTopDown = 0, mortonSizeBits = 0;
  std::string mortonGrid = "cube";
  float sbvhAlpha = 1e-5f, sbvhBudget = 2.0f;
  bool json = false;
  int gpuBuilds = 11;  // GPU builders with --json: GL-timed builds after a warm-up
};

int buildCommand(const BuildCommand& c) {
  // The same checks and warnings as render's (render/render_job.hpp), before the mesh is read.
  RenderCommand asRender;
  asRender.builder = c.builder;
  asRender.leafSize = c.leafSize;
  asRender.bins = c.bins;
  asRender.optimize = c.optimize;
  asRender.sbvhAlpha = c.sbvhAlpha;
  asRender.sbvhBudget = c.sbvhBudget;
  asRender.plocRadius = c.plocRadius;
  asRender.plocTopDown = c.plocTopDown;
  asRender.mortonSizeBits = c.mortonSizeBits;
  asRender.mortonGrid = c.mortonGrid;
  OptionReview review;
  const BuildOptions options = renderBuildOptions(asRender, &review);
  const LayoutInfo& layout = findLayout(c.layout);
  const std::string& triangleFormat = findTriangleFormat(c.triangles).name;
  for (const std::string& w : review.warnings) std::fprintf(stderr, "bvhlab: warning: %s\n", w.c_str());
  Scene scene = loadInput(c.mesh);
  TriangleSoup soup = gatherTriangles(scene);
  if (soup.size() == 0) throw InputError(c.mesh + ": no triangles to build a BVH over");
  std::vector<Aabb> boxes = triangleBoxes(soup);
  std::vector<glm::vec3> centroids = triangleCentroids(soup);
  BuildStats stats;
  Bvh bvh = buildBvh(c.builder, BuildInput{boxes, centroids, soup.v0, soup.v1, soup.v2}, options, &stats);
  PackedBvh packed = layout.pack(bvh, soup);
  packTriangles(packed, soup, triangleFormat);
  stats.bytes = packed.bytes();
  const double epo = endPointOverlap(bvh, soup.v0, soup.v1, soup.v2, options.cost);
  if (c.json) {
    nlohmann::json j = {{"mesh", c.mesh},
                        {"builder", c.builder},
                        {"optimize", c.optimize.empty() ? nlohmann::json() : nlohmann::json(c.optimize)},
                        {"leaf_size", stats.leafSize},  // what the leaves were limited to
                        {"leaf_size_requested", c.leafSize},
                        {"sbvh_alpha", options.sbvhAlpha},
                        {"sbvh_budget", options.sbvhReferenceBudget},
                        {"ploc_radius", options.plocRadius},
                        {"ploc_top_down", options.plocTopDown},
                        {"morton_size_bits", options.mortonSizeBits},
                        {"morton_grid", mortonGridName(options.mortonGrid)},
                        {"warnings", review.warnings},
                        {"primitives", stats.primitives},
                        {"references", stats.references},
                        {"nodes", stats.nodes},
                        {"leaves", stats.leaves},
                        {"depth", stats.depth},
                        {"sah_cost", stats.sahCost},
                        {"sah_before_optimize", stats.sahBeforeOptimize},
                        {"epo", epo},
                        {"build_ms", stats.buildMs},
                        {"optimize_ms", stats.optimizeMs},
                        {"layout", layout.name},
                        {"triangle_format", triangleFormat},
                        {"vertices", packed.vertices.size()},
                        {"bytes", stats.bytes},
                        {"bytes_per_triangle", double(stats.bytes) / double(stats.primitives)},
                        {"tree_hash", packedTreeHash(packed)},
                        {"prims_per_leaf_mean", stats.primsPerLeafMean},
                        {"prims_per_leaf_max", stats.primsPerLeafMax}};
    if (findBuilder(c.builder).gpu) {  // GL timer queries per phase over repeated builds
      // v1, bvh2-cb and cwbvh with raw triangles are packed on the GPU too (phase `pack`, and the wide_*
      // phases for cwbvh), checked against the CPU's.
      // A pack whose buffers pass the GL limits where the build's alone do not is left out (said in
      // gpu_pack_refused), so the build is still timed.
      const bool gpuPack = gpubuild::gpuPackable(layout.name) && triangleFormat == "raw";
      const BuildInput input{boxes, centroids, soup.v0, soup.v1, soup.v2};
      const size_t builds = size_t(std::max(c.gpuBuilds, 1));
      std::string packRefused;
      GpuBuildTiming t;
      try {
        t = timeGpuBuild(c.builder, input, options, builds, gpuPack ? layout.name : std::string(), &soup);
      } catch (const InputError& e) {
        const std::string what = e.what();
        if (!gpuPack || (what.find("(pack)") == std::string::npos && what.find("(cwbvh pack)") == std::string::npos))
          throw;
        packRefused = e.what();
        std::fprintf(stderr, "bvhlab: warning: %s; timed without the GPU pack\n", e.what());
        t = timeGpuBuild(c.builder, input, options, builds);
      }
      nlohmann::json total = {{"median", t.medianMs}, {"builds", t.builds}};
      if (t.totalMs) total["low"] = t.totalMs->low, total["high"] = t.totalMs->high;
      j["gpu_build_ms"] = total;
      nlohmann::json phases = nlohmann::json::object();
      for (const auto& [phase, ms] : t.phaseMedianMs) phases[phase] = ms;
      j["gpu_phases_ms"] = phases;
      if (t.passesIssued) {  // ploc-gpu's clustering passes and the CPU's reads of their state
        j["gpu_passes"] = t.passes;
        j["gpu_passes_issued"] = t.passesIssued;
        j["gpu_readbacks"] = t.readbacks;
      }
      // plocpp-gpu: fused passes that ran again split, over the timed builds (0 where none gave up).
      if (c.builder == "plocpp-gpu") j["gpu_fused_fallbacks"] = t.fusedFallbacks;
      j["gpu_renderer"] = t.renderer;
      j["gpu_pack"] = t.packLayout.empty() ? nlohmann::json() : nlohmann::json(t.packLayout);
      if (!packRefused.empty()) j["gpu_pack_refused"] = packRefused;
    }
    std::cout << j.dump() << std::endl;
  } else {
    std::printf("%s%s on %s: %zu triangles (%zu references), %zu nodes, %zu leaves, depth %u, SAH %.3f, EPO %.3f, "
                "%.2f ms, %zu bytes in layout %s with %s triangles\n",
                c.builder.c_str(), c.optimize.empty() ? "" : ("+" + c.optimize).c_str(), c.mesh.c_str(),
                stats.primitives, stats.references, stats.nodes, stats.leaves, stats.depth, stats.sahCost, epo,
                stats.buildMs, stats.bytes, layout.name.c_str(), triangleFormat.c_str());
  }
  return 0;
}

// A CLI11 parse failure (everything but --help and --version) as a usage error: one line naming the
// command, what CLI11 refused (it names the flag or argument) and where help is; exit status 2.
int reportParseError(CLI::App& app, const CLI::ParseError& e, int argc, char** argv) {
  std::vector<std::string> names;
  for (const CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) names.push_back(sub->get_name());
  const bool known = argc > 1 && std::find(names.begin(), names.end(), argv[1]) != names.end();
  if (argc < 2 || (!known && argv[1][0] != '-')) {
    // A mistyped or missing command: name it and list the real ones (CLI11 would only say that an
    // argument was not expected).
    std::string list;
    for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
    if (argc < 2)
      std::fprintf(stderr, "bvhlab: error: no command given; commands: %s (bvhlab COMMAND --help)\n", list.c_str());
    else
      std::fprintf(stderr, "bvhlab: error: unknown command '%s'; commands: %s (bvhlab COMMAND --help)\n", argv[1],
                   list.c_str());
    return kExitUsage;
  }
  if (!known) {  // an option before any command (CLI11 would only ask for a command)
    std::fprintf(stderr, "bvhlab: error: unknown option '%s' (options follow the command: bvhlab COMMAND --help)\n",
                 argv[1]);
    return kExitUsage;
  }
  const std::vector<CLI::App*> selected = app.get_subcommands();
  const std::string command = selected.empty() ? std::string() : selected.front()->get_name();
  std::fprintf(stderr, "bvhlab: error: %s%s (bvhlab %s--help)\n", command.empty() ? "" : (command + ": ").c_str(),
               e.what(), command.empty() ? "" : (command + " ").c_str());
  return kExitUsage;
}

}  // namespace

int main(int argc, char** argv) {
  registerGpuBuilders();  // lbvh-gpu and ploc-gpu beside the CPU builders, wherever a builder name is accepted
  CLI::App app{"bvhlab: a testbed for BVH construction strategies in a GLSL Whitted ray tracer"};
  app.require_subcommand(1);

  RenderCommand rc;
  auto* render = app.add_subcommand("render", "render a scene file or a bare mesh (OBJ/OFF/PLY/STL)");
  RenderCliText renderText;
  addRenderOptions(*render, rc, renderText);

  TraceCommand tc;
  RenderCliText traceText;
  auto* traceCmd = app.add_subcommand(
      "trace", "trace a ray workload (primary/shadow/specular/diffuse/ao) with a GLSL kernel and Embree, interleaved");
  addTraceOptions(*traceCmd, tc, traceText);

  MeasureCommand mc;
  auto* measureCmd = app.add_subcommand(
      "measure", "time a group of renders, or of traced runs (\"command\": \"trace\"), interleaved in one process (what `bvhlab run` calls; experiments/README.md)");
  measureCmd->add_option("spec", mc.spec, "group file (JSON: the runs' render or trace arguments and the [measure] settings)")
      ->required()
      ->check(notADirectory("a group file (JSON)"));

  BuildCommand bc;
  auto* build = app.add_subcommand("build", "build a BVH over a mesh and print its statistics");
  build->option_defaults()->always_capture_default();
  build->add_option("--mesh", bc.mesh, "mesh or scene file")->required()->check(notADirectory("a mesh or scene file"));
  build->add_option("--builder", bc.builder, "BVH builder");
  build->add_option("--layout", bc.layout, "texture layout to pack into (bytes, tree_hash; see `bvhlab layouts`)");
  build->add_option("--triangles", bc.triangles, "triangle format: raw | precomputed | indexed (see `bvhlab layouts`)");
  build->add_option("--leaf-size", bc.leafSize, "max triangles per leaf");
  build->add_option("--bins", bc.bins, "bins for sah-binned and sbvh (0 = default)");
  build->add_option("--optimize", bc.optimize, "post-pass after the builder: reinsert (Bittner et al. 2013)");
  build->add_option("--sbvh-alpha", bc.sbvhAlpha, "sbvh: overlap threshold for spatial splits");
  build->add_option("--sbvh-budget", bc.sbvhBudget, "sbvh: at most this many leaf references per primitive, >= 1 (1: no spatial splits)");
  build->add_option("--ploc-radius", bc.plocRadius, "ploc: nearest-neighbour search radius");
  build->add_option("--ploc-top-down", bc.plocTopDown,
                    "ploc: split the last n/F clusters top-down by binned SAH, 0..1024 (0 = cluster to the end)");
  build->add_option("--morton-size-bits", bc.mortonSizeBits,
                    "ploc, lbvh: primitive-size bits in the Morton codes, 0..9 (0 = position only)");
  build->add_option("--morton-grid", bc.mortonGrid,
                    "ploc, lbvh: the Morton codes' grid: cube (one cell size on every axis) | axes (each axis over its own extent)");
  build->add_flag("--json", bc.json, "print JSON");
  build->add_option("--gpu-builds", bc.gpuBuilds, "GPU builders with --json: GL-timed builds after a warm-up (median and interval)")
      ->check(CLI::Range(1, 1000));

  RunOptions ro;
  std::string config, outDir, shard, binary;
  bool noRetry = false, noReport = false;
  auto* runCmd = app.add_subcommand("run", "run an experiment config (a sweep) and write its report");
  runCmd->add_option("config", config, "experiment config .toml (see experiments/README.md)")
      ->required()
      ->check(notADirectory("an experiment config .toml (experiments/configs/ has examples)"));
  runCmd->add_option("--out", outDir, "output directory (default results/<experiment name>)");
  runCmd->add_option("--shard", shard, "run only slice I of N: I/N");
  runCmd->add_flag("--no-retry", noRetry, "keep failed runs as failed instead of retrying them");
  runCmd->add_flag("--no-report", noReport, "do not write report.html at the end");
  runCmd->add_option("--binary", binary, "renderer executable (default: this bvhlab)");
  runCmd->add_option("--replicates", ro.replicates,
                     "measure the sweep R times over, each pass after the previous one, and pool every comparison "
                     "over the passes (default: the config's [experiment] replicates, else 1; experiments/README.md)")
      ->check(CLI::Range(1, kMaxReplicates));

  std::vector<std::string> mergeDirs;
  std::string mergeOut;
  auto* mergeCmd = app.add_subcommand("merge", "combine shard output directories and regenerate the report");
  mergeCmd->add_option("dirs", mergeDirs, "shard output directories")->required();
  mergeCmd->add_option("--out", mergeOut, "merged output directory")->required();
  bool mergeReplicates = false;
  mergeCmd->add_flag("--replicates", mergeReplicates,
                     "the directories are repetitions of one sweep: keep each as its own replicates and pool "
                     "the comparisons over them (--out must be a new directory)");

  std::string reportDir;
  auto* reportCmd = app.add_subcommand("report", "regenerate DIR/report.html from DIR/results.json");
  reportCmd->add_option("dir", reportDir, "experiment output directory")->required();

  std::string findingsDir;
  bool findingsCheck = false;
  auto* findingsCmd = app.add_subcommand(
      "findings", "compute DIR/findings.json again from DIR/results.json with the current rules (docs/measurement.md)");
  findingsCmd->add_option("dir", findingsDir, "experiment output directory (with results.json)")->required();
  findingsCmd->add_flag("--check", findingsCheck,
                        "write nothing; exit 1 naming the first difference when DIR/findings.json does not follow "
                        "from the rows");

  ViewerOptions vo;
  std::string viewEye, viewTarget, viewUp;
  auto* viewCmd = app.add_subcommand("view", "interactive first-person viewer (needs a display; docs/viewer.md)");
  viewCmd->option_defaults()->always_capture_default();
  viewCmd->add_option("input", vo.input, "scene .toml or mesh file")
      ->required()
      ->check(notADirectory("a scene .toml or a mesh file (OBJ/OFF/PLY/STL)"));
  viewCmd->add_option("--width", vo.width, "window width");
  viewCmd->add_option("--height", vo.height, "window height");
  viewCmd->add_option("--builder", vo.builder, "initial BVH builder (B cycles)");
  viewCmd->add_option("--optimize", vo.optimize, "post-pass after every build: reinsert");
  viewCmd->add_option("--layout", vo.layout, "texture layout of the tree for the session (see `bvhlab layouts`)");
  viewCmd->add_option("--triangles", vo.triangles,
                      "triangle format for the session: raw | precomputed | indexed (see `bvhlab layouts`)");
  viewCmd->add_option("--kernel", vo.kernel,
                      "initial traversal kernel of that layout (K cycles through its kernels; default: the layout's)");
  viewCmd->add_option("--leaf-size", vo.leafSize, "initial max triangles per leaf (L / Shift+L)");
  viewCmd->add_option("--depth", vo.depth, "initial max path depth ([ and ])");
  viewCmd->add_option("--view", vo.view, "shaded | normal | depth | primid | visits (V cycles)");
  viewCmd->add_option("--scale", vo.resolutionScale, "render at this fraction of the window (0.05..1)");
  viewCmd->add_option("--aa", vo.aa, "none | smaa-low|medium|high|ultra | ssaa4 | ssaa16 (M cycles)");
  viewCmd->add_option("--robust", vo.robust, "robustness variant, as render --robust (T cycles)");
  viewCmd->add_option("--texture-lod", vo.textureLod, "none | cones | cones-aniso, as render --texture-lod");
  viewCmd->add_flag("--readback-present", vo.readbackPresent, "display via CPU read-back (to measure the blit)");
  viewCmd->add_option("--eye", viewEye, "camera position x,y,z");
  viewCmd->add_option("--target", viewTarget, "camera target x,y,z");
  viewCmd->add_option("--up", viewUp, "camera up x,y,z");
  viewCmd->add_option("--fov", vo.fov, "vertical field of view in degrees");
  viewCmd->add_option("--script", vo.script, "scripted input file (frame-numbered key presses / poses)");
  viewCmd->add_option("--frames", vo.frames, "stop after N frames (0 = when closed / the script ends)");
  viewCmd->add_option("--screenshot", vo.screenshot, "write the last frame (without overlay) here");
  viewCmd->add_option("--record", vo.record, "record the camera path to this file (one pose per line)");
  viewCmd->add_option("--replay", vo.replay, "replay a recorded camera path");
  viewCmd->add_option("--update", vo.update,
                       "animated scene: the tree's update strategy while the clip plays (default rebuild; U cycles)");
  viewCmd->add_flag("--paused", vo.paused, "animated scene: start with the clip paused (Space plays)");
  viewCmd->add_flag("--json", vo.json, "print the final state and every switch as JSON");
  viewCmd->add_flag("!--no-overlay", vo.overlay, "hide the ImGui overlay");


  HardCasesCommand hc;
  auto* hardCmd = app.add_subcommand("hard-cases", "robustness variants on the hard-case suite: leaks, exact-oracle disagreement");
  hardCmd->option_defaults()->always_capture_default();
  hardCmd->add_option("--robust", hc.robust, "variant to run (repeatable; default: every variant)");
  hardCmd->add_option("--json", hc.json, "write the results as JSON here ('-' = stdout)");
  hardCmd->add_flag("--gpu", hc.gpu, "also count the GLSL kernel's leaks (camera inside closed meshes)");
  hardCmd->add_option("--backend", hc.backend, "osmesa | egl (with --gpu)");
  hardCmd->add_option("--layout", hc.layout, "texture layout the cases' trees are packed in (see `bvhlab layouts`)");
  hardCmd->add_option("--kernel", hc.kernel, "traversal kernel of that layout (default: the layout's)");
  hardCmd->add_option("--builder", hc.builder, "BVH builder");
  auto* listBuilders = app.add_subcommand("builders", "list the BVH builders");
  auto* listKernels = app.add_subcommand("kernels", "list the traversal kernels (and the layout each walks)");
  auto* listLayouts = app.add_subcommand("layouts", "list the texture layouts, the kernels that walk each, and the triangle formats");

  // --version: the release and the commit of the source tree it runs from (as the run records say).
  app.set_version_flag("--version", [] {
    return std::string("bvhlab ") + BVHLAB_VERSION + " (commit " + gitCommit(findSourceDir()) + ")";
  });
  app.footer(kExitStatusHelp);  // after the subcommands: they would copy it
  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {
    return app.exit(e);  // --help, --help-all, --version: printed on stdout, exit status 0
  } catch (const CLI::ParseError& e) {
    return reportParseError(app, e, argc, argv);
  }
  try {
    if (render->parsed()) {
      applyRenderCliText(rc, renderText);
      return runRender(rc);
    }
    if (measureCmd->parsed()) return runMeasure(mc);
    if (traceCmd->parsed()) {
      applyRenderCliText(tc.render, traceText);
      return runTrace(tc);
    }
    if (viewCmd->parsed()) {
      if (!viewEye.empty()) vo.eye = parseVec3(viewEye, "--eye");
      if (!viewTarget.empty()) vo.target = parseVec3(viewTarget, "--target");
      if (!viewUp.empty()) vo.up = glm::vec3(parseVec3(viewUp, "--up"));
      return runViewer(vo);
    }
    if (runCmd->parsed()) {
      ro.config = config;
      ro.outDir = outDir;
      if (!shard.empty()) std::tie(ro.shardIndex, ro.shardCount) = parseShard(shard);
      ro.retryFailed = !noRetry;
      ro.report = !noReport;
      ro.binary = binary;
      return runCommand(ro);
    }
    if (mergeCmd->parsed())
      return mergeCommand(std::vector<std::filesystem::path>(mergeDirs.begin(), mergeDirs.end()), mergeOut,
                          mergeReplicates);
    if (reportCmd->parsed()) return reportCommand(reportDir);
    if (findingsCmd->parsed()) return findingsCommand(findingsDir, findingsCheck);
    if (hardCmd->parsed()) return runHardCases(hc);
    if (build->parsed()) return buildCommand(bc);
    if (listBuilders->parsed()) {
      for (const BuilderInfo& b : builders())
        std::printf("%-12s %-3s %s\n", b.name.c_str(), b.gpu ? "gpu" : "cpu", b.description.c_str());
      return 0;
    }
    if (listKernels->parsed()) {
      for (const KernelInfo* k : allKernels())
        std::printf("%-20s %-8s %s\n", k->name.c_str(), k->layout.c_str(), k->description.c_str());
      return 0;
    }
    if (listLayouts->parsed()) {
      for (const LayoutInfo& l : layouts()) {
        std::string names;
        for (const KernelInfo& k : kernelsFor(l.name))
          names += (names.empty() ? "" : ", ") + k.name + (k.name == l.defaultKernel ? " (default)" : "");
        std::printf("%-8s %s\n         kernels: %s\n", l.name.c_str(), l.description.c_str(), names.c_str());
      }
      std::printf("\ntriangle formats (--triangles; any layout with any format):\n");
      for (const TriangleFormatInfo& f : triangleFormats())
        std::printf("%-12s %s%s\n", f.name.c_str(), f.description.c_str(),
                    f.name == kDefaultTriangleFormat ? " (default)" : "");
      return 0;
    }
  } catch (const std::exception& e) {
    return reportError(e);  // a ShaderError is a runtime failure like any other GL failure
  }
  return 0;
}
