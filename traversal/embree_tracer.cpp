#include "traversal/embree_tracer.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <stdexcept>
#include <string>
#include <thread>

#include <embree3/rtcore.h>

namespace bvhlab {

struct EmbreeTracer::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
  void check(const char* what) const {
    const RTCError e = rtcGetDeviceError(device);
    if (e != RTC_ERROR_NONE) throw std::runtime_error(std::string("embree: ") + what + " failed (error " + std::to_string(int(e)) + ")");
  }
};

namespace {

using Clock = std::chrono::steady_clock;

RTCRay toEmbree(const BatchRay& r) {
  RTCRay ray{};
  ray.org_x = r.origin.x;
  ray.org_y = r.origin.y;
  ray.org_z = r.origin.z;
  ray.dir_x = r.dir.x;
  ray.dir_y = r.dir.y;
  ray.dir_z = r.dir.z;
  ray.tnear = r.tMin;
  ray.tfar = r.tMax;
  ray.mask = ~0u;
  ray.flags = 0;
  return ray;
}

// Rays per share. Threads take chunks of consecutive rays, each the next one not yet taken (one
// atomic counter): a thread that meets costlier rays, or starts late, takes fewer chunks, and each
// chunk writes its own 768 bytes of hits. Ray i on thread i mod threads (the first share) had both
// threads writing into every cache line of the hits: on this 2-core machine that false sharing made
// Embree's time multimodal from process to process (bunny close view, 131,072 rays, medians of 7
// rounds in 11 alternating processes each: primary 12.2-12.7 ms in 7 of them and 17.5-19.1 ms in 4,
// diffuse 14.6-27.7 ms, against 12.2-13.0 and 14.4-21.4 ms with chunks of 64). Chunks taken in turn
// (the second share: chunk c on thread c mod threads) left the threads unbalanced where the image
// is: on the report scene's primary rays one thread took 9.8-10.7 ms and the other 7.4-8.4 ms in
// every round (docs/layouts.md).
constexpr size_t kRaysPerChunk = 64;

// Runs body(i) for every ray index on `threads` threads, each taking the next free chunk of
// kRaysPerChunk rays. Which thread traces a ray does not change its answer.
template <class Body>
double parallelRays(size_t n, unsigned threads, const Body& body) {
  const auto start = Clock::now();
  std::atomic<size_t> next{0};
  const auto share = [&] {
    for (size_t first; (first = next.fetch_add(kRaysPerChunk, std::memory_order_relaxed)) < n;)
      for (size_t i = first, end = std::min(n, first + kRaysPerChunk); i < end; ++i) body(i);
  };
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < threads; ++t) pool.emplace_back(share);
  share();
  for (std::thread& t : pool) t.join();
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

}  // namespace

EmbreeTracer::EmbreeTracer(const TriangleSoup& soup, unsigned threads, bool robust)
    : impl_(std::make_unique<Impl>()), robust_(robust) {
  threads_ = threads ? threads : std::max(1u, std::thread::hardware_concurrency());
  const auto start = Clock::now();
  const std::string config = "threads=" + std::to_string(threads_);
  impl_->device = rtcNewDevice(config.c_str());
  if (!impl_->device) throw std::runtime_error("embree: rtcNewDevice failed");
  impl_->scene = rtcNewScene(impl_->device);
  rtcSetSceneFlags(impl_->scene, robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
  rtcSetSceneBuildQuality(impl_->scene, RTC_BUILD_QUALITY_MEDIUM);
  RTCGeometry geom = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
  const size_t n = soup.size();
  auto* v = static_cast<float*>(
      rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), 3 * n));
  auto* idx = static_cast<unsigned*>(
      rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), n));
  if (!v || !idx) {
    rtcReleaseGeometry(geom);
    impl_->check("allocating the triangle buffers");
    throw std::runtime_error("embree: could not allocate the triangle buffers");
  }
  for (size_t i = 0; i < n; ++i) {
    const glm::vec3* vs[3] = {&soup.v0[i], &soup.v1[i], &soup.v2[i]};
    for (int k = 0; k < 3; ++k) {
      v[9 * i + 3 * k + 0] = vs[k]->x;
      v[9 * i + 3 * k + 1] = vs[k]->y;
      v[9 * i + 3 * k + 2] = vs[k]->z;
      idx[3 * i + k] = unsigned(3 * i + k);  // primID = soup index
    }
  }
  rtcCommitGeometry(geom);
  rtcAttachGeometry(impl_->scene, geom);
  rtcReleaseGeometry(geom);
  rtcCommitScene(impl_->scene);
  impl_->check("building the scene");
  buildMs_ = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

EmbreeTracer::~EmbreeTracer() = default;

double EmbreeTracer::closest(const std::vector<BatchRay>& rays, std::vector<BatchHit>& out) const {
  out.assign(rays.size(), BatchHit{});
  RTCScene scene = impl_->scene;
  return parallelRays(rays.size(), threads_, [&](size_t i) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rh{};
    rh.ray = toEmbree(rays[i]);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene, &context, &rh);
    BatchHit& h = out[i];
    h.hit = rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
    h.prim = h.hit ? rh.hit.primID : BatchHit::kNoPrim;
    h.t = rh.ray.tfar;
  });
}

double EmbreeTracer::occluded(const std::vector<BatchRay>& rays, std::vector<BatchHit>& out) const {
  out.assign(rays.size(), BatchHit{});
  RTCScene scene = impl_->scene;
  return parallelRays(rays.size(), threads_, [&](size_t i) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRay ray = toEmbree(rays[i]);
    rtcOccluded1(scene, &context, &ray);
    // Embree marks an occluded ray by setting tfar to -inf.
    out[i].hit = ray.tfar < 0.0f;
    out[i].t = rays[i].tMax;
  });
}

}  // namespace bvhlab
