// One configured render, in the three steps `render` and `measure` share:
//   1. setupRender: the command line checked and the scene loaded with its settings applied (no GL);
//   2. prepareScene (render/prepared_scene.hpp): the tree built; jobs with equal treeKey() may share it;
//   3. GpuJob: the GL state (needs a current context): timed frames, then the image and the counts,
//      and renderJson(): the object `render --json` prints.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "render/fly_camera.hpp"
#include "render/gl_context.hpp"
#include "render/gpu_renderer.hpp"
#include "render/prepared_scene.hpp"
#include "render/render_command.hpp"
#include "render/smaa.hpp"
#include "shaders/assemble.hpp"

namespace bvhlab {

struct RenderSetup {
  CameraPath path;  // empty = the scene's (or the command line's) camera
  Scene scene;      // loaded, settings and camera applied; moved into prepareScene
  ShaderOptions shader;
  BuildOptions build;
  OptionReview buildReview;  // the leaf size the builder honours; warnings for options it ignores
  Backend backend = Backend::OSMesa;
  bool smaaOn = false;
  std::string smaaPreset;
  SmaaSettings smaa;
};

// Validates every option (throws std::invalid_argument / InputError naming the flag) and loads the
// input. `loaded`: a copy of loadInput(cmd.input) to start from instead of reading the file again.
RenderSetup setupRender(const RenderCommand& cmd, const Scene* loaded = nullptr);

// The command's build options, checked (throws std::invalid_argument naming the flag) and reviewed
// against the builder (builders/builder.hpp reviewBuildOptions); needs no input file.
BuildOptions renderBuildOptions(const RenderCommand& cmd, OptionReview* review = nullptr);

// Commands with the same key build the same PreparedScene (input, scene settings, camera, layout,
// builder, leaf size, bins): `measure` builds each tree once for all the kernels and knobs that use it.
std::string treeKey(const RenderCommand& cmd);

// The GL side of one render. Keeps `prepared` alive; needs a current context for its whole life.
class GpuJob {
 public:
  // `programs`: draw with the cache's program for this shader source (render/program_cache.hpp),
  // else compile one of its own. `stackSize`: BVH_STACK_SIZE at least this (0: the tree's own bound,
  // stackSizeFor): a group gives all runs of one layout the same, so that their shaders are one text.
  GpuJob(const RenderCommand& cmd, const RenderSetup& setup, std::shared_ptr<const PreparedScene> prepared,
         ProgramCache* programs = nullptr, int stackSize = 0);
  // One frame (the trace, plus the SMAA passes when on, each waited for with glFinish), drawn from
  // camera-path pose index mod N. Returns its wall-clock ms; `aaMs` gets the SMAA part.
  double frame(int index, double& aaMs);
  // Draws pose 0 (for a camera path), reads the image back, and renders one more frame with the
  // statistics counters compiled in (timed frames run without them). Frees the timed shader.
  void finish(bool wantStats);

  const PreparedScene& prepared() const { return *prepared_; }
  const ShaderOptions& shader() const { return shader_; }
  const FrameOptions& frameOptions() const { return frame_; }
  int programIndex() const { return programIndex_; }  // in the cache; -1: its own program
  std::vector<uint8_t> image;     // RGBA8, rows bottom-up (after finish)
  std::vector<glm::uvec4> stats;  // per pixel (after finish(true))
  std::vector<uint32_t> boxTests;  // per pixel, ray-box tests (after finish(true))

 private:
  std::shared_ptr<const PreparedScene> prepared_;
  ShaderOptions shader_;
  FrameOptions frame_;
  CameraPath path_;
  ProgramCache* programs_ = nullptr;
  int programIndex_ = -1;
  std::unique_ptr<GpuRenderer> gpu_;
  std::unique_ptr<SmaaPass> smaa_;
};

// Frame times of one run and how their measurement ended (measure: "target" | "max_frames" | "fixed").
struct FrameTimes {
  std::vector<double> ms, aaMs;
  std::string stop = "fixed";
  double targetCiPct = 0.0;  // 0 = no target
};

// Writes the image and heatmap the command asks for and returns `render --json`'s object (keys:
// README "Using it"; frame_ms with its 95% interval, counts per ray, tree_hash, epo, ray_cost).
// `stats` empty = no counts (the --cpu path passes the mirror's); `boxTests` per pixel beside them.
nlohmann::json finishRender(const RenderCommand& cmd, const RenderSetup& setup, const PreparedScene& prepared,
                            const FrameOptions& frame, std::vector<uint8_t> image,
                            const std::vector<glm::uvec4>& stats, const std::vector<uint32_t>& boxTests,
                            const FrameTimes& times,
                            const std::string& renderer, bool cpu);

// Pixels whose traversal stack overflowed (main.glsl's stats z bit 31): a render with any is an error.
uint64_t stackOverflowPixels(const std::vector<glm::uvec4>& stats);

}  // namespace bvhlab
