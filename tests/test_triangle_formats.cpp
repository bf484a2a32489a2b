// Triangle formats as a second layout axis (layout/triangle_formats.hpp): the registry and
// the refused pairings, what each format decodes to (indexed: the soup's positions exactly, normals
// within the oct32 bound, uvs within half precision), the bytes each stream takes, every format x
// node layout x kernel against brute force, and the GLSL accessor modules against their mirrors.
#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <glm/gtc/packing.hpp>
#include <nlohmann/json.hpp>

#include "cli_run.hpp"
#include "gl_compute.hpp"
#include "layout/layouts.hpp"
#include "layout/triangle_formats.hpp"
#include "layout_test_util.hpp"
#include "render/gpu_renderer.hpp"
#include "render/ray_tracer_gl.hpp"
#include "shaders/assemble.hpp"
#include "traversal/intersectors.hpp"
#include "traversal/kernels.hpp"
#include "require.hpp"

namespace bvhlab {
namespace {

[[maybe_unused]] ::testing::Environment* const kRemoveTestDir =
    ::testing::AddGlobalTestEnvironment(new clitest::RemoveTestDir);

using namespace layouttest;

std::string message(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "no exception";
}

PackedBvh packed(const LayoutInfo& layout, const Bvh& bvh, const TriangleSoup& soup, const std::string& format) {
  PackedBvh p = layout.pack(bvh, soup);
  packTriangles(p, soup, format);
  return p;
}

// The robustness variants a format runs: both triangle tests, or Moller-Trumbore only.
std::vector<Robustness> variantsFor(const std::string& format) {
  if (findTriangleFormat(format).watertight) return {Robustness::Watertight, Robustness::Fast};
  return {Robustness::Fast};
}

// The test meshes, plus one with normals and uvs on every vertex (the uv sphere has them; the others
// are flat: a corner's normal is its triangle's geometric normal).
const std::vector<TestMesh>& meshes() {
  static const std::vector<TestMesh> all = [] {
    std::vector<TestMesh> m = testMeshes();
    MeshSceneOptions mo;
    mo.groundPlane = false;
    Mesh smooth = makeUvSphere(20, 10);
    for (glm::vec2& uv : smooth.uvs) uv = 3.0f * uv - 0.5f;  // some uvs outside [0, 1]
    m.push_back({"smooth-sphere", gatherTriangles(makeMeshScene(smooth, mo))});
    return m;
  }();
  return all;
}

float angleBetween(glm::vec3 a, glm::vec3 b) {
  return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b));
}

