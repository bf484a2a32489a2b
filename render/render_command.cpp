#include "render/render_command.hpp"

#include <iostream>

#include <nlohmann/json.hpp>

#include "render/exit_status.hpp"
#include "render/render_clip.hpp"
#include "render/render_job.hpp"
#include "shaders/tracer.hpp"

namespace bvhlab {

int runRender(const RenderCommand& cmd) {
  if (!cmd.update.empty()) return runRenderClip(cmd);
  RenderSetup setup = setupRender(cmd);
  for (const std::string& w : setup.buildReview.warnings) std::cerr << "bvhlab: warning: " << w << '\n';
  std::shared_ptr<const PreparedScene> prepared = prepareScene(std::move(setup.scene), cmd.builder, setup.build, setup.shader.layout,
                                                               setup.shader.triangles);
  const bool wantStats = cmd.json || cmd.view == "visits" || !cmd.visitsOutput.empty();

  FrameTimes times;
  std::vector<uint8_t> image;
  std::vector<glm::uvec4> stats;
  std::vector<uint32_t> boxTests;
  std::string renderer;
  FrameOptions fo;
  if (cmd.cpu) {
    ShaderOptions so = setup.shader;
    so.countStats = true;
    so.bvhStackSize = stackSizeFor(prepared->packed);
    fo.width = prepared->scene.settings.width;
    fo.height = prepared->scene.settings.height;
    fo.camera = prepared->scene.camera;
    fo.exposure = prepared->scene.settings.exposure;
    ReferenceImage ref = renderReference(prepared->scene, prepared->data, prepared->packed, so, fo);
    image = std::move(ref.rgba);
    stats = std::move(ref.stats);
    boxTests = std::move(ref.boxTests);
    times.ms.push_back(ref.ms);
    renderer = "bvhlab C++ mirror";
  } else {
    std::unique_ptr<GlContext> ctx = createContext(setup.backend);
    renderer = ctx->renderer();
    GpuJob job(cmd, setup, prepared);
    fo = job.frameOptions();
    double aaMs = 0.0;
    for (int i = 0; i < cmd.warmup; ++i) job.frame(i, aaMs);  // llvmpipe JIT-compiles at the first draw
    for (int i = 0; i < cmd.frames; ++i) {
      times.ms.push_back(job.frame(i, aaMs));
      if (setup.smaaOn) times.aaMs.push_back(aaMs);
    }
    job.finish(wantStats);
    image = std::move(job.image);
    stats = std::move(job.stats);
    boxTests = std::move(job.boxTests);
  }

  const nlohmann::json out = finishRender(cmd, setup, *prepared, fo, std::move(image), stats, boxTests, times, renderer,
                                            cmd.cpu);
  if (cmd.json) std::cout << out.dump() << std::endl;
  // Say what was written: on stdout for a person, on stderr when stdout carries the JSON.
  std::ostream& say = cmd.json ? std::cerr : std::cout;
  if (!cmd.json)
    say << "bvhlab: " << out["width"].get<int>() << "x" << out["height"].get<int>() << ", " << out["frames"].get<int>()
        << (out["frames"].get<int>() == 1 ? " frame" : " frames") << ", median " << out["frame_ms"].get<double>() << " ms on "
        << renderer << '\n';
  if (!cmd.output.empty()) say << "bvhlab: wrote " << cmd.output << '\n';
  if (!cmd.visitsOutput.empty()) say << "bvhlab: wrote " << cmd.visitsOutput << " (node visits per pixel)\n";
  if (const uint64_t overflows = stackOverflowPixels(stats); overflows > 0) {
    std::cerr << "bvhlab: error: traversal stack overflowed in " << overflows << " pixels\n";
    return kExitFailure;  // a runtime failure: the image is wrong
  }
  return 0;
}

}  // namespace bvhlab
