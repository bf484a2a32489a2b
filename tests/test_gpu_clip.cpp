// An animated clip's rebuild kept on the GPU (render/gpu_clip_build.hpp, builders/gpu/gpu_clip_builder.hpp)
// on llvmpipe: boxes computed from the soup on the GPU give the host input's tree, signed zeros
// included; the streams left on the GPU hold what the download holds; a tracer bound to them answers
// and counts as one that uploaded the CPU's pack of the same tree; `trace --update rebuild` with a GPU
// builder takes that path and gives the CPU builder's tree every frame, and says where it updated.
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <glad/gl.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "builders/builder.hpp"
#include "builders/gpu/gpu_builders.hpp"
#include "builders/gpu/gpu_build_steps.hpp"
#include "builders/gpu/gpu_compute.hpp"
#include "builders/gpu/gpu_clip_builder.hpp"
#include "builders/gpu/gpu_lbvh.hpp"
#include "builders/gpu/gpu_pack.hpp"
#include "builders/gpu/gpu_ploc.hpp"
#include "cli_run.hpp"
#include "render_fixture.hpp"
#include "datasets/image_io.hpp"
#include "datasets/scene.hpp"
#include "layout/layout.hpp"
#include "layout/layout_bvh2cb.hpp"
#include "layout/tree_hash.hpp"
#include "render/gl_context.hpp"
#include "render/gpu_renderer.hpp"
#include "render/ray_tracer_gl.hpp"
#include "traversal_test_util.hpp"

namespace bvhlab {
namespace {

using nlohmann::json;
[[maybe_unused]] ::testing::Environment* const kRemoveTestDir =
    ::testing::AddGlobalTestEnvironment(new clitest::RemoveTestDir);

class GpuClip : public ::testing::Test {
 public:
  static void SetUpTestSuite() {
    registerGpuBuilders();
    context_ = createContext(Backend::OSMesa);
  }
  static void TearDownTestSuite() { context_.reset(); }