TEST(TriangleFormats, RegistryAndRefusals) {
  ASSERT_EQ(triangleFormats().size(), 3u);
  EXPECT_EQ(triangleFormats().front().name, kDefaultTriangleFormat);
  for (const TriangleFormatInfo& f : triangleFormats()) {
    EXPECT_EQ(&findTriangleFormat(f.name), &f);
    EXPECT_NO_THROW(glslModule(f.glslModule)) << f.name;
  }
  std::string m = message([] { findTriangleFormat("strips"); });
  EXPECT_NE(m.find("valid formats: raw precomputed indexed"), std::string::npos) << m;
  // precomputed keeps rounded edges, not the vertices: every variant with the watertight triangle test
  // is refused, naming the ones that work; the other formats take every variant.
  for (Robustness r : robustnessVariants()) {
    EXPECT_NO_THROW(checkTriangleFormat("raw", r));
    EXPECT_NO_THROW(checkTriangleFormat("indexed", r));
    if (r.triangle == TriangleTest::Watertight) {
      m = message([&] { checkTriangleFormat("precomputed", r); });
      EXPECT_NE(m.find("--robust fast, box, ulp or box+ulp"), std::string::npos) << m;
      EXPECT_NE(m.find("watertight triangle test"), std::string::npos) << m;
    } else {
      EXPECT_NO_THROW(checkTriangleFormat("precomputed", r)) << robustnessName(r);
    }
  }
  // The assembler refuses the pairing too, before any GLSL is compiled.
  m = message([] { assembleRayTracer("stack-ordered", Storage::Tbo, Robustness::Watertight, 8, false, false, "v1",
                                     "precomputed"); });
  EXPECT_NE(m.find("watertight"), std::string::npos) << m;
  ShaderOptions so;
  so.triangles = "precomputed";  // robust stays watertight
  SceneFeatures f;
  f.mesh = true;
  EXPECT_THROW(assembleTracer(f, so), std::invalid_argument);
  so.robust = Robustness::Fast;
  EXPECT_TRUE(assembleTracer(f, so).hasModule("triangles_precomputed.glsl"));
  EXPECT_FALSE(assembleTracer(f, so).hasModule("triangles_raw.glsl"));
  // A mirror asked to run the pairing anyway throws rather than test something else.
  const TestMesh& mesh = meshes()[0];
  const PackedBvh p = packed(findLayout("v1"), build("sah-binned", mesh.soup), mesh.soup, "precomputed");
  float t;
  glsl::vec2 bary;
  EXPECT_THROW(glsl::RobustTests::testTriangle(p, glsl::Ray{glm::vec3(0.0f), glm::vec3(0, 0, 1)}, 0, 0.0f, 1.0f, t, bary),
               std::invalid_argument);
  // Packing twice, or from streams that are not raw, is an error, not a silent re-pack.
  PackedBvh twice = p;
  EXPECT_THROW(packTriangles(twice, mesh.soup, "indexed"), std::runtime_error);
}

// The oct32 code: every direction decodes within kOctNormalMaxError of itself (axes, the octahedron's
// folds and edges, and 200,000 random directions); kFlatNormal is never a code.
TEST(TriangleFormats, OctNormalsStayWithinTheirBound) {
  std::vector<glm::vec3> dirs = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1},
                                 {1, 1, 0}, {1, -1, 0}, {-1, 0, 1e-9f}, {0.5f, 0.5f, -1e-7f}, {1, 1, 1}, {-1, -1, -1}};
  std::mt19937 rng(3);
  std::normal_distribution<float> g;
  for (int i = 0; i < 200000; ++i) dirs.push_back({g(rng), g(rng), g(rng)});
  float worst = 0.0f;
  for (const glm::vec3& d : dirs) {
    const glm::vec3 n = glm::normalize(d);
    const uint32_t code = encodeOctNormal(n);
    ASSERT_NE(code, kFlatNormal);
    const glm::vec3 back = decodeOctNormal(code);
    EXPECT_EQ(glsl::indexed::decodeOctNormal(code), back) << "mirror = packer's decoder";
    worst = std::max(worst, angleBetween(n, back));
  }
  EXPECT_LE(worst, kOctNormalMaxError);
  EXPECT_GT(worst, 0.25f * kOctNormalMaxError) << "the bound should be near what is reached";
  std::printf("oct32 worst angle over %zu directions: %.3g rad (bound %.3g)\n", dirs.size(), worst, kOctNormalMaxError);
  EXPECT_THROW(encodeOctNormal(glm::vec3(0.0f)), std::invalid_argument);
}

