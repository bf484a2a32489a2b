#include "render/clip_update.hpp"

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <string>

#include "datasets/animation.hpp"

namespace bvhlab {

ClipPlan planClip(const RenderCommand& cmd, const Scene& scene) {
  try {
    parseUpdateSpec(cmd.update);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("--update: ") + e.what());
  }
  if (cmd.updateRepeats < 1) throw std::invalid_argument("--update-repeats must be >= 1");
  if (cmd.clipFrames < 0 || cmd.clipStep < 1) throw std::invalid_argument("--clip-frames must be >= 0 and --clip-step >= 1");
  ClipPlan p;
  p.sceneFrames = clipFrames(scene);
  if (p.sceneFrames <= 1)
    throw std::invalid_argument("--update: " + cmd.input +
                                " is not animated (its clip has 1 frame); --update needs a scene with a clip");
  p.step = cmd.clipStep;
  p.count = (p.sceneFrames + p.step - 1) / p.step;
  if (cmd.clipFrames > 0) p.count = std::min(p.count, cmd.clipFrames);
  return p;
}

ClipUpdater::ClipUpdater(const RenderCommand& cmd, const BuildOptions& build) {
  options_.builder = cmd.builder;
  options_.build = build;
  for (int k = 0; k < cmd.updateRepeats; ++k) {
    try {
      copies_.push_back(makeUpdateStrategy(cmd.update, options_));
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(std::string("--update: ") + e.what());
    }
  }
}

ClipUpdater::Step ClipUpdater::update(const TriangleSoup& soup) {
  Step s;
  const FrameTriangles frame{soup.v0, soup.v1, soup.v2};
  for (size_t k = 0; k < copies_.size(); ++k) {
    const auto start = std::chrono::steady_clock::now();
    const bool rebuilt = copies_[k]->update(frame);
    s.ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    const double sah = sahCost(copies_[k]->tree(), options_.build.cost);
    if (k == 0) {
      s.rebuilt = rebuilt;
      s.sah = sah;
    } else if (rebuilt != s.rebuilt || sah != s.sah) {
      s.agree = false;
    }
  }
  return s;
}

}  // namespace bvhlab
