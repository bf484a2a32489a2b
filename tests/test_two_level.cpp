// Two-level trees (layout/pack_two_level.hpp, traversal/two_level.{glsl,hpp}): the C++ mirror and the
// GLSL against brute force over the flattened scene, far from the origin and under non-uniform
// scale, watertightness at shared edges and vertices, GLSL == mirror per ray on every counter, and a
// single identity instance == the flat tree. TwoLevel.* need no GL context ("cpu"); TwoLevelGlsl.*
// run the GLSL on llvmpipe ("gl", tests/CMakeLists.txt).
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <glad/gl.h>
#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include "builders/builder.hpp"
#include "datasets/random_draws.hpp"
#include "gl_compute.hpp"
#include "layout/layouts.hpp"
#include "layout/pack_two_level.hpp"
#include "render/gl_context.hpp"
#include "require.hpp"
#include "shaders/assemble.hpp"
#include "traversal/two_level.hpp"
#include "traversal_test_util.hpp"
#include "two_level_test_util.hpp"

namespace bvhlab {
namespace {

using namespace traversaltest;
using namespace twoleveltest;
using glsl::two_level::TwoLevelCounters;
using glsl::two_level::TwoLevelHit;

void checkMirrorAgainstBruteForce(const TwoLevelScene& scene, size_t rayCount, uint32_t seed, const char* name) {
  SCOPED_TRACE(name);
  const std::vector<FlatTriangle> flat = flatten(scene);
  Aabb bounds;
  for (const FlatTriangle& f : flat)
    for (const glm::dvec3& v : {f.v0, f.v1, f.v2}) bounds.grow(glm::vec3(v));
  const std::vector<RayQuery> rays = sceneRays(scene, bounds, rayCount, seed);
  std::vector<Reference> refs;
  for (const RayQuery& q : rays) refs.push_back(reference(flat, q));
  for (const std::string& layout : {std::string("v1"), std::string("bvh2-cb")}) {
    const PackedTwoLevel packed = packTwoLevel(packBlases(scene, layout), scene.instances, TopLevelBuild{"sah-binned", {}});
    const glsl::Storage storage(packed.streams);
    for (const auto& [l, kernel] : layoutKernels()) {
      if (l != layout) continue;
      for (Robustness robust : {Robustness::Fast, Robustness::Watertight}) {
        const std::string who = layout + "/" + kernel + "/" + robustnessName(robust);
        const TwoLevelMirror m = twoLevelMirror(kernel, robust);
        Tally tally;
        for (size_t i = 0; i < rays.size(); ++i) {
          const MirrorRun r = runMirror(m, storage, rays[i]);
          EXPECT_FALSE(r.cc.tlas.stackOverflow || r.cc.blas.stackOverflow) << who;
          agrees(packed, r.closest, r.any, r.hit, refs[i], rays[i], who, tally);
          EXPECT_LE(r.ac.tlas.nodeVisits + r.ac.blas.nodeVisits, r.cc.tlas.nodeVisits + r.cc.blas.nodeVisits) << who;
        }
        std::printf("%s %s: %zu of %zu rays clear of edges and ties, %zu hits, max relative t error %.2g\n", name,
                    who.c_str(), tally.clear, tally.rays, tally.hits, tally.maxRelativeT);
        EXPECT_EQ(tally.failures, 0u) << who;
        // Both outcomes exercised, and the margins leave most rays in the comparison.
        EXPECT_GT(tally.hits, tally.clear / 10) << who;
        EXPECT_LT(tally.hits, tally.clear) << who;
        EXPECT_GT(tally.clear, tally.rays * 8 / 10) << who;
      }
    }
  }
}

TEST(TwoLevel, MirrorEqualsBruteForceOverTheFlattenedScene) {
  checkMirrorAgainstBruteForce(randomScene(glm::vec3(0.0f), glm::vec3(1.0f), 12, 3), 600, 5, "near the origin");
}

// The TLAS by every registered builder (over the instances' world boxes, no triangles), leaves of
// one and of four instances.
TEST(TwoLevel, AnyBuilderBuildsTheTopLevel) {
  const TwoLevelScene scene = randomScene(glm::vec3(0.0f), glm::vec3(1.0f), 16, 41);
  const std::vector<FlatTriangle> flat = flatten(scene);
  Aabb bounds;
  for (const FlatTriangle& f : flat)
    for (const glm::dvec3& v : {f.v0, f.v1, f.v2}) bounds.grow(glm::vec3(v));
  const std::vector<RayQuery> rays = sceneRays(scene, bounds, 200, 42);
  std::vector<Reference> refs;
  for (const RayQuery& q : rays) refs.push_back(reference(flat, q));
  const std::vector<PackedBvh> blases = packBlases(scene, "bvh2-cb");
  for (const BuilderInfo& b : builders())
    for (uint32_t leaf : {1u, 4u}) {
      SCOPED_TRACE(b.name + " leaf " + std::to_string(leaf));
      TopLevelBuild top{b.name, {}};
      top.options.maxLeafSize = leaf;
      const PackedTwoLevel packed = packTwoLevel(blases, scene.instances, top);
      const glsl::Storage storage(packed.streams);
      const TwoLevelMirror m = twoLevelMirror("bvh2cb-stack-ordered", Robustness::Watertight);
      Tally tally;
      for (size_t i = 0; i < rays.size(); ++i) {
        const MirrorRun r = runMirror(m, storage, rays[i]);
        agrees(packed, r.closest, r.any, r.hit, refs[i], rays[i], b.name, tally);
      }
      EXPECT_EQ(tally.failures, 0u);
      EXPECT_GT(tally.hits, tally.clear / 10);
    }
}

TEST(TwoLevel, FarFromTheOriginAndNonUniformlyScaled) {
  checkMirrorAgainstBruteForce(randomScene(glm::vec3(1e5f, -1e5f, 1e5f), glm::vec3(1.0f, 10.0f, 0.1f), 12, 4), 600, 6,
                               "at 1e5, scale (1, 10, 0.1)");
}

// The object-space ray origin's error, translation first (as two_level.glsl) against the affine map
// applied whole (A o + b): the error the choice of order decides.
TEST(TwoLevel, TranslationFirstKeepsTheOriginErrorSmall) {
  const TwoLevelScene scene = randomScene(glm::vec3(1e5f, -1e5f, 1e5f), glm::vec3(1.0f, 10.0f, 0.1f), 12, 4);
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(-8.0f, 8.0f);
  double worstFirst = 0.0, worstWhole = 0.0, worstBound = 0.0;
  for (const Instance& inst : scene.instances) {
    const glm::mat4x3 inv = inverseAffine(inst.objectToWorld);
    const glm::dmat3 lInv{glm::dvec3(inv[0]), glm::dvec3(inv[1]), glm::dvec3(inv[2])};
    for (int k = 0; k < 200; ++k) {
      const glm::vec3 o = inst.objectToWorld[3] + draw3<glm::vec3>(u, rng);
      // Exact, for the stored (rounded) L^-1: the error of the evaluation alone.
      const glm::dvec3 exact = lInv * (glm::dvec3(o) - glm::dvec3(inst.objectToWorld[3]));
      const glm::vec3 p = o - inst.objectToWorld[3];
      glm::vec3 first, whole;
      for (int i = 0; i < 3; ++i) {
        first[i] = inv[0][i] * p.x + inv[1][i] * p.y + inv[2][i] * p.z;
        whole[i] = inv[0][i] * o.x + inv[1][i] * o.y + inv[2][i] * o.z + inv[3][i];
        // The dot-product bound for three products and two sums of exact inputs: 3u sum |r_ij p_j|
        // (u = 2^-24; o - T is exact here: o and T lie within a factor 2 of each other, Sterbenz).
        const double bound = 3.0 * 0x1p-24 * (std::abs(inv[0][i] * p.x) + std::abs(inv[1][i] * p.y) + std::abs(inv[2][i] * p.z));
        const double errFirst = std::abs(double(first[i]) - exact[i]);
        EXPECT_LE(errFirst, bound * 1.0000001) << "component " << i;
        worstFirst = std::max(worstFirst, errFirst);
        worstBound = std::max(worstBound, bound);
        worstWhole = std::max(worstWhole, std::abs(double(whole[i]) - exact[i]));
      }
    }
  }
  std::printf("object-space origin error at 1e5, scale (1, 10, 0.1): translation first %.3g (bound %.3g), "
              "affine map whole %.3g\n", worstFirst, worstBound, worstWhole);
  EXPECT_LT(worstFirst * 1000.0, worstWhole) << "translation first should be far more precise";
}

// Rays aimed at every vertex and every edge midpoint of a closed mesh, from outside along the outward
// direction, at 1e5 under a non-uniform power-of-two scale: the world ray is chosen so that its
// object-space image is exactly the aimed ray (o - T exact by Sterbenz, the scale exact), so the
// object-space rays pass through the shared edges and vertices as in the flat watertight tests.
TEST(TwoLevel, WatertightAtSharedEdgesAndVerticesFarAndScaled) {
  const Mesh mesh = closedSphere(8, 16);
  const glm::vec3 scale(1.0f, 8.0f, 0.125f), translation(1e5f, -1e5f, 1e5f);
  TwoLevelScene scene;
  scene.soups = {soupOf({mesh})};
  scene.instances = {{0, affine(translation, glm::vec3(0, 0, 1), 0.0f, scale)}};
  // A second instance rotated and scaled (1, 10, 0.1), aimed at through its own transform (not exact).
  scene.instances.push_back({0, affine(translation + glm::vec3(20.0f, 0.0f, 0.0f), glm::normalize(glm::vec3(1, 2, 3)),
                                       0.7f, glm::vec3(1.0f, 10.0f, 0.1f))});
  std::vector<glm::vec3> targets = mesh.positions;
  for (const auto& t : mesh.triangles)
    for (int e = 0; e < 3; ++e) targets.push_back(0.5f * (mesh.positions[t[e]] + mesh.positions[t[(e + 1) % 3]]));
  std::vector<RayQuery> rays;
  for (const glm::vec3& target : targets) {
    for (int dir = 0; dir < 3; ++dir) {  // straight in, and tilted two ways
      const glm::vec3 n = glm::normalize(target);
      const glm::vec3 tilt = dir == 0 ? glm::vec3(0.0f) : dir == 1 ? glm::vec3(0.3f, 0.0f, 0.2f) : glm::vec3(-0.2f, 0.3f, 0.0f);
      const glm::vec3 objectOrigin = target + 3.0f * (n + tilt);
      // Instance 0: exact object-space image.
      const glm::vec3 worldOrigin = objectOrigin * scale + translation;
      const glm::vec3 exactObjectOrigin = (worldOrigin - translation) / scale;
      rays.push_back({{worldOrigin, (target - exactObjectOrigin) * scale}, 0.0f, glsl::INF});
      // Instance 1: through its transform, in double, rounded.
      const Instance& inst = scene.instances[1];
      const glm::dmat3 l{glm::dvec3(inst.objectToWorld[0]), glm::dvec3(inst.objectToWorld[1]), glm::dvec3(inst.objectToWorld[2])};
      const glm::dvec3 wo = l * glm::dvec3(objectOrigin) + glm::dvec3(inst.objectToWorld[3]);
      const glm::dvec3 wt = l * glm::dvec3(target) + glm::dvec3(inst.objectToWorld[3]);
      rays.push_back({{glm::vec3(wo), glm::vec3(wt - glm::dvec3(glm::vec3(wo)))}, 0.0f, glsl::INF});
    }
  }
  for (const std::string& layout : {std::string("v1"), std::string("bvh2-cb")}) {
    const PackedTwoLevel packed = packTwoLevel(packBlases(scene, layout), scene.instances);
    const glsl::Storage storage(packed.streams);
    for (const auto& [l, kernel] : layoutKernels()) {
      if (l != layout) continue;
      size_t leaksWatertight = 0, leaksFast = 0;
      for (const RayQuery& q : rays) {
        leaksWatertight += !runMirror(twoLevelMirror(kernel, Robustness::Watertight), storage, q).closest;
        leaksFast += !runMirror(twoLevelMirror(kernel, Robustness::Fast), storage, q).closest;
      }
      std::printf("%s/%s: %zu rays at shared edges and vertices: watertight misses %zu, fast misses %zu\n",
                  layout.c_str(), kernel.c_str(), rays.size(), leaksWatertight, leaksFast);
      EXPECT_EQ(leaksWatertight, 0u) << layout << "/" << kernel;
    }
  }
}

// One instance with the identity transform walks its BLAS exactly as the flat kernel walks the same
// tree: same hit bits, and the BLAS counters are the flat kernel's.
TEST(TwoLevel, IdentityInstanceEqualsTheFlatTree) {
  const TriangleSoup soup = soupOf({sphereMesh(12, 24, 1.0f), gridMesh(5)});
  const std::vector<RayQuery> rays = mixedRays(soup, 300, 21);
  TwoLevelScene scene;
  scene.soups = {soup};
  scene.instances = {{0, glm::mat4x3(1.0f)}};
  for (const std::string& layout : {std::string("v1"), std::string("bvh2-cb")}) {
    const std::vector<PackedBvh> blases = packBlases(scene, layout);
    const PackedTwoLevel packed = packTwoLevel(blases, scene.instances);
    const glsl::Storage twoLevel(packed.streams), flat(blases[0], stackSizeFor(packed.streams));
    for (const auto& [l, kernel] : layoutKernels()) {
      if (l != layout) continue;
      for (Robustness robust : {Robustness::Fast, Robustness::Watertight}) {
        SCOPED_TRACE(layout + "/" + kernel + "/" + robustnessName(robust));
        const KernelInfo& k = findKernel(layout, kernel);
        size_t failures = 0, hits = 0, entered = 0;
        for (const RayQuery& q : rays) {
          MeshHit fh;
          Counters fc, fa;
          const bool ff = k.closest(robust)(flat, q.ray, q.tMin, q.tMax, fh, fc);
          const bool fany = k.any(robust)(flat, q.ray, q.tMin, q.tMax, fa);
          const MirrorRun r = runMirror(twoLevelMirror(kernel, robust), twoLevel, q);
          hits += ff;
          entered += r.cc.tlas.triTests;
          const bool same = ff == r.closest && fany == r.any && fh.tri == r.hit.hit.tri &&
                            std::bit_cast<uint32_t>(fh.t) == std::bit_cast<uint32_t>(r.hit.hit.t) &&
                            fh.bary == r.hit.hit.bary && (ff ? r.hit.record == int(packed.firstRecord()) : r.hit.record == -1) &&
                            r.cc.tlas.triTests <= 1 && r.ac.tlas.triTests == r.cc.tlas.triTests &&
                            // Entered (the TLAS box = the BLAS root box here, exactly): the BLAS walk is the
                            // flat walk. Not entered: the flat walk found nothing and tested no triangle.
                            (r.cc.tlas.triTests == 1
                                 ? fc.nodeVisits == r.cc.blas.nodeVisits && fc.triTests == r.cc.blas.triTests &&
                                       fc.boxTests == r.cc.blas.boxTests && fa.nodeVisits == r.ac.blas.nodeVisits &&
                                       fa.triTests == r.ac.blas.triTests
                                 : !ff && fc.triTests == 0 && r.cc.blas.nodeVisits == 0);
          if (!same && ++failures <= 3)
            ADD_FAILURE() << "flat: " << ff << " tri " << fh.tri << " t " << fh.t << " visits " << fc.nodeVisits
                          << "; two-level: " << r.closest << " tri " << r.hit.hit.tri << " t " << r.hit.hit.t
                          << " BLAS visits " << r.cc.blas.nodeVisits << "; " << describe(q);
        }
        EXPECT_EQ(failures, 0u);
        EXPECT_GT(hits, rays.size() / 10);
        EXPECT_GT(entered, hits) << "some rays must enter the instance and miss its triangles";
      }
    }
  }
}

TEST(TwoLevel, PackingKeepsTheBlasRegionAndRefusesBadInput) {
  const TwoLevelScene scene = randomScene(glm::vec3(0.0f), glm::vec3(1.0f), 7, 8);
  PackedTwoLevel p = packTwoLevel(packBlases(scene, "v1"), scene.instances);
  EXPECT_EQ(p.streams.nodes[0].x, p.tlasRoot);
  EXPECT_EQ(p.streams.nodes[0].y, 7u);
  EXPECT_EQ(p.recordInstance.size(), 7u);
  std::vector<uint32_t> ids = p.recordInstance;
  std::sort(ids.begin(), ids.end());
  for (uint32_t i = 0; i < 7; ++i) EXPECT_EQ(ids[i], i);
  // World boxes contain the exact image of the BLAS box's corners.
  for (const Instance& inst : scene.instances) {
    const Aabb w = transformBox(p.blasBox[inst.blas], inst.objectToWorld);
    const glm::dmat3 l{glm::dvec3(inst.objectToWorld[0]), glm::dvec3(inst.objectToWorld[1]), glm::dvec3(inst.objectToWorld[2])};
    for (int c = 0; c < 8; ++c) {
      const Aabb& b = p.blasBox[inst.blas];
      const glm::dvec3 corner((c & 1) ? b.max.x : b.min.x, (c & 2) ? b.max.y : b.min.y, (c & 4) ? b.max.z : b.min.z);
      const glm::dvec3 x = l * corner + glm::dvec3(inst.objectToWorld[3]);
      for (int k = 0; k < 3; ++k) EXPECT_TRUE(double(w.min[k]) <= x[k] && x[k] <= double(w.max[k]));
    }
  }
  const std::vector<glm::uvec4> staticPart(p.streams.nodes.begin(), p.streams.nodes.begin() + std::ptrdiff_t(p.dynamicTexelBegin));
  TwoLevelScene moved = scene;
  for (Instance& inst : moved.instances) inst.objectToWorld[3] += glm::vec3(1.0f, 2.0f, 3.0f);
  repackTopLevel(p, moved.instances);
  EXPECT_TRUE(std::equal(staticPart.begin() + 1, staticPart.end(), p.streams.nodes.begin() + 1))
      << "repackTopLevel rewrote the BLAS region";
  // The repacked tree traces the moved scene: brute force agrees on every clear ray.
  {
    const std::vector<FlatTriangle> flat = flatten(moved);
    Aabb bounds;
    for (const FlatTriangle& f : flat)
      for (const glm::dvec3& v : {f.v0, f.v1, f.v2}) bounds.grow(glm::vec3(v));
    const glsl::Storage storage(p.streams);
    const TwoLevelMirror m = twoLevelMirror("stack-ordered", Robustness::Watertight);
    Tally tally;
    for (const RayQuery& q : sceneRays(moved, bounds, 200, 31)) {
      const MirrorRun r = runMirror(m, storage, q);
      agrees(p, r.closest, r.any, r.hit, reference(flat, q), q, "repacked", tally);
    }
    EXPECT_EQ(tally.failures, 0u);
    EXPECT_GT(tally.hits, tally.clear / 10);
  }
  // Bad input: clear errors.
  auto message = [](auto f) {
    try {
      f();
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::vector<PackedBvh> blases = packBlases(scene, "v1");
  EXPECT_NE(message([&] { packTwoLevel(blases, {{9, glm::mat4x3(1.0f)}}); }).find("names BLAS 9"), std::string::npos);
  EXPECT_NE(message([&] { packTwoLevel(blases, {{0, glm::mat4x3(0.0f)}}); }).find("singular"), std::string::npos);
  EXPECT_NE(message([&] { packTwoLevel(blases, {}); }).find("no instances"), std::string::npos);
  EXPECT_NE(message([&] { packTwoLevel(packBlases(scene, "bvh4"), scene.instances); }).find("no two-level walk"),
            std::string::npos);
  EXPECT_NE(message([&] { twoLevelMirror("bvh4-stack-ordered", Robustness::Fast); }).find("stack-ordered"), std::string::npos);
  EXPECT_NE(message([&] { checkTwoLevel("bvh8", ""); }).find("v1, bvh2-cb"), std::string::npos);
}

// ---- GLSL ---------------------------------------------------------------------------------------

// Per ray: closest hit, then any hit, with every counter.
const char* const kTwoLevelMain = R"(
layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer RayBuffer { vec4 rays[]; };
layout(std430, binding = 1) writeonly buffer ResultBuffer { uvec4 results[]; };
uniform int u_count;
void main() {
  int i = int(gl_GlobalInvocationID.x);
  if (i >= u_count) return;
  Ray ray = Ray(rays[2 * i].xyz, rays[2 * i + 1].xyz);
  float tMin = rays[2 * i].w, tMax = rays[2 * i + 1].w;
  MeshHit hit;
  bool closest = traceClosest(ray, tMin, tMax, hit);
  results[4 * i + 1] = uvec4(uint(g_instance), g_nodeVisits, g_triTests, g_boxTests);
  results[4 * i + 2] = uvec4(g_tlasNodeVisits, g_instanceTests, g_tlasBoxTests, g_stackOverflow ? 1u : 0u);
  g_nodeVisits = 0u; g_triTests = 0u; g_boxTests = 0u;
  g_tlasNodeVisits = 0u; g_instanceTests = 0u; g_tlasBoxTests = 0u;
  bool any = traceAny(ray, tMin, tMax);
  results[4 * i + 0] = uvec4(closest ? 1u : 0u, uint(hit.tri), floatBitsToUint(hit.t), any ? 1u : 0u);
  results[4 * i + 3] = uvec4(g_nodeVisits, g_triTests, g_tlasNodeVisits, g_instanceTests);
}
)";

struct GlRun {
  bool closest, any;
  TwoLevelHit hit;
  uint32_t c[6], a[4];  // closest: blas visits, tri tests, box tests, tlas visits, instance tests, tlas box tests
  bool overflow;
};

std::vector<GlRun> traceOnGl(const std::string& layout, const std::string& kernel, Robustness robust, Storage storage,
                             const PackedTwoLevel& p, const std::vector<RayQuery>& rays) {
  const AssembledShader shader = assembleTraversal(kernel, storage, robust, stackSizeFor(p.streams), "", layout, "raw", true);
  GLuint program;
  try {
    program = test::compileCompute(shader.source + kTwoLevelMain);
  } catch (const std::exception& e) {
    ADD_FAILURE() << shader.mapLog(e.what());
    return {};
  }
  const std::vector<glm::uvec4>* streams[3] = {&p.streams.nodes, &p.streams.triangles, &p.streams.attributes};
  // The streams in the storage kind: texture buffers or 2D textures on units 0..2, or storage buffers
  // at traversal/storage_ssbo.glsl's bindings 4..6.
  GLuint buffers[3], textures[3];
  glCreateBuffers(3, buffers);
  glCreateTextures(storage == Storage::Tex2D ? GL_TEXTURE_2D : GL_TEXTURE_BUFFER, 3, textures);
  for (GLuint unit = 0; unit < 3; ++unit) {
    const std::vector<glm::uvec4>& texels = *streams[unit];
    if (storage == Storage::Tex2D) {
      const GLsizei w = GLsizei(kTex2DWidth), h = GLsizei((texels.size() + kTex2DWidth - 1) / kTex2DWidth);
      std::vector<glm::uvec4> padded(size_t(w) * size_t(h), glm::uvec4(0));
      std::copy(texels.begin(), texels.end(), padded.begin());
      glTextureStorage2D(textures[unit], 1, GL_RGBA32UI, w, h);
      glTextureSubImage2D(textures[unit], 0, 0, 0, w, h, GL_RGBA_INTEGER, GL_UNSIGNED_INT, padded.data());
      glTextureParameteri(textures[unit], GL_TEXTURE_MIN_FILTER, GL_NEAREST);
      glTextureParameteri(textures[unit], GL_TEXTURE_MAG_FILTER, GL_NEAREST);
      glBindTextureUnit(unit, textures[unit]);
      continue;
    }
    glNamedBufferData(buffers[unit], GLsizeiptr(texels.size() * sizeof(glm::uvec4)), texels.data(), GL_STATIC_DRAW);
    if (storage == Storage::Ssbo) {
      glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 4 + unit, buffers[unit]);
      continue;
    }
    glTextureBuffer(textures[unit], GL_RGBA32UI, buffers[unit]);
    glBindTextureUnit(unit, textures[unit]);
  }
  glUseProgram(program);
  const char* names[3] = {"u_nodes", "u_triangles", "u_attributes"};
  for (int unit = 0; unit < 3; ++unit)
    if (storage != Storage::Ssbo) glUniform1i(glGetUniformLocation(program, names[unit]), unit);
  std::vector<glm::vec4> in;
  for (const RayQuery& q : rays) {
    in.emplace_back(q.ray.origin, q.tMin);
    in.emplace_back(q.ray.dir, q.tMax);
  }
  const std::vector<glm::uvec4> out =
      test::dispatchCompute<glm::uvec4>(program, in, rays.size() * 4, rays.size(), "two-level dispatch");
  glDeleteTextures(3, textures);
  glDeleteBuffers(3, buffers);
  glDeleteProgram(program);
  std::vector<GlRun> runs(rays.size());
  for (size_t i = 0; i < rays.size(); ++i) {
    const glm::uvec4 a = out[4 * i], b = out[4 * i + 1], c = out[4 * i + 2], d = out[4 * i + 3];
    GlRun& r = runs[i];
    r.closest = a.x != 0;
    r.any = a.w != 0;
    r.hit.hit = MeshHit{std::bit_cast<float>(a.z), int(a.y), glm::vec2(0.0f)};
    r.hit.record = int(b.x);
    const uint32_t cs[6] = {b.y, b.z, b.w, c.x, c.y, c.z};
    std::copy(cs, cs + 6, r.c);
    const uint32_t as[4] = {d.x, d.y, d.z, d.w};
    std::copy(as, as + 4, r.a);
    r.overflow = c.w != 0;
  }
  return runs;
}

TEST(TwoLevelGlsl, GlslEqualsTheMirrorAndBruteForce) {
  std::unique_ptr<GlContext> context;
  try {
    const char* backend = std::getenv("BVHLAB_GL_BACKEND");
    context = createContext(backend && *backend ? parseBackend(backend) : Backend::OSMesa);
  } catch (const std::exception& e) {
    BVHLAB_SKIP_OR_FAIL("no OpenGL 4.5 context (" << e.what() << "): GLSL not run");
  }
  struct Case {
    const char* name;
    TwoLevelScene scene;
  };
  const std::vector<Case> cases = {{"near the origin", randomScene(glm::vec3(0.0f), glm::vec3(1.0f), 10, 13)},
                                   {"at 1e5, scale (1, 10, 0.1)",
                                    randomScene(glm::vec3(1e5f, -1e5f, 1e5f), glm::vec3(1.0f, 10.0f, 0.1f), 10, 14)}};
  size_t compared = 0, identical = 0;
  for (const Case& c : cases) {
    const std::vector<FlatTriangle> flat = flatten(c.scene);
    Aabb bounds;
    for (const FlatTriangle& f : flat)
      for (const glm::dvec3& v : {f.v0, f.v1, f.v2}) bounds.grow(glm::vec3(v));
    const std::vector<RayQuery> rays = sceneRays(c.scene, bounds, 256, 15);
    std::vector<Reference> refs;
    for (const RayQuery& q : rays) refs.push_back(reference(flat, q));
    for (const auto& [layout, kernel] : layoutKernels()) {
      const PackedTwoLevel packed = packTwoLevel(packBlases(c.scene, layout), c.scene.instances);
      const glsl::Storage mirrorStorage(packed.streams);
      // Every storage kind reads the same streams; the fast tests, and the watertight ones from tbo.
      for (const auto& [robust, storage] : {std::pair{Robustness::Fast, Storage::Tbo}, std::pair{Robustness::Watertight, Storage::Tbo},
                                            std::pair{Robustness::Fast, Storage::Tex2D}, std::pair{Robustness::Fast, Storage::Ssbo}}) {
        const std::string who = std::string(c.name) + " " + layout + "/" + kernel + "/" + robustnessName(robust) + "/" +
                                 storageName(storage);
        SCOPED_TRACE(who);
        const std::vector<GlRun> gpu = traceOnGl(layout, kernel, robust, storage, packed, rays);
        ASSERT_EQ(gpu.size(), rays.size());
        const TwoLevelMirror m = twoLevelMirror(kernel, robust);
        Tally tally;
        size_t failures = 0;
        for (size_t i = 0; i < rays.size(); ++i) {
          const MirrorRun r = runMirror(m, mirrorStorage, rays[i]);
          const GlRun& g = gpu[i];
          agrees(packed, g.closest, g.any, g.hit, refs[i], rays[i], "GLSL " + who, tally);
          const uint32_t mc[6] = {r.cc.blas.nodeVisits, r.cc.blas.triTests, r.cc.blas.boxTests,
                                  r.cc.tlas.nodeVisits, r.cc.tlas.triTests, r.cc.tlas.boxTests};
          const uint32_t ma[4] = {r.ac.blas.nodeVisits, r.ac.blas.triTests, r.ac.tlas.nodeVisits, r.ac.tlas.triTests};
          // t may differ in its last bits (the driver's own evaluation order in dot and cross).
          const double relT = g.hit.hit.t == r.hit.hit.t ? 0.0
                                                           : std::abs(double(g.hit.hit.t) - double(r.hit.hit.t)) /
                                                                 std::abs(double(r.hit.hit.t));
          const bool same = g.closest == r.closest && g.any == r.any && g.hit.hit.tri == r.hit.hit.tri &&
                            g.hit.record == r.hit.record && relT <= 1e-6 && std::equal(mc, mc + 6, g.c) &&
                            std::equal(ma, ma + 4, g.a) && !g.overflow;
          ++compared;
          identical += same;
          if (!same && ++failures <= 3)
            ADD_FAILURE() << "GLSL found " << g.closest << "/" << g.any << " tri " << g.hit.hit.tri << " record "
                          << g.hit.record << " t " << g.hit.hit.t << " counters " << g.c[0] << " " << g.c[1] << " "
                          << g.c[2] << " " << g.c[3] << " " << g.c[4] << " " << g.c[5] << "; mirror " << r.closest << "/"
                          << r.any << " tri " << r.hit.hit.tri << " record " << r.hit.record << " t " << r.hit.hit.t
                          << " counters " << mc[0] << " " << mc[1] << " " << mc[2] << " " << mc[3] << " " << mc[4]
                          << " " << mc[5] << "; " << describe(rays[i]);
        }
        EXPECT_EQ(tally.failures, 0u);
        EXPECT_GT(tally.hits, tally.clear / 10);
      }
    }
  }
  // The ray tracer's shader (`bvhlab trace`: trace_rays.glsl) assembles and compiles over a two-level
  // tree, closest and any hit, with the counters.
  for (const auto& [layout, kernel] : {layoutKernels()[0], layoutKernels()[3]})
    for (bool anyHit : {false, true}) {
      const AssembledShader shader =
          assembleRayTracer(kernel, Storage::Tbo, Robustness::Watertight, 8, anyHit, true, layout, "raw", true);
      EXPECT_TRUE(shader.hasModule("two_level.glsl"));
      try {
        glDeleteProgram(test::compileCompute(shader.source));
      } catch (const std::exception& e) {
        ADD_FAILURE() << layout << "/" << kernel << ": " << shader.mapLog(e.what());
      }
    }
  // The renderer's fragment shader (uber: every module) compiles over a two-level tree too. Its
  // shading still takes normals in object space (instanceNormalToWorld is not called by shade.glsl).
  {
    ShaderOptions options;
    options.uber = true;
    options.twoLevel = true;
    const AssembledShader shader = assembleTracer(SceneFeatures{}, options);
    GLuint fs = glCreateShader(GL_FRAGMENT_SHADER);
    const char* text = shader.source.c_str();
    glShaderSource(fs, 1, &text, nullptr);
    glCompileShader(fs);
    GLint ok = 0;
    glGetShaderiv(fs, GL_COMPILE_STATUS, &ok);
    char log[4096] = {};
    glGetShaderInfoLog(fs, sizeof log, nullptr, log);
    EXPECT_TRUE(ok) << shader.mapLog(log);
    glDeleteShader(fs);
  }
  std::printf("two-level GLSL vs mirror on %s: %zu of %zu ray queries agree on hits and every counter\n",
              context->renderer().c_str(), identical, compared);
  EXPECT_EQ(identical, compared);
}

}  // namespace
}  // namespace bvhlab