// What each format's accessors give back for every TRIANGLE-stream triangle: the ids exactly; raw and
// indexed the soup's vertices exactly, precomputed v0 exactly and v1, v2 as v0 + rounded edges; the
// corner normals (bary at the corners) raw/precomputed exactly, indexed within the oct bound or as the
// geometric normal for a flat corner; uvs exactly or within half-float rounding.
TEST(TriangleFormats, AccessorsReturnTheSoup) {
  for (const TestMesh& m : meshes()) {
    const Bvh bvh = build("sbvh", m.soup);  // sbvh: a triangle may sit in several leaves
    for (const TriangleFormatInfo& f : triangleFormats()) {
      SCOPED_TRACE(m.name + " / " + f.name);
      const PackedBvh p = packed(findLayout("v1"), bvh, m.soup, f.name);
      const PackedBvh raw = packBvh(bvh, m.soup);
      ASSERT_EQ(p.triangleFormat, f.name);
      const glsl::Storage s(p);
      const size_t count = raw.triangles.size() / kTriangleTexels;
      int failures = 0;
      for (size_t j = 0; j < count && failures < 5; ++j) {
        const int tri = int(j);
        uint32_t prim, material, mesh;
        glsl::loadTriangleIds(s, tri, prim, material, mesh);
        ASSERT_EQ(prim, raw.triangles[3 * j].w) << "triangle " << j << ": the stream order is the node packer's";
        EXPECT_EQ(material, m.soup.material[prim]);
        EXPECT_EQ(mesh, m.soup.mesh[prim]);
        glm::vec3 v[3];
        glsl::loadTriangle(s, tri, v[0], v[1], v[2]);
        const glm::vec3 sv[3] = {m.soup.v0[prim], m.soup.v1[prim], m.soup.v2[prim]};
        const glm::vec3 sn[3] = {m.soup.n0[prim], m.soup.n1[prim], m.soup.n2[prim]};
        const glm::vec2 suv[3] = {m.soup.uv0[prim], m.soup.uv1[prim], m.soup.uv2[prim]};
        EXPECT_EQ(v[0], sv[0]);
        if (f.format == TriangleFormat::Precomputed) {
          EXPECT_EQ(v[1], sv[0] + (sv[1] - sv[0]));
          EXPECT_EQ(v[2], sv[0] + (sv[2] - sv[0]));
        } else {
          EXPECT_EQ(v[1], sv[1]);
          EXPECT_EQ(v[2], sv[2]);
        }
        const glm::vec2 corners[3] = {{0, 0}, {1, 0}, {0, 1}};
        for (int k = 0; k < 3; ++k) {
          glm::vec3 n;
          glm::vec2 uv;
          glsl::loadAttributes(s, tri, corners[k], n, uv);
          if (f.format != TriangleFormat::Indexed) {
            EXPECT_EQ(n, sn[k]);
            EXPECT_EQ(uv, suv[k]);
            continue;
          }
          const float angle = angleBetween(n, sn[k]);
          // A flat corner is recomputed from the same vertices: a few float roundings off, far below
          // the oct bound.
          if (!(angle <= kOctNormalMaxError) || std::abs(glm::length(n) - 1.0f) > 1e-6f) {
            ++failures;
            ADD_FAILURE() << "triangle " << j << " corner " << k << ": normal off by " << angle << " rad";
          }
          // Half floats: 11 significant bits, so |error| <= 2^-11 |uv| (rounded to nearest; 2^-25
          // absolute below the normal range, where uvs of 0 are exact).
          for (int c = 0; c < 2; ++c)
            EXPECT_LE(std::abs(uv[c] - suv[k][c]), std::ldexp(std::abs(suv[k][c]), -11) + 0x1.0p-25f);
        }
      }
    }
  }
}

// Welding is exact: the indexed VERTEX stream holds one vertex per distinct (mesh, material, position,
// normal or flat, uv) of the soup's corners, no fewer and no more; the smooth sphere shares vertices.
TEST(TriangleFormats, IndexedWeldsExactlyEqualCorners) {
  for (const TestMesh& m : meshes()) {
    SCOPED_TRACE(m.name);
    const PackedBvh p = packed(findLayout("v1"), build("sah-binned", m.soup), m.soup, "indexed");
    std::set<std::vector<float>> distinct;
    for (size_t i = 0; i < m.soup.size(); ++i) {
      const glm::vec3 v[3] = {m.soup.v0[i], m.soup.v1[i], m.soup.v2[i]};
      const glm::vec3 n[3] = {m.soup.n0[i], m.soup.n1[i], m.soup.n2[i]};
      const glm::vec2 uv[3] = {m.soup.uv0[i], m.soup.uv1[i], m.soup.uv2[i]};
      const glm::vec3 flat = geometricNormal(v[0], v[1], v[2]);
      for (int k = 0; k < 3; ++k) {
        const bool isFlat = n[k] == flat;
        distinct.insert({float(m.soup.mesh[i]), float(m.soup.material[i]), v[k].x, v[k].y, v[k].z,
                         isFlat ? 9.0f : n[k].x, isFlat ? 9.0f : n[k].y, isFlat ? 9.0f : n[k].z, uv[k].x, uv[k].y});
      }
    }
    EXPECT_EQ(p.vertices.size(), distinct.size());
    if (m.name == "soup") {
      EXPECT_EQ(p.vertices.size(), 3 * m.soup.size()) << "separate triangles share nothing";
    } else {
      EXPECT_LT(p.vertices.size(), 3 * m.soup.size()) << "corners shared by triangles weld";
    }
  }
}

