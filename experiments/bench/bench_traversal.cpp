// Primary rays at 640x360 over the bunny filling the view: every GLSL kernel on a SAH tree
// (primid view: closest hit only, no shading) side by side with Embree's rtcIntersect1 on the same
// rays on all cores, in one run. Target from issue 3: best kernel <= 2.0x Embree's time.
#include <cmath>
#include <filesystem>
#include <map>
#include <thread>

#include <benchmark/benchmark.h>
#include <embree3/rtcore.h>

#include "datasets/scene_io.hpp"
#include "render/gl_context.hpp"
#include "render/gpu_renderer.hpp"
#include "traversal/kernels.hpp"

using namespace bvhlab;

namespace {

constexpr int kWidth = 640, kHeight = 360;

const PreparedScene* bunny(const std::string& builder) {
  static std::map<std::string, std::unique_ptr<PreparedScene>> cache;
  auto& p = cache[builder];
  if (!p) {
    std::filesystem::path path = std::filesystem::path(BVHLAB_SOURCE_DIR) / "datasets/cache/meshes/bunny00.off";
    if (!std::filesystem::exists(path)) return nullptr;
    MeshSceneOptions mo;
    mo.groundPlane = false;
    Scene s = loadMeshScene(path, mo);
    // Close view: the bunny fills the frame.
    glm::vec3 toEye = s.camera.eye - s.camera.target;
    s.camera.eye = s.camera.target + 0.45f * toEye;
    p = prepareScene(std::move(s), builder, BuildOptions{});
  }
  return p.get();
}

void glslKernel(benchmark::State& state, const char* kernel) {
  static std::unique_ptr<GlContext> ctx = createContext(Backend::OSMesa);
  const PreparedScene* p = bunny("sah-binned");
  if (!p) return state.SkipWithError("bunny00.off missing: run datasets/fetch.sh");
  ShaderOptions o;
  o.view = View::PrimId;
  o.kernel = kernel;
  o.bvhStackSize = stackSizeFor(p->packed.depth);
  FrameOptions f{kWidth, kHeight, p->scene.camera, 1.0f};
  GpuRenderer r(*p, o, f);
  for (int i = 0; i < 2; ++i) r.drawFrame();  // llvmpipe JIT at the first draw
  for (auto _ : state) state.SetIterationTime(r.drawFrame() / 1000.0);
}

void embreeIntersect1(benchmark::State& state) {
  const PreparedScene* p = bunny("sah-binned");
  if (!p) return state.SkipWithError("bunny00.off missing: run datasets/fetch.sh");
  RTCDevice device = rtcNewDevice(nullptr);
  RTCScene scene = rtcNewScene(device);
  rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_MEDIUM);
  RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  const TriangleSoup& soup = p->soup;
  auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                        3 * sizeof(float), 3 * soup.size()));
  auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                             3 * sizeof(unsigned), soup.size()));
  for (size_t i = 0; i < soup.size(); ++i) {
    const glm::vec3* vs[3] = {&soup.v0[i], &soup.v1[i], &soup.v2[i]};
    for (int k = 0; k < 3; ++k) {
      v[9 * i + 3 * k + 0] = vs[k]->x;
      v[9 * i + 3 * k + 1] = vs[k]->y;
      v[9 * i + 3 * k + 2] = vs[k]->z;
      idx[3 * i + k] = unsigned(3 * i + k);
    }
  }
  rtcCommitGeometry(geom);
  rtcAttachGeometry(scene, geom);
  rtcReleaseGeometry(geom);
  rtcCommitScene(scene);

  CameraBasis cam = cameraBasis(p->scene.camera, kWidth, kHeight);
  const unsigned threads = std::max(1u, std::thread::hardware_concurrency());
  size_t hits = 0;
  auto trace = [&](unsigned first, size_t* hitCount) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    for (int y = int(first); y < kHeight; y += int(threads))
      for (int x = 0; x < kWidth; ++x) {
        // The same ray main.glsl generates for this pixel.
        glm::vec2 ndc = 2.0f * glm::vec2(x + 0.5f, y + 0.5f) / glm::vec2(kWidth, kHeight) - 1.0f;
        glm::vec3 d = glm::normalize(cam.forward + ndc.x * cam.right + ndc.y * cam.up);
        RTCRayHit rh{};
        rh.ray.org_x = cam.eye.x; rh.ray.org_y = cam.eye.y; rh.ray.org_z = cam.eye.z;
        rh.ray.dir_x = d.x; rh.ray.dir_y = d.y; rh.ray.dir_z = d.z;
        rh.ray.tnear = 0.0f;
        rh.ray.tfar = INFINITY;
        rh.ray.mask = ~0u;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(scene, &context, &rh);
        *hitCount += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
      }
  };
  for (auto _ : state) {
    auto start = std::chrono::steady_clock::now();
    std::vector<size_t> counts(threads, 0);
    std::vector<std::thread> pool;
    for (unsigned t = 0; t < threads; ++t) pool.emplace_back(trace, t, &counts[t]);
    for (auto& t : pool) t.join();
    hits = 0;
    for (size_t c : counts) hits += c;
    state.SetIterationTime(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  state.counters["hit_fraction"] = double(hits) / (double(kWidth) * kHeight);
  rtcReleaseScene(scene);
  rtcReleaseDevice(device);
}

}  // namespace

BENCHMARK(embreeIntersect1)->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(10);
BENCHMARK_CAPTURE(glslKernel, stack_unordered, "stack-unordered")->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(10);
BENCHMARK_CAPTURE(glslKernel, stack_ordered, "stack-ordered")->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(10);
BENCHMARK_CAPTURE(glslKernel, stackless, "stackless")->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(10);

BENCHMARK_MAIN();
