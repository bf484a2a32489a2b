// Embree 3 tracing the same triangles and the same ray batch as a GLSL kernel: the external
// yardstick of `bvhlab trace`. Embree builds its own BVH (quality MEDIUM, its default), in robust
// mode (RTC_SCENE_FLAG_ROBUST: watertight edges, the counterpart of the watertight triangle test)
// unless `robust` is false (Embree's default, faster test: the counterpart of the fast one), and
// traces with rtcIntersect1 / rtcOccluded1 on `threads` threads, each taking an interleaved share of
// rays. Robust mode costs Embree 8% of its time on the bunny's primary rays and 14% on diffuse ones
// (docs/layouts.md), about what the watertight test costs a GLSL kernel, so a ratio to Embree compares
// like with like only when the two tests match.
#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include "layout/layout.hpp"
#include "traversal/ray_batch.hpp"

namespace bvhlab {

class EmbreeTracer {
 public:
  // threads = 0: std::thread::hardware_concurrency(). Throws std::runtime_error with Embree's error.
  EmbreeTracer(const TriangleSoup& soup, unsigned threads = 0, bool robust = true);
  ~EmbreeTracer();
  EmbreeTracer(const EmbreeTracer&) = delete;
  EmbreeTracer& operator=(const EmbreeTracer&) = delete;

  // Closest hits (prim = soup index) or any-hit answers into `out` (resized); returns wall-clock ms.
  double closest(const std::vector<BatchRay>& rays, std::vector<BatchHit>& out) const;
  double occluded(const std::vector<BatchRay>& rays, std::vector<BatchHit>& out) const;
  unsigned threads() const { return threads_; }
  double buildMs() const { return buildMs_; }
  bool robust() const { return robust_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  unsigned threads_ = 1;
  double buildMs_ = 0.0;
  bool robust_ = true;
};

}  // namespace bvhlab