// bytes(): the node stream is the layout's whatever the format; raw 112 B a triangle, precomputed 128,
// indexed 16 a triangle + 16 a vertex + 8 a vertex (two to an ATTRIBUTE texel).
TEST(TriangleFormats, BytesAccounting) {
  const TestMesh& m = meshes().back();
  const Bvh bvh = build("sah-binned", m.soup);
  for (const LayoutInfo& l : layouts()) {
    SCOPED_TRACE(l.name);
    const PackedBvh raw = packed(l, bvh, m.soup, "raw");
    const size_t t = raw.triangles.size() / kTriangleTexels, nodeBytes = 16 * raw.nodes.size();
    EXPECT_EQ(raw.bytes(), nodeBytes + 112 * t);
    const PackedBvh pre = packed(l, bvh, m.soup, "precomputed");
    EXPECT_EQ(pre.nodes, raw.nodes);
    EXPECT_EQ(pre.bytes(), nodeBytes + 128 * t);
    const PackedBvh idx = packed(l, bvh, m.soup, "indexed");
    const size_t v = idx.vertices.size();
    EXPECT_EQ(idx.nodes, raw.nodes);
    EXPECT_EQ(idx.bytes(), nodeBytes + 16 * t + 16 * v + 16 * ((v + 1) / 2));
    EXPECT_LT(idx.bytes(), raw.bytes());
  }
}

// Brute force in a format: every TRIANGLE-stream triangle through the format's testTriangle.
template <class Tests>
BatchHit bruteForceStream(const glsl::Storage& s, size_t count, const BatchRay& r) {
  BatchHit best;
  best.t = r.tMax;
  for (size_t j = 0; j < count; ++j) {
    float t;
    glsl::vec2 bary;
    if (Tests::testTriangle(s, glsl::Ray{r.origin, r.dir}, int(j), r.tMin, best.t, t, bary)) best = {true, 0, t};
  }
  return best;
}

size_t streamTriangles(const PackedBvh& p) {
  return p.triangles.size() / (p.triangleFormat == "raw" ? kTriangleTexels
                               : p.triangleFormat == "precomputed" ? kPrecomputedTriangleTexels
                                                                   : kIndexedTriangleTexels);
}