 protected:
  static std::unique_ptr<GlContext> context_;
};
std::unique_ptr<GlContext> GpuClip::context_;

PackedBvh cpuPack(const Bvh& bvh, const TriangleSoup& soup, const std::string& layout) {
  return gpubuild::cpuPackFor(bvh, soup, layout);
}

// A sphere and a random soup, with every vertex coordinate that is 0 made -0 on the sphere's lower
// half: a box whose min or max is a zero of either sign, which GLSL's min/max may order either way
// (the boxes pass writes glm's comparisons), so a wrong order changes node texels.
TriangleSoup signedZeroSoup() {
  using namespace traversaltest;
  Mesh sphere = sphereMesh(10, 20, 1.0f);
  for (glm::vec3& p : sphere.positions)
    for (int a = 0; a < 3; ++a) {
      if (std::abs(p[a]) < 1e-6f) p[a] = 0.0f;  // snapped to an exact zero (the grid's are ~1e-8)
      if (p[a] == 0.0f && p.y < 0.0f) p[a] = -0.0f;
    }
  return soupOf({sphere, randomSoupMesh(300, 7)});
}

size_t negativeZeros(const TriangleSoup& soup) {
  size_t n = 0;
  for (const std::vector<glm::vec3>* v : {&soup.v0, &soup.v1, &soup.v2})
    for (const glm::vec3& p : *v)
      for (int a = 0; a < 3; ++a) n += p[a] == 0.0f && std::signbit(p[a]);
  return n;
}

void expectSameTexels(const std::vector<glm::uvec4>& a, const std::vector<glm::uvec4>& b, const char* what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (size_t i = 0; i < a.size(); ++i) ASSERT_EQ(a[i], b[i]) << what << " texel " << i;
}

TEST_F(GpuClip, BoxesFromTheSoupGiveTheHostInputsTreeAndTheKeptStreamsHoldIt) {
  const TriangleSoup soup = signedZeroSoup();
  ASSERT_GT(negativeZeros(soup), 10u) << "no -0 coordinates: the signed-zero case tests nothing";
  const std::vector<Aabb> boxes = triangleBoxes(soup);
  const std::vector<glm::vec3> centroids = triangleCentroids(soup);
  const BuildInput input{boxes, centroids, soup.v0, soup.v1, soup.v2};
  const gpubuild::GpuLbvh lbvh;
  const gpubuild::GpuPloc ploc;
  for (const char* builder : {"lbvh-gpu", "ploc-gpu"})
    for (const char* layout : {"v1", kLayoutBvh2cb}) {
      SCOPED_TRACE(std::string(builder) + ", " + layout);
      auto build = [&](const gpubuild::GpuPackRequest& request, gpubuild::GpuPhaseTimes* times) {
        return std::string(builder) == "ploc-gpu" ? ploc.build(input, BuildOptions{}, times, &request)
                                                  : lbvh.build(input, BuildOptions{}, times, &request);
      };
      PackedBvh host, fromSoup;
      const Bvh hostTree = build({layout, &soup, &host}, nullptr);
      gpubuild::GpuStreamBuffers kept;
      gpubuild::GpuPhaseTimes times;
      const Bvh soupTree = build({layout, &soup, &fromSoup, 0, /*boxesFromSoup=*/true, &kept}, &times);
      EXPECT_EQ(packedTreeHash(fromSoup), packedTreeHash(host));
      expectSameTexels(fromSoup.nodes, host.nodes, "node (boxes from the soup vs uploaded)");
      expectSameTexels(fromSoup.nodes, cpuPack(soupTree, soup, layout).nodes, "node (vs the CPU's pack)");
      ASSERT_FALSE(times.phases.empty());
      EXPECT_EQ(times.phases.front().first, "boxes");
      EXPECT_GT(times.wallMs, 0.0);
      // The kept buffers hold the downloaded streams (and more room: sized for 2n - 1 nodes).
      ASSERT_NE(kept.node, 0u);
      expectSameTexels(gpubuild::download<glm::uvec4>(kept.node, fromSoup.nodes.size()), fromSoup.nodes, "kept node");
      expectSameTexels(gpubuild::download<glm::uvec4>(kept.triangle, fromSoup.triangles.size()), fromSoup.triangles,
                       "kept triangle");
      expectSameTexels(gpubuild::download<glm::uvec4>(kept.attribute, fromSoup.attributes.size()), fromSoup.attributes,
                       "kept attribute");
      gpubuild::deleteStreams(kept);
      EXPECT_EQ(kept.node, 0u);
    }
}

// The glm order the boxes pass copies matters: Aabb::grow keeps the first of two equal zeros.
TEST_F(GpuClip, TheSignedZeroCaseCanFail) {
  Aabb box;
  box.grow(glm::vec3(-0.0f));
  box.grow(glm::vec3(0.0f));
  EXPECT_TRUE(std::signbit(box.min.x) && std::signbit(box.max.x)) << "glm keeps -0 for min and max here";
  const TriangleSoup soup = signedZeroSoup();
  TriangleSoup flipped = soup;  // the same triangles with -0 made +0: other boxes, other node texels
  for (std::vector<glm::vec3>* v : {&flipped.v0, &flipped.v1, &flipped.v2})
    for (glm::vec3& p : *v)
      for (int a = 0; a < 3; ++a)
        if (p[a] == 0.0f) p[a] = 0.0f;
  ASSERT_EQ(negativeZeros(flipped), 0u);
  auto nodes = [](const TriangleSoup& s) {
    const std::vector<Aabb> boxes = triangleBoxes(s);
    const std::vector<glm::vec3> centroids = triangleCentroids(s);
    return packBvh(buildBvh("lbvh", BuildInput{boxes, centroids, s.v0, s.v1, s.v2}, BuildOptions{}), s).nodes;
  };
  EXPECT_NE(nodes(soup), nodes(flipped)) << "the sign of a zero does not reach the node texels: the test above "
                                            "could not tell a wrong min/max order";
}

// Per frame of a moving sphere: the resident builder's tree is the CPU builder's; a tracer bound to its
// streams on the GPU answers and counts as one given the CPU's pack, in both storage kinds that bind.
TEST_F(GpuClip, ATracerBoundToTheStreamsOnTheGpuTracesTheCpuPack) {
  using namespace traversaltest;
  const Mesh base = sphereMesh(12, 24, 1.0f);
  for (const char* builder : {"lbvh-gpu", "ploc-gpu", "hploc-gpu"})
    for (const char* layout : {"v1", kLayoutBvh2cb, "cwbvh"})
      for (const Storage storage : {Storage::Tbo, Storage::Ssbo}) {
        SCOPED_TRACE(std::string(builder) + ", " + layout + (storage == Storage::Tbo ? ", tbo" : ", ssbo"));
        std::unique_ptr<GpuClipBuilder> resident = makeResidentClipBuilder(builder, BuildOptions{}, layout);
        ASSERT_TRUE(resident);
        RayTracerOptions options;
        options.storage = storage;
        options.kernel = "";
        for (int frame = 0; frame < 3; ++frame) {
          Mesh m = base;
          for (glm::vec3& p : m.positions) p = p * glm::vec3(1.0f + 0.3f * float(frame), 1.0f, 1.0f) + 0.1f * float(frame);
          const TriangleSoup soup = soupOf({m, randomSoupMesh(200, uint32_t(frame + 1))});
          const GpuClipFrame f = resident->build(soup);
          const std::vector<Aabb> boxes = triangleBoxes(soup);
          const std::vector<glm::vec3> centroids = triangleCentroids(soup);
          const std::string name = builder;
          const Bvh cpu = buildBvh(name.substr(0, name.size() - 4),  // the CPU builder of the same tree
                                   BuildInput{boxes, centroids, soup.v0, soup.v1, soup.v2}, BuildOptions{});
          const PackedBvh cpuPacked = cpuPack(cpu, soup, layout);
          ASSERT_EQ(packedTreeHash(f.packed), packedTreeHash(cpuPacked)) << "frame " << frame;
          EXPECT_GT(f.buildMs, 0.0);
          EXPECT_GT(f.gpuMs, 0.0);

          std::vector<BatchRay> rays;
          for (const RayQuery& q : randomRays(soupBounds(soup), 300, uint32_t(11 + frame)))
            rays.push_back({q.ray.origin, q.tMin, q.ray.dir, q.tMax});
          GlRayTracer uploaded(cpuPacked, options), bound(cpuPacked, options);
          bound.setTreeBuffers(f.packed, f.streams);
          uploaded.setRays(rays);
          bound.setRays(rays);
          std::vector<BatchHit> hitsUploaded, hitsBound;
          const std::vector<glm::uvec4> countsUploaded = uploaded.traceCounted(&hitsUploaded);
          const std::vector<glm::uvec4> countsBound = bound.traceCounted(&hitsBound);
          ASSERT_EQ(hitsBound.size(), rays.size());
          size_t hits = 0;
          for (size_t i = 0; i < rays.size(); ++i) {
            ASSERT_EQ(hitsBound[i].hit, hitsUploaded[i].hit) << "ray " << i;
            ASSERT_EQ(hitsBound[i].prim, hitsUploaded[i].prim) << "ray " << i;
            ASSERT_EQ(hitsBound[i].t, hitsUploaded[i].t) << "ray " << i;
            ASSERT_EQ(countsBound[i], countsUploaded[i]) << "ray " << i;
            hits += hitsBound[i].hit;
          }
          EXPECT_GT(hits, rays.size() / 10) << "too few hits to compare trees by";
          // The bound tracer reads the GPU's buffers themselves: their triangles zeroed there (every one a
          // point at the origin), it finds none, while the tracer with its own upload still does.
          const glm::uvec4 zero(0u);
          glClearNamedBufferData(f.streams[1], GL_RGBA32UI, GL_RGBA_INTEGER, GL_UNSIGNED_INT, &zero);
          glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
          std::vector<BatchHit> afterBound, afterUploaded;
          bound.traceCounted(&afterBound);
          uploaded.traceCounted(&afterUploaded);
          size_t boundHits = 0, uploadedHits = 0;
          for (size_t i = 0; i < rays.size(); ++i) {
            boundHits += afterBound[i].hit;
            uploadedHits += afterUploaded[i].hit;
          }
          EXPECT_EQ(boundHits, 0u);
          EXPECT_EQ(uploadedHits, hits);
        }
      }
}

TEST_F(GpuClip, RefusalsAndErrors) {
  EXPECT_EQ(makeResidentClipBuilder("lbvh", BuildOptions{}, "v1"), nullptr);
  EXPECT_EQ(makeResidentClipBuilder("lbvh-gpu", BuildOptions{}, "bvh4"), nullptr);
  EXPECT_EQ(makeGpuClipBuilder("lbvh-gpu", BuildOptions{}, "v1", "compressed"), nullptr);
  EXPECT_NE(makeGpuClipBuilder("lbvh-gpu", BuildOptions{}, "v1", "raw"), nullptr);
  // A non-finite vertex: the CPU's check names the triangle, before any GPU work.
  TriangleSoup soup = traversaltest::soupOf({traversaltest::sphereMesh(4, 8, 1.0f)});
  soup.v1[5].y = std::numeric_limits<float>::quiet_NaN();
  std::unique_ptr<GpuClipBuilder> resident = makeResidentClipBuilder("ploc-gpu", BuildOptions{}, "v1");
  try {
    resident->build(soup);
    ADD_FAILURE() << "a NaN vertex was built";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("5"), std::string::npos) << e.what();
  }
  // Tex2D storage would need a copy: refused by the tracer.
  const TriangleSoup ok = traversaltest::soupOf({traversaltest::sphereMesh(4, 8, 1.0f)});
  const GpuClipFrame f = makeResidentClipBuilder("lbvh-gpu", BuildOptions{}, "v1")->build(ok);
  RayTracerOptions tex2d;
  tex2d.storage = Storage::Tex2D;
  tex2d.kernel = "";
  GlRayTracer tracer(f.packed, tex2d);
  EXPECT_THROW(tracer.setTreeBuffers(f.packed, f.streams), std::invalid_argument);
}

// A renderer given streams on the GPU (PreparedScene::gpuStreams) draws from those buffers themselves:
// the image of a renderer that uploads its own copy, and, once their triangles are zeroed on the GPU, no
// mesh (while the copy's renderer still draws it). tex2d storage is refused (it would copy).
TEST_F(GpuClip, ARendererDrawsFromTheStreamsOnTheGpuThemselves) {
  std::unique_ptr<PreparedScene> p = test::prepareToml(
      "[camera]\neye = [0, 2.5, 4]\ntarget = [0, 0, 0]\n[[object]]\nkind = \"mesh\"\ngenerate = \"terrain\"\n"
      "triangles = 1500\nfit = 2\n");
  const FrameOptions frame = test::smallFrame(p->scene, 32, 24);
  const PackedBvh& packed = p->packed;
  for (const Storage storage : {Storage::Tbo, Storage::Ssbo}) {
    SCOPED_TRACE(storage == Storage::Tbo ? "tbo" : "ssbo");
    ShaderOptions options = test::tracerOptions(*p);
    options.storage = storage;
    p->gpuStreams = {};
    GpuRenderer own(*p, options, frame);
    own.drawFrame();
    const std::vector<uint8_t> expected = own.readColor();
    gpubuild::GpuStreamBuffers buffers{gpubuild::makeStorageBuffer(packed.nodes.size() * 16, packed.nodes.data()),
                                       gpubuild::makeStorageBuffer(packed.triangles.size() * 16, packed.triangles.data()),
                                       gpubuild::makeStorageBuffer(packed.attributes.size() * 16, packed.attributes.data())};
    p->gpuStreams = {buffers.node, buffers.triangle, buffers.attribute};
    {
      GpuRenderer bound(*p, options, frame);
      bound.drawFrame();
      EXPECT_EQ(bound.readColor(), expected);
      const glm::uvec4 zero(0u);
      glClearNamedBufferData(buffers.triangle, GL_RGBA32UI, GL_RGBA_INTEGER, GL_UNSIGNED_INT, &zero);
      glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
      bound.drawFrame();
      EXPECT_NE(bound.readColor(), expected) << "the renderer drew from a copy of its own";
      own.drawFrame();
      EXPECT_EQ(own.readColor(), expected);
    }
    ShaderOptions tex2d = options;
    tex2d.storage = Storage::Tex2D;
    EXPECT_THROW(GpuRenderer(*p, tex2d, frame), std::invalid_argument);
    p->gpuStreams = {};
    gpubuild::deleteStreams(buffers);
  }
}

json traceJson(const std::string& args) {
  const clitest::Result r = clitest::run("trace " + args + " --json --frames 1 --warmup 0");
  EXPECT_EQ(r.code, 0) << r.err;
  if (r.code != 0) return json::object();
  return json::parse(r.out);
}

TEST(GpuClipCli, TraceUpdateRebuildWithAGpuBuilderBuildsOnTheGpuAndGivesTheCpuBuildersTrees) {
  const std::string scene = clitest::writeTemp("gpu_clip/wave.toml",
                                               "[clip]\nframes = 3\nfps = 10\n[camera]\neye = [0, 2.5, 4]\n"
                                               "target = [0, 0, 0]\n[render]\nwidth = 24\nheight = 24\n"
                                               "[[object]]\nkind = \"mesh\"\ngenerate = \"terrain\"\n"
                                               "triangles = 1500\nfit = 2\n[object.deform]\nkind = \"wave\"\n"
                                               "amplitude = 0.3\nwavelength = 1\n")
                                  .string();
  const std::string common = scene + " --update rebuild --rays diffuse --count 256 --update-repeats 2";
  for (const char* layout : {"v1", "bvh2-cb", "cwbvh"}) {
    SCOPED_TRACE(layout);
    const json gpu = traceJson(common + " --builder ploc-gpu --layout " + layout);
    const json cpu = traceJson(common + " --builder ploc --layout " + layout);
    ASSERT_EQ(gpu["update_on"], "gpu");
    ASSERT_EQ(cpu["update_on"], "cpu");
    ASSERT_EQ(gpu["frames"].size(), 3u);
    ASSERT_EQ(cpu["frames"].size(), 3u);
    EXPECT_EQ(gpu["hit_mismatches"], 0);
    EXPECT_TRUE(gpu["clip"]["gpu_update_ms_total"].is_number());
    EXPECT_TRUE(cpu["clip"]["gpu_update_ms_total"].is_null());
    for (size_t k = 0; k < 3; ++k) {
      const json &g = gpu["frames"][k], &c = cpu["frames"][k];
      SCOPED_TRACE("frame " + std::to_string(g["frame"].get<int>()));
      EXPECT_EQ(g["tree_hash"], c["tree_hash"]);
      EXPECT_EQ(g["node_visits_per_ray"], c["node_visits_per_ray"]);
      EXPECT_EQ(g["triangle_tests_per_ray"], c["triangle_tests_per_ray"]);
      EXPECT_EQ(g["sah_cost"], c["sah_cost"]);
      EXPECT_TRUE(g["rebuilt"].get<bool>());
      EXPECT_TRUE(g["repeats_agree"].get<bool>());
      EXPECT_EQ(g["pack_ms"], 0.0);
      EXPECT_EQ(g["update_ms_all"].size(), 2u);
      EXPECT_EQ(g["gpu_update_ms_all"].size(), 2u);
      ASSERT_TRUE(g["gpu_update_phases_ms"].is_object());
      for (const char* phase : {"boxes", "morton", "sort", "nn", "merge", "collapse", "pack"})
        EXPECT_TRUE(g["gpu_update_phases_ms"].contains(phase)) << phase;
    }
  }
  // tex2d storage cannot bind the GPU's buffers: the tree goes through the CPU, and the JSON says so.
  const json tex2d = traceJson(common + " --builder lbvh-gpu --storage tex2d");
  EXPECT_EQ(tex2d["update_on"], "cpu");
  EXPECT_EQ(tex2d["hit_mismatches"], 0);
}

// `render --update rebuild` with a GPU builder: the renderer binds the streams the GPU made (`update_on`
// gpu), and draws the CPU builder's trees: the same per-frame tree_hash and ray cost, the same image.
TEST(GpuClipCli, RenderUpdateRebuildDrawsFromTheStreamsOnTheGpu) {
  const std::string scene = clitest::writeTemp("gpu_clip/explode.toml",
                                               "[clip]\nframes = 3\nfps = 10\n[camera]\neye = [0, 2.5, 4]\n"
                                               "target = [0, 0, 0]\n[render]\nwidth = 32\nheight = 24\n"
                                               "[[object]]\nkind = \"mesh\"\ngenerate = \"terrain\"\n"
                                               "triangles = 1500\nfit = 2\n[object.deform]\nkind = \"explode\"\n"
                                               "speed = 2\njitter = 0.5\n")
                                  .string();
  json out[2];
  std::string images[2];
  for (int k = 0; k < 2; ++k) {
    const std::string builder = k == 0 ? "lbvh-gpu" : "lbvh";
    images[k] = (clitest::testDir() / ("render_" + builder + ".png")).string();
    const clitest::Result r = clitest::run("render " + scene + " --update rebuild --builder " + builder +
                                           " --frames 1 --warmup 0 --update-repeats 2 --json -o " + images[k]);
    ASSERT_EQ(r.code, 0) << r.err;
    out[k] = json::parse(r.out);
  }
  EXPECT_EQ(out[0]["update_on"], "gpu");
  EXPECT_EQ(out[1]["update_on"], "cpu");
  ASSERT_EQ(out[0]["frames"].size(), 3u);
  for (size_t f = 0; f < 3; ++f) {
    const json &g = out[0]["frames"][f], &c = out[1]["frames"][f];
    SCOPED_TRACE(f);
    EXPECT_EQ(g["tree_hash"], c["tree_hash"]);
    EXPECT_EQ(g["ray_cost"], c["ray_cost"]);
    EXPECT_EQ(g["pack_ms"], 0.0);
    EXPECT_EQ(g["upload_ms_all"].size(), 2u);  // one per build: each uploads the frame's triangles
    EXPECT_TRUE(g["gpu_update_phases_ms"].contains("pack"));
  }
  EXPECT_NE(out[0]["frames"][0]["tree_hash"], out[0]["frames"][2]["tree_hash"]) << "the clip does not move";
  EXPECT_EQ(loadImageRgba8(images[0]).rgba, loadImageRgba8(images[1]).rgba) << "the last frames drawn differ";
}

}  // namespace
}  // namespace bvhlab
