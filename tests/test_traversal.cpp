// The traversal kernels (traversal/kernel_*.glsl through their C++ mirrors): every builder x every
// kernel against brute force over all triangles, the counters against independent recursive
// definitions, the stack bounds, the ray-box / ray-triangle tests, and the GLSL through glslang.
// The GLSL run on a GL device against the mirrors: test_traversal_glsl.cpp; shared helpers:
// traversal_test_util.hpp.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <glad/gl.h>
#include <glm/gtc/constants.hpp>
#include <gtest/gtest.h>
#include <unistd.h>

#include "datasets/random_draws.hpp"
#include "gl_compute.hpp"
#include "builders/builder.hpp"
#include "datasets/mesh_io.hpp"
#include "layout/layout.hpp"
#include "render/gl_context.hpp"
#include "shaders/assemble.hpp"
#include "traversal/kernels.hpp"
#include "traversal/ray_box.hpp"
#include "traversal/ray_triangle.hpp"

#include "traversal_test_util.hpp"
#include "require.hpp"

namespace bvhlab {
namespace {

using namespace traversaltest;
using test::compileCompute;

// ---- tests --------------------------------------------------------------------------------------

TEST(Traversal, RegistryAndStackSize) {
  ASSERT_GE(kernels().size(), 3u);
  for (const KernelInfo& k : kernels()) {
    EXPECT_EQ(&findKernel(k.name), &k);
    EXPECT_NO_THROW(glslModule(k.glslFile)) << k.name << " names a GLSL file that is not embedded";
    EXPECT_NE(k.traceClosest, nullptr);
    EXPECT_NE(k.traceAny, nullptr);
  }
  try {
    findKernel("no-such-kernel");
    ADD_FAILURE() << "no error for an unknown kernel";
  } catch (const std::invalid_argument& e) {
    for (const KernelInfo& k : kernels()) EXPECT_NE(std::string(e.what()).find(k.name), std::string::npos) << e.what();
  }
  EXPECT_EQ(stackSizeFor(0), 1);
  EXPECT_EQ(stackSizeFor(1), 1);
  EXPECT_EQ(stackSizeFor(37), 37);
}

TEST(Traversal, SphereFromOutsideAndInside) {
  const TriangleSoup soup = soupOf({sphereMesh(16, 32, 1.0f)});
  std::vector<RayQuery> rays = mixedRays(soup, 300, 1);
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int i = 0; i < 100; ++i)  // from inside a closed surface every ray hits
    rays.push_back({{draw3<glm::vec3>(u, rng) * 0.3f, draw3<glm::vec3>(u, rng)}, 0.0f, glsl::INF});
  checkScene("sphere", soup, rays, true);
}

TEST(Traversal, RandomSoup) {
  const TriangleSoup soup = soupOf({randomSoupMesh(600, 4)});
  checkScene("random soup", soup, mixedRays(soup, 400, 5), true);
}

TEST(Traversal, FlatGridWithTiesAndAxisAlignedRays) {
  const TriangleSoup soup = soupOf({gridMesh(12)});
  std::vector<RayQuery> rays = mixedRays(soup, 200, 6);
  // Straight down through grid vertices and edge midpoints: direction components exactly 0, origins
  // exactly on slab planes, up to six triangles hit at the same t.
  for (int i = 0; i <= 12; ++i)
    for (int j = 0; j <= 24; j += 3) {
      const glm::vec3 o(-1.0f + 2.0f * float(i) / 12.0f, 1.0f, -1.0f + 2.0f * float(j) / 24.0f);
      rays.push_back({{o, glm::vec3(0.0f, -1.0f, 0.0f)}, 0.0f, glsl::INF});
      rays.push_back({{o, glm::vec3(0.0f, -1.0f, 0.0f)}, 0.0f, 1.0f});  // ends exactly on the plane: a miss
    }
  // In the plane, parallel to it: the flat boxes are entered but no triangle can be hit (det = 0).
  rays.push_back({{glm::vec3(-2.0f, 0.0f, 0.1f), glm::vec3(1.0f, 0.0f, 0.0f)}, 0.0f, glsl::INF});
  checkScene("grid", soup, rays, true);
}

TEST(Traversal, Bunny) {
  const std::filesystem::path path = std::filesystem::path(BVHLAB_SOURCE_DIR) / "datasets/cache/meshes/bunny00.off";
  if (!std::filesystem::exists(path)) BVHLAB_SKIP_OR_FAIL(path << " not found: run datasets/fetch.sh to test on the bunny");
  const TriangleSoup soup = soupOf({loadMesh(path)});
  checkScene("bunny", soup, mixedRays(soup, 150, 7), false);
}

// Triangles stacked along z over the same square, in a chain tree: every box is hit by a ray down
// the z axis, which is what makes the documented stack bounds tight.
TEST(Traversal, StackBoundsAreExactAndOverflowIsReported) {
  const int n = 40;
  Mesh m;
  for (int k = 0; k < n; ++k) {
    const float z = float(k);
    const uint32_t base = uint32_t(m.positions.size());
    m.positions.insert(m.positions.end(), {{-1.0f, -1.0f, z}, {1.0f, -1.0f, z}, {-1.0f, 1.0f, z}});
    m.triangles.push_back({base, base + 1, base + 2});
  }
  const TriangleSoup soup = soupOf({m});
  const PackedBvh packed = packBvh(chainBvh(triangleBoxes(soup)), soup);
  ASSERT_EQ(packed.depth, uint32_t(n));
  const int depth = int(packed.depth);
  const Ray ray{glm::vec3(-0.5f, -0.25f, float(n) + 5.0f), glm::vec3(0.0f, 0.0f, -1.0f)};
  const float expectedT = 6.0f;  // the top triangle, z = n - 1

  // kernel -> the smallest stack that never overflows, from the bound documented in its GLSL file
  const std::map<std::string, int> bounds = {{"stack-unordered", depth}, {"stack-ordered", depth - 1}};
  for (const auto& [name, bound] : bounds) {
    SCOPED_TRACE(name);
    const KernelInfo& k = findKernel(name);
    ASSERT_LE(bound, stackSizeFor(packed.depth));
    Counters enough, tooSmall;
    MeshHit hit;
    EXPECT_TRUE(k.traceClosest(glsl::Storage(packed, bound), ray, 0.0f, glsl::INF, hit, enough));
    EXPECT_FALSE(enough.stackOverflow);
    EXPECT_EQ(hit.t, expectedT);
    k.traceClosest(glsl::Storage(packed, bound - 1), ray, 0.0f, glsl::INF, hit, tooSmall);
    EXPECT_TRUE(tooSmall.stackOverflow) << "a stack of " << bound - 1 << " must overflow on this chain";
    Counters anyCounters;
    k.traceAny(glsl::Storage(packed, bound - 1), ray, 0.0f, glsl::INF, anyCounters);
    EXPECT_TRUE(anyCounters.stackOverflow);
  }
  // The stackless kernel needs no stack at all.
  Counters c;
  MeshHit hit;
  EXPECT_TRUE(findKernel("stackless").traceClosest(glsl::Storage(packed, 1), ray, 0.0f, glsl::INF, hit, c));
  EXPECT_EQ(hit.t, expectedT);
  EXPECT_THROW(glsl::Storage(packed, 0), std::invalid_argument);
}

// A node stream of zeros (what llvmpipe hands a fragment shader's helper invocations from a storage
// buffer) ends every v1 kernel's walk when the ray misses the zero box: the stack kernels pop an
// empty stack, the stackless one meets an escape link that does not move forward. Before the
// stackless kernel checked that, its walk never ended (node 0's escape link is node 0).
TEST(Kernels, ARecordOfZerosEndsTheWalk) {
  const TriangleSoup soup = soupOf({sphereMesh(16, 32, 1.0f)});
  PackedBvh packed = packBvh(buildBvh("sah-binned", BuildInput{triangleBoxes(soup), triangleCentroids(soup)}, BuildOptions{}), soup);
  std::fill(packed.nodes.begin(), packed.nodes.end(), glm::uvec4(0u));
  for (const glm::vec3 origin : {glm::vec3(1.0f, 0.0f, 5.0f), glm::vec3(-3.0f, 2.0f, 0.5f)}) {
    const Ray ray{origin, glm::vec3(0.0f, 0.0f, -1.0f)};  // misses the point box at the origin
    for (const KernelInfo& k : kernels()) {
      SCOPED_TRACE(k.name);
      Counters c;
      MeshHit hit;
      k.traceClosest(glsl::Storage(packed), ray, 0.0f, glsl::INF, hit, c);
      // At most the root and its two child records (stack-unordered loads both before it tests them).
      EXPECT_LE(c.nodeVisits, 3u) << "the walk went on over records of zeros";
      Counters any;
      k.traceAny(glsl::Storage(packed), ray, 0.0f, glsl::INF, any);
      EXPECT_LE(any.nodeVisits, 3u);
    }
  }
}

TEST(RayBox, InverseDirectionIsFiniteAndSlabsNeverSeeNan) {
  for (float d : {0.0f, -0.0f, 1e-40f, -1e-40f, 1e-31f}) {
    const glm::vec3 inv = glsl::rayInverseDirection(glm::vec3(d, 1.0f, -2.0f));
    EXPECT_TRUE(std::isfinite(inv.x)) << d;
    if (d != 0.0f) {
      EXPECT_EQ(std::signbit(inv.x), std::signbit(d)) << d;  // a zero may become either sign
    }
    EXPECT_EQ(inv.y, 1.0f);
    EXPECT_EQ(inv.z, -0.5f);
  }
  // Parallel to x = 0 and lying in it: the box [0,1]^3 spans the plane, so the ray meets it;
  // with the origin just outside the slab it does not.
  const glm::vec3 dir(0.0f, 1.0f, 0.0f), inv = glsl::rayInverseDirection(dir);
  float tEnter = -1.0f;
  EXPECT_TRUE(glsl::intersectAabb(glm::vec3(0.5f, -1.0f, 0.5f), inv, glm::vec3(0), glm::vec3(1), 0.0f, glsl::INF, tEnter));
  EXPECT_EQ(tEnter, 1.0f);
  EXPECT_FALSE(glsl::intersectAabb(glm::vec3(1.5f, -1.0f, 0.5f), inv, glm::vec3(0), glm::vec3(1), 0.0f, glsl::INF, tEnter));
  EXPECT_FALSE(std::isnan(tEnter));
  // On either bounding plane of the slab: inside (the box is closed), whatever the sign of the zero.
  for (float x : {0.0f, 1.0f})
    for (float zero : {0.0f, -0.0f}) {
      const glm::vec3 invZero = glsl::rayInverseDirection(glm::vec3(zero, 1.0f, 0.0f));
      EXPECT_TRUE(glsl::intersectAabb(glm::vec3(x, -1.0f, 0.5f), invZero, glm::vec3(0), glm::vec3(1), 0.0f, glsl::INF, tEnter))
          << "origin x = " << x << ", dir x = " << zero;
      EXPECT_EQ(tEnter, 1.0f);
    }
  // A flat box (min = max on an axis), as every node over a plane has, with the ray in its plane.
  EXPECT_TRUE(glsl::intersectAabb(glm::vec3(0.5f, -1.0f, 0.5f), inv, glm::vec3(0, 0, 0.5f), glm::vec3(1, 1, 0.5f), 0.0f,
                                  glsl::INF, tEnter));
  // The interval clips: a box wholly behind tMax's end or before tMin's start is missed.
  const glm::vec3 along = glsl::rayInverseDirection(glm::vec3(1, 0, 0));
  EXPECT_FALSE(glsl::intersectAabb(glm::vec3(-5, 0.5f, 0.5f), along, glm::vec3(0), glm::vec3(1), 0.0f, 4.0f, tEnter));
  EXPECT_TRUE(glsl::intersectAabb(glm::vec3(-5, 0.5f, 0.5f), along, glm::vec3(0), glm::vec3(1), 0.0f, 5.0f, tEnter));
  EXPECT_FALSE(glsl::intersectAabb(glm::vec3(-5, 0.5f, 0.5f), along, glm::vec3(0), glm::vec3(1), 6.5f, 9.0f, tEnter));
  EXPECT_TRUE(glsl::intersectAabb(glm::vec3(-5, 0.5f, 0.5f), along, glm::vec3(0), glm::vec3(1), 5.5f, 9.0f, tEnter));
  EXPECT_EQ(tEnter, 5.5f);
}

TEST(RayTriangle, OpenIntervalEdgesAndDegenerates) {
  const glm::vec3 v0(0, 0, 0), v1(1, 0, 0), v2(0, 1, 0);
  const Ray down{glm::vec3(0.25f, 0.25f, 2.0f), glm::vec3(0, 0, -1)};
  float t;
  glm::vec2 bary;
  EXPECT_TRUE(glsl::intersectTriangle(down, v0, v1, v2, 0.0f, glsl::INF, t, bary));
  EXPECT_EQ(t, 2.0f);
  EXPECT_EQ(bary, glm::vec2(0.25f, 0.25f));
  EXPECT_FALSE(glsl::intersectTriangle(down, v0, v1, v2, 0.0f, 2.0f, t, bary)) << "t == tMax is outside";
  EXPECT_FALSE(glsl::intersectTriangle(down, v0, v1, v2, 2.0f, glsl::INF, t, bary)) << "t == tMin is outside";
  EXPECT_TRUE(glsl::intersectTriangle(down, v0, v1, v2, 1.9f, 2.1f, t, bary));
  // Edges and vertices belong to the triangle.
  EXPECT_TRUE(glsl::intersectTriangle({glm::vec3(0.5f, 0.0f, 1.0f), glm::vec3(0, 0, -1)}, v0, v1, v2, 0.0f, glsl::INF, t, bary));
  EXPECT_TRUE(glsl::intersectTriangle({glm::vec3(0.0f, 1.0f, 1.0f), glm::vec3(0, 0, -1)}, v0, v1, v2, 0.0f, glsl::INF, t, bary));
  EXPECT_FALSE(glsl::intersectTriangle({glm::vec3(0.6f, 0.6f, 1.0f), glm::vec3(0, 0, -1)}, v0, v1, v2, 0.0f, glsl::INF, t, bary));
  // Parallel ray in the plane, a zero-area triangle, a denormal determinant: misses, no NaN.
  EXPECT_FALSE(glsl::intersectTriangle({glm::vec3(-1, 0.2f, 0), glm::vec3(1, 0, 0)}, v0, v1, v2, 0.0f, glsl::INF, t, bary));
  EXPECT_FALSE(glsl::intersectTriangle(down, v0, v1, glm::vec3(2, 0, 0), 0.0f, glsl::INF, t, bary));
  EXPECT_FALSE(std::isnan(t));
  const float tiny = 1e-20f;  // det ~ 1e-40: below the smallest normal float
  EXPECT_FALSE(glsl::intersectTriangle({glm::vec3(0.25f * tiny, 0.25f * tiny, 1.0f), glm::vec3(0, 0, -1)}, v0,
                                       glm::vec3(tiny, 0, 0), glm::vec3(0, tiny, 0), 0.0f, glsl::INF, t, bary));
  EXPECT_FALSE(std::isnan(t));
  // Backfaces hit too (no culling): the kernels serve refraction rays leaving a surface.
  EXPECT_TRUE(glsl::intersectTriangle({glm::vec3(0.25f, 0.25f, -2.0f), glm::vec3(0, 0, 1)}, v0, v1, v2, 0.0f, glsl::INF, t, bary));
}

TEST(TraversalLayout, AttributesInterpolateLikeTheGlsl) {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.normals = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.uvs = {{0, 0}, {1, 0}, {0, 1}};
  m.triangles = {{0, 1, 2}};
  const TriangleSoup soup = soupOf({m});
  Bvh bvh;
  bvh.nodes.resize(1);
  bvh.nodes[0].count = 1;
  bvh.nodes[0].bounds = triangleBoxes(soup)[0];
  bvh.primIndices = {0};
  const PackedBvh packed = packBvh(bvh, soup);
  glm::vec3 n;
  glm::vec2 uv;
  glsl::loadAttributes(packed, 0, glm::vec2(0.25f, 0.5f), n, uv);
  EXPECT_EQ(n, glm::vec3(0.25f, 0.25f, 0.5f));  // weights (1 - u - v, u, v), not normalised
  EXPECT_EQ(uv, glm::vec2(0.25f, 0.5f));
  uint32_t primitive, material, mesh;
  glsl::loadTriangleIds(packed, 0, primitive, material, mesh);
  EXPECT_EQ(primitive, 0u);
  EXPECT_EQ(material, 0u);
  EXPECT_EQ(mesh, 0u);
}

// The GLSL itself: every kernel with both storage kinds, concatenated in assembly order under a stub
// main, must compile with the reference front end.
TEST(TraversalGlsl, EveryKernelCompilesWithGlslang) {
  if (std::system("command -v glslangValidator > /dev/null 2>&1") != 0)
    BVHLAB_SKIP_OR_FAIL("glslangValidator not found (Debian package glslang-tools)");
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("bvhlab_test_traversal_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string stubMain = R"(
layout(location = 0) out uvec4 o_result;
void main() {
  Ray ray = Ray(vec3(gl_FragCoord.xy, -1.0), vec3(0.0, 0.0, 1.0));
  MeshHit hit;
  bool closest = traceClosest(ray, 0.0, INF, hit);
  bool any = traceAny(ray, 0.0, INF);
  vec3 normal;
  vec2 uv;
  if (closest) loadAttributes(hit.tri, hit.bary, normal, uv);
  o_result = uvec4(floatBitsToUint(hit.t), uint(hit.tri), g_nodeVisits + g_triTests,
                   uint(any) + (g_stackOverflow ? 2u : 0u) + floatBitsToUint(normal.x + uv.y));
}
)";
  for (const char* storage : {"storage_tbo.glsl", "storage_tex2d.glsl", "storage_ssbo.glsl"})
    for (const KernelInfo& k : kernels()) {
      std::string source = "#version 450 core\n#define BVH_STACK_SIZE 7\n";
      for (const std::string& module : {std::string("common.glsl"), std::string(storage), std::string("layout.glsl"),
                                        std::string("ray_box.glsl"), std::string("ray_triangle.glsl"),
                                        std::string("triangles_raw.glsl"), k.glslFile})
        source += glslModule(module);
      source += stubMain;
      const std::filesystem::path file = dir / (k.name + "_" + storage + ".frag");
      const std::filesystem::path log = dir / (k.name + "_" + storage + ".log");
      std::ofstream(file) << source;
      const std::string cmd = "glslangValidator -S frag '" + file.string() + "' > '" + log.string() + "' 2>&1";
      const int rc = std::system(cmd.c_str());
      std::stringstream text;
      text << std::ifstream(log).rdbuf();
      EXPECT_EQ(rc, 0) << k.name << " with " << storage << ":\n" << text.str();
    }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace bvhlab