// Every format x node layout x kernel of that layout x the format's triangle tests finds brute force's
// closest t and its any-hit answer on every ray; raw and indexed with the watertight test also equal
// brute force over the soup (test_layout_bvh2cb's oracle), so the packing is checked too.
TEST(TriangleFormatKernels, EveryFormatLayoutAndKernelFindTheBruteForceHits) {
  for (const TestMesh& m : meshes()) {
    const std::vector<BatchRay> rays = testRays(m.soup, 240, 21);
    std::vector<BatchHit> soupHits;
    for (const BatchRay& r : rays) soupHits.push_back(bruteForce(m.soup, r));
    const Bvh bvh = build("sah-binned", m.soup);
    for (const LayoutInfo& l : layouts())
      for (const TriangleFormatInfo& f : triangleFormats()) {
        const PackedBvh p = packed(l, bvh, m.soup, f.name);
        const glsl::Storage s(p);
        for (Robustness robust : variantsFor(f.name)) {
          std::vector<BatchHit> expected;
          for (const BatchRay& r : rays)
            expected.push_back(robust == Robustness::Fast ? bruteForceStream<glsl::FastTests>(s, streamTriangles(p), r)
                                                          : bruteForceStream<glsl::RobustTests>(s, streamTriangles(p), r));
          // precomputed's arithmetic differs from Moller-Trumbore's only in rounding: the same hits as
          // raw with the fast test, t within 2^-16 relative, but for rays grazing an edge (a few).
          if (f.format == TriangleFormat::Precomputed) {
            const PackedBvh rawPacked = packed(l, bvh, m.soup, "raw");
            const glsl::Storage rawStorage(rawPacked);
            size_t disagree = 0;
            for (size_t i = 0; i < rays.size(); ++i) {
              const BatchHit mt = bruteForceStream<glsl::FastTests>(rawStorage, streamTriangles(rawPacked), rays[i]);
              disagree += mt.hit != expected[i].hit || (mt.hit && !nearlyEqual(mt.t, expected[i].t));
            }
            EXPECT_LE(disagree, rays.size() / 50) << m.name << " / " << l.name << ": precomputed vs raw";
          }
          if (robust == Robustness::Watertight) {
            for (size_t i = 0; i < rays.size(); ++i)
              ASSERT_TRUE(expected[i].hit == soupHits[i].hit && expected[i].t == soupHits[i].t)
                  << m.name << " / " << f.name << " ray " << i;
          }
          for (const KernelInfo& k : kernelsFor(l.name)) {
            SCOPED_TRACE(m.name + " / " + l.name + " / " + f.name + " / " + k.name + " / " + robustnessName(robust));
            expectBruteForceHits(p, k, robust, rays, expected);
          }
        }
      }
  }
}

// Each format's GLSL module (through each layout's default kernel) gives the mirror's answer and
// counters per ray, closest and any hit: the same triangle, t within llvmpipe's fused multiply-adds.
TEST(TriangleFormatKernelsGlsl, EqualTheMirrorPerRay) {
  auto ctx = contextOrNull();
  if (!ctx) BVHLAB_SKIP_OR_FAIL("no OpenGL 4.5 context");
  const TestMesh& m = meshes().back();
  const std::vector<BatchRay> rays = testRays(m.soup, 800, 13);
  const Bvh bvh = build("sah-binned", m.soup);
  for (const LayoutInfo& l : layouts())
    for (const TriangleFormatInfo& f : triangleFormats()) {
      const PackedBvh p = packed(l, bvh, m.soup, f.name);
      const glsl::Storage s(p);
      const KernelInfo& k = findKernel(l.name, "");
      for (Robustness robust : variantsFor(f.name))
        for (bool anyHit : {false, true}) {
          SCOPED_TRACE(l.name + " / " + f.name + " / " + robustnessName(robust) + (anyHit ? " any" : " closest"));
          RayTracerOptions o;
          o.kernel = k.name;
          o.robust = robust;
          o.anyHit = anyHit;
          GlRayTracer gl(p, o);
          gl.setRays(rays);
          std::vector<BatchHit> hits;
          const std::vector<glm::uvec4> counts = gl.traceCounted(&hits);
          int failures = 0;
          size_t found = 0;
          for (size_t i = 0; i < rays.size() && failures < 3; ++i) {
            const BatchRay& r = rays[i];
            glsl::Counters c;
            glsl::MeshHit mh{};
            uint32_t prim = BatchHit::kNoPrim, material, mesh;
            const bool hit = anyHit ? k.any(robust)(s, glsl::Ray{r.origin, r.dir}, r.tMin, r.tMax, c)
                                    : k.closest(robust)(s, glsl::Ray{r.origin, r.dir}, r.tMin, r.tMax, mh, c);
            if (hit && !anyHit) glsl::loadTriangleIds(s, mh.tri, prim, material, mesh);
            found += hit;
            if (hits[i].hit != hit || counts[i].x != c.nodeVisits || counts[i].y != c.triTests ||
                (!anyHit && hit && (hits[i].prim != prim || !nearlyEqual(hits[i].t, mh.t)))) {
              ++failures;
              ADD_FAILURE() << "ray " << i << ": GLSL " << hits[i].hit << " prim " << hits[i].prim << " visits "
                            << counts[i].x << " tests " << counts[i].y << "; mirror " << hit << " prim " << prim
                            << " visits " << c.nodeVisits << " tests " << c.triTests;
            }
          }
          EXPECT_GT(found, rays.size() / 10);
        }
    }
}

