// runClip (builders/update.hpp): a strategy over a clip's frames, one record per frame.
#include <chrono>
#include <stdexcept>

#include "builders/epo.hpp"
#include "builders/update.hpp"

namespace bvhlab {

std::vector<UpdateRecord> runClip(UpdateStrategy& strategy, uint32_t frameCount, const FrameSource& frame,
                                  const ClipOptions& options, const FrameCallback& onFrame) {
  std::vector<UpdateRecord> records;
  records.reserve(frameCount);
  size_t firstCount = 0;
  for (uint32_t f = 0; f < frameCount; ++f) {
    const FrameTriangles triangles = frame(f);
    if (f == 0)
      firstCount = triangles.size();
    else if (triangles.size() != firstCount)
      throw std::invalid_argument("clip: frame " + std::to_string(f) + " has " + std::to_string(triangles.size()) +
                                  " triangles, frame 0 had " + std::to_string(firstCount));
    UpdateRecord record;
    record.frame = f;
    const auto start = std::chrono::steady_clock::now();
    record.rebuilt = strategy.update(triangles);
    const auto stop = std::chrono::steady_clock::now();
    record.updateMs = std::chrono::duration<double, std::milli>(stop - start).count();
    record.rotations = strategy.rotations();
    const Bvh& tree = strategy.tree();
    record.sahCost = sahCost(tree, strategy.options().build.cost);
    if (options.epo)
      record.epo = endPointOverlap(tree, triangles.v0, triangles.v1, triangles.v2, strategy.options().build.cost,
                                   options.epoThreads);
    if (onFrame) onFrame(f, tree, record);
    records.push_back(std::move(record));
  }
  return records;
}

std::vector<UpdateRecord> runClip(UpdateStrategy& strategy, std::span<const FrameTriangles> frames,
                                  const ClipOptions& options, const FrameCallback& onFrame) {
  if (frames.size() > UINT32_MAX) throw std::invalid_argument("clip: more than 2^32 - 1 frames");
  return runClip(strategy, uint32_t(frames.size()), [&](uint32_t f) { return frames[f]; }, options, onFrame);
}

}  // namespace bvhlab
