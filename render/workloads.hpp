// Ray workloads for `bvhlab trace`: buffers of rays generated on the CPU, deterministically
// from a seed, over a scene's triangles. What each one is there for:
//   primary   camera rays through a grid of pixel centres (coherent; what `render` traces first)
//   shadow    from primary hits to one of the scene's lights, ending at a point light (any hit)
//   specular  mirror bounces of primary hits (coherent on smooth surfaces, scattered on scans)
//   diffuse   cosine-weighted hemisphere directions at primary hits: the incoherent case
//   ao        the same directions, shortened to a fraction of the scene's diagonal (any hit)
// Secondary rays start at a primary hit, offset off the surface with the renderer's ULP offset
// (shaders/offset_ulp.hpp), towards the side they leave on.
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "datasets/scene.hpp"
#include "layout/layout.hpp"
#include "traversal/ray_batch.hpp"

namespace bvhlab {

enum class Workload { Primary, Shadow, Specular, Diffuse, Ao };
Workload parseWorkload(const std::string& name);  // throws std::invalid_argument naming the valid ones
const char* workloadName(Workload w);
const std::vector<std::string>& workloadNames();
inline bool isAnyHit(Workload w) { return w == Workload::Shadow || w == Workload::Ao; }

struct WorkloadRequest {
  Workload workload = Workload::Primary;
  uint32_t count = 1u << 17;  // rays wanted (secondary workloads: one per selected primary hit)
  uint64_t seed = 1;
  float aoRadius = 0.1f;      // ao ray length as a fraction of the triangles' bounding-box diagonal
  int width = 16, height = 9; // image aspect the primary grid keeps (the scene's settings)
};

// The closest hits of a batch (the generator's way to find primary hits; `trace` passes Embree).
using ClosestHitFn = std::function<std::vector<BatchHit>(const std::vector<BatchRay>&)>;

struct RayWorkload {
  Workload workload = Workload::Primary;
  std::vector<BatchRay> rays;
  uint32_t gridWidth = 0, gridHeight = 0;  // the primary grid the hits came from
  uint32_t primaryHits = 0;                // hits on that grid
  float aoDistance = 0.0f;                 // ao: the rays' tMax
};

// Throws std::invalid_argument for a bad request (count 0 or above kMaxTraceRays, ao radius not in
// (0, 1]), and InputError when the workload cannot be built (no triangle seen, no light for shadows).
RayWorkload generateWorkload(const WorkloadRequest& request, const Scene& scene, const TriangleSoup& soup,
                             const ClosestHitFn& closest);

// Rays per batch at most: 2^24 rays are 512 MiB of rays and 256 MiB of results on the GPU.
constexpr uint32_t kMaxTraceRays = 1u << 24;

}  // namespace bvhlab