// Each format's GLSL accessors decode what their mirrors decode, triangle by triangle: vertices and ids
// exactly, the interpolated normal and uv to float rounding (llvmpipe may fuse the interpolation's
// multiply-adds; 1e-6 is far below the oct bound and far above that), flat corners included.
TEST(TriangleFormatKernelsGlsl, AccessorsEqualTheMirror) {
  auto ctx = contextOrNull();
  if (!ctx) BVHLAB_SKIP_OR_FAIL("no OpenGL 4.5 context");
  const char* kMain = R"(
layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer In { vec4 unused[]; };
layout(std430, binding = 1) writeonly buffer Out { uvec4 results[]; };
uniform int u_count;
void main() {
  int i = int(gl_GlobalInvocationID.x);
  if (i >= u_count) return;
  vec3 v0, v1, v2;
  loadTriangle(i, v0, v1, v2);
  uint primitive, material, mesh;
  loadTriangleIds(i, primitive, material, mesh);
  vec3 normal;
  vec2 uv;
  loadAttributes(i, vec2(0.2, 0.3), normal, uv);
  results[5 * i + 0] = uvec4(floatBitsToUint(v0), primitive);
  results[5 * i + 1] = uvec4(floatBitsToUint(v1), material);
  results[5 * i + 2] = uvec4(floatBitsToUint(v2), mesh);
  results[5 * i + 3] = uvec4(floatBitsToUint(normal), 0u);
  results[5 * i + 4] = uvec4(floatBitsToUint(uv), 0u, 0u);
}
)";
  for (const TestMesh& m : {meshes()[1], meshes().back()})  // flat corners, then smooth ones with uvs
    for (const TriangleFormatInfo& f : triangleFormats()) {
      SCOPED_TRACE(m.name + " / " + f.name);
      const PackedBvh p = packed(findLayout("v1"), build("sah-binned", m.soup), m.soup, f.name);
      const size_t count = streamTriangles(p);
      const std::string source = "#version 450 core\n#define BVH_STACK_SIZE 1\n" + glslModule("common.glsl") +
                                 glslModule("storage_tbo.glsl") + glslModule("ray_triangle.glsl") +
                                 glslModule(f.glslModule) + kMain;
      const GLuint program = test::compileCompute(source);
      unsigned buffers[4], textures[4];
      const std::vector<glm::uvec4>* streams[4] = {&p.nodes, &p.triangles, &p.attributes, &p.vertices};
      const char* names[4] = {"u_nodes", "u_triangles", "u_attributes", "u_vertices"};
      glUseProgram(program);
      for (int unit = 0; unit < 4; ++unit) {
        textures[unit] = uploadBvhStream(*streams[unit], Storage::Tbo, names[unit], &buffers[unit]);
        glBindTextureUnit(GLuint(unit), textures[unit]);
        glUniform1i(glGetUniformLocation(program, names[unit]), unit);
      }
      const std::vector<glm::uvec4> out = test::dispatchCompute<glm::uvec4>(
          program, std::vector<glm::vec4>(1), 5 * count, count, "triangle accessors");
      glDeleteTextures(4, textures);
      glDeleteBuffers(4, buffers);
      glDeleteProgram(program);
      const glsl::Storage s(p);
      int failures = 0;
      for (size_t j = 0; j < count && failures < 3; ++j) {
        glm::vec3 v[3], n;
        glm::vec2 uv;
        uint32_t ids[3];
        glsl::loadTriangle(s, int(j), v[0], v[1], v[2]);
        glsl::loadTriangleIds(s, int(j), ids[0], ids[1], ids[2]);
        glsl::loadAttributes(s, int(j), glm::vec2(0.2f, 0.3f), n, uv);
        bool same = true;
        for (int k = 0; k < 3; ++k)
          same = same && glm::uvec4(glsl::floatBitsToUint(v[k]), ids[k]) == out[5 * j + size_t(k)];
        const glm::vec3 gn = glsl::uintBitsToFloat(glm::uvec3(out[5 * j + 3]));
        const glm::vec2 guv = glsl::uintBitsToFloat(glm::uvec2(out[5 * j + 4]));
        same = same && glm::all(glm::lessThanEqual(glm::abs(gn - n), glm::vec3(1e-6f))) &&
               glm::all(glm::lessThanEqual(glm::abs(guv - uv), glm::vec2(1e-6f * std::max(1.0f, glm::length(uv)))));
        if (!same) {
          ++failures;
          ADD_FAILURE() << "triangle " << j << ": GLSL normal " << gn.x << " " << gn.y << " " << gn.z << " uv " << guv.x
                        << " " << guv.y << "; mirror " << n.x << " " << n.y << " " << n.z << " uv " << uv.x << " " << uv.y;
        }
      }
    }
}

// The command line: `layouts` lists the formats; a format that cannot run the robustness variant, or an
// unknown one, is refused before the input is read; build reports the format and its bytes.
TEST(TriangleFormatCli, ListsRefusesAndReports) {
  using clitest::run;
  clitest::Result r = run("layouts");
  ASSERT_EQ(r.code, 0) << r.err;
  for (const TriangleFormatInfo& f : triangleFormats()) EXPECT_NE(r.out.find(f.name), std::string::npos) << r.out;
  r = run("render /no/such/mesh.off --triangles precomputed");
  EXPECT_EQ(r.code, 2);  // a usage error
  EXPECT_NE(r.err.find("--robust fast, box, ulp or box+ulp"), std::string::npos) << r.err;
  r = run("trace /no/such/mesh.off --triangles strips");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("valid formats: raw precomputed indexed"), std::string::npos) << r.err;
  r = run("build --mesh /no/such/mesh.off --triangles strips");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("valid formats"), std::string::npos) << r.err;

  // A tetrahedron: 4 triangles, 4 welded vertices (flat corners: the OFF has no normals).
  const std::filesystem::path mesh = clitest::writeTemp("tetra.off", "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
                                                        "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
  nlohmann::json raw, idx;
  for (auto [format, out] : {std::pair{"raw", &raw}, std::pair{"indexed", &idx}}) {
    r = run("build --mesh " + mesh.string() + " --leaf-size 1 --triangles " + format + " --json");
    ASSERT_EQ(r.code, 0) << r.err;
    *out = nlohmann::json::parse(r.out);
    EXPECT_EQ((*out)["triangle_format"], format);
    EXPECT_DOUBLE_EQ((*out)["bytes_per_triangle"].get<double>(), (*out)["bytes"].get<double>() / 4.0);
  }
  EXPECT_EQ(idx["vertices"], 4);
  EXPECT_EQ(raw["bytes"].get<int>() - idx["bytes"].get<int>(), 4 * 112 - (4 * 16 + 4 * 16 + 2 * 16));
  r = run("render " + mesh.string() + " --triangles indexed --leaf-size 1 --width 32 --height 18 --frames 1 --warmup 0 --json");
  if (r.code == 0) {  // needs a GL context
    const nlohmann::json j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["triangle_format"], "indexed");
    EXPECT_EQ(j["bytes"], idx["bytes"]);
  }
}

}  // namespace
}  // namespace bvhlab
