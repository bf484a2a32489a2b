// The robustness variants through the real GLSL, one by one (traversal/robustness.hpp):
//  - a camera inside closed tessellated meshes (unit scale, far away, tiny, huge; and from the cube's
//    exact centre with pixel centres on its edges) must see the mesh in EVERY pixel whenever the
//    variant has both the watertight triangle test and Ize's box test; the other variants' leak counts
//    are measured and printed, not hidden. Hit ids match the C++ mirror's;
//  - every variant's GLSL renders a small scene with mesh reflection and refraction like its mirror;
//  - the watertight test's double-precision fallback decides rays whose float edge function rounds to 0
//    (GLSL and mirror), on cases where dropping the fallback would give a wrong hit.
#include <cmath>
#include <iostream>
#include <random>

#include <glad/gl.h>
#include <glm/gtc/matrix_transform.hpp>

#include "datasets/hard_cases.hpp"
#include "datasets/random_draws.hpp"
#include "layout/layouts.hpp"
#include "render/hard_cases_command.hpp"
#include "gl_compute.hpp"
#include "render_fixture.hpp"
#include "shaders/assemble.hpp"
#include "traversal/ray_triangle_watertight.hpp"

namespace bvhlab::test {
namespace {

// The same inside views with every other layout's trees and kernels (the layouts' own packers and
// decoders: bvh2-cb's parent-held boxes, the wide slots, cwbvh's quantised boxes), watertight only.
TEST(RobustGpu, EveryLayoutsKernelNeverLeaksInsideClosedMeshesWhenWatertight) {
  glContext();
  for (const LayoutInfo& l : layouts()) {
    if (l.name == "v1") continue;  // the test below, with every v1 kernel and variant
    for (const KernelInfo& k : kernelsFor(l.name)) {  // every kernel of the layout
      size_t rays = 0;
      for (const InsideView& v : insideViews()) {
        const std::unique_ptr<PreparedScene> scene = prepareInsideView(v, "sah-binned", l.name);
        const GpuLeakCounts n = gpuLeaks(*scene, v.name, Robustness::Watertight, k.name);
        EXPECT_EQ(n.leaks, 0u) << v.name << " " << k.name;
        EXPECT_LE(n.mirrorIdMismatch, n.rays / 200) << v.name << " " << k.name;  // as below: FMA contraction
        rays += n.rays;
      }
      EXPECT_GT(rays, 0u);
    }
  }
}

TEST(RobustGpu, CameraInsideClosedMeshesNeverLeaksWithWatertightTrianglesAndBoxes) {
  glContext();
  std::vector<std::pair<std::string, std::unique_ptr<PreparedScene>>> views;
  for (const InsideView& v : insideViews()) views.emplace_back(v.name, prepareInsideView(v, "sah-binned"));
  for (const KernelInfo& k : kernels()) {
    for (Robustness r : robustnessVariants()) {
      if (r.offset == OriginOffset::Ulp) continue;  // the primid view spawns no secondary ray
      const bool watertight = r.triangle == TriangleTest::Watertight && r.box == BoxTest::Robust;
      size_t leaks = 0, rays = 0, mismatch = 0;
      for (const auto& [name, scene] : views) {
        const GpuLeakCounts n = gpuLeaks(*scene, name, r, k.name);
        if (watertight) {
          EXPECT_EQ(n.leaks, 0u) << name << " " << k.name << " " << robustnessName(r);
        }
        // The mirror rounds like the GLSL except where llvmpipe contracts to FMA: allow a handful of
        // pixels on an edge to pick the neighbouring triangle (or, without the watertight pair, to leak
        // on one side and not the other).
        EXPECT_LE(n.mirrorIdMismatch, n.rays / 200) << name << " " << k.name << " " << robustnessName(r);
        leaks += n.leaks;
        rays += n.rays;
        mismatch += n.mirrorIdMismatch;
      }
      std::cout << "[ leaks    ] " << k.name << " " << robustnessName(r) << ": " << leaks << " of " << rays
                << " rays leak; " << mismatch << " hit ids differ from the mirror\n";
    }
  }
}

// A mirror-finish tessellated sphere and a glass tessellated cube over an analytic ground plane, lit by
// a point light: reflection, refraction in and out of a closed mesh, and shadow rays, so every knob
// (and both origin offsets) is on the path of some pixel. The cube floats 0.1 above the ground: a face
// coplanar with the plane would z-fight, which is no robustness question.
std::unique_ptr<PreparedScene> secondaryRayScene() {
  Scene s;
  s.materials.resize(3);
  s.materials[0].color = glm::vec3(0.7f);
  s.materials[1].color = glm::vec3(0.9f);
  s.materials[1].reflectivity = 0.8f;
  s.materials[2].color = glm::vec3(0.95f);
  s.materials[2].transparency = 0.9f;
  s.materials[2].ior = 1.5f;
  Object ground;
  ground.kind = ObjectKind::Plane;
  ground.transform = glm::scale(glm::mat4(1.0f), glm::vec3(6.0f));
  s.objects.push_back(ground);
  const hard::HardCase sphere = hard::transformed(hard::closedSphere(32, 16), glm::vec3(-0.9f, 1.0f, 0.0f), 1.0f);
  const hard::HardCase cube = hard::transformed(hard::closedCube(4), glm::vec3(1.0f, 0.7f, 0.8f), 0.6f);
  int material = 1;
  for (const hard::HardCase* c : {&sphere, &cube}) {
    Mesh m;
    m.name = c->name;
    m.positions = c->positions;
    m.triangles = c->triangles;
    m.material = material;
    Object o;
    o.kind = ObjectKind::Mesh;
    o.mesh = int(s.meshes.size());
    o.material = material++;
    s.meshes.push_back(std::move(m));
    s.objects.push_back(o);
  }
  Light light;
  light.position = glm::vec3(3.0f, 6.0f, 4.0f);
  s.lights.push_back(light);
  s.camera.eye = glm::vec3(0.0f, 2.0f, 6.0f);
  s.camera.target = glm::vec3(0.0f, 0.8f, 0.0f);
  s.camera.fovDeg = 40.0f;
  s.settings.maxDepth = 5;
  return prepareScene(std::move(s), "sah-binned", BuildOptions{});
}

TEST(RobustGpu, EveryVariantMatchesItsMirrorWithSecondaryRays) {
  auto p = secondaryRayScene();
  FrameOptions f = smallFrame(p->scene, 160, 90);
  std::vector<uint8_t> fastImage;
  for (Robustness r : robustnessVariants()) {
    ShaderOptions o;
    o.maxDepth = p->scene.settings.maxDepth;
    o.bvhStackSize = stackSizeFor(p->packed.depth);
    o.robust = r;
    const Rendered gpu = renderGpu(*p, o, f);
    const ReferenceImage cpu = renderReference(p->scene, p->data, p->packed, o, f);
    const ImageDiff d = compareRgba(gpu.rgba, cpu.rgba);
    // Measured (llvmpipe, 160x90): the GLSL image equals the mirror's in every variant (mean 0, max 0).
    // Bounds as test_hard_scenes' for its unit-scale scenes: a rounding difference here and there passes,
    // a mirror or kernel that is wrong anywhere visible does not.
    EXPECT_LE(d.meanAbs, 0.002) << robustnessName(r);
    EXPECT_LE(d.maxDiff, 3) << robustnessName(r);
    if (r == Robustness::Fast) fastImage = gpu.rgba;
    std::cout << "[ mirror   ] " << robustnessName(r) << ": mean |GLSL - mirror| " << d.meanAbs << ", within 3: "
              << d.within3 << "; mean |variant - fast| " << compareRgba(gpu.rgba, fastImage).meanAbs << "\n";
  }
}

// ---- the watertight test's double fallback (Woop et al. 2013, section 3.4) ------------------------

struct FallbackCase {
  glm::vec3 v0, v1, v2;
  bool exactHit;  // the exact answer: the signs of the edge functions in exact arithmetic
};

// Rays along +z from the origin: the ray frame is the identity (kz = 2, shear 0), so the edge functions
// are 2D cross products of the vertices' x, y. v1 and v2 lie on opposite sides of the origin on a line
// through it (v2 = -s v1), then v2.x moves by a few ulps: the exact edge function of (v1, v2) is a tiny
// non-zero number, and the float one is 0 whenever both products round to the same float. v0 is off
// that line, so the other two edge functions have one clear sign: the ray hits iff the tiny one agrees.
// Only cases whose float edge function is exactly 0 are kept; the vertex order is rotated so the zero
// falls on each of the three edge functions.
std::vector<FallbackCase> fallbackCases() {
  std::mt19937 rng(20130821u);
  std::uniform_real_distribution<float> coord(0.5f, 2.0f), scale(0.5f, 2.0f), off(0.3f, 1.5f);
  std::uniform_int_distribution<int> ulps(-3, 3);
  std::vector<FallbackCase> out;
  for (int trial = 0; trial < 200000 && out.size() < 600; ++trial) {
    const glm::vec2 b = draw2<glm::vec2>(coord, rng);
    glm::vec2 c = -scale(rng) * b;
    const int k = ulps(rng);
    if (k == 0) continue;
    for (int i = 0; i < std::abs(k); ++i) c.x = std::nextafter(c.x, k > 0 ? INFINITY : -INFINITY);
    const float uFloat = c.x * b.y - c.y * b.x;  // the kernel's u for (v0, v1, v2) = (a, b, c)
    // Products of two floats are exact in double (48 significant bits), and the difference of two such
    // products keeps its sign: exact sign, as the fallback's argument says.
    const double uExact = double(c.x) * double(b.y) - double(c.y) * double(b.x);
    if (uFloat != 0.0f || uExact == 0.0) continue;
    const glm::vec2 perp = glm::normalize(glm::vec2(-b.y, b.x)) * off(rng) * (trial % 2 ? 1.0f : -1.0f);
    const glm::vec2 a = 0.5f * (b + c) + perp;
    const double vExact = double(a.x) * double(c.y) - double(a.y) * double(c.x);
    const double wExact = double(b.x) * double(a.y) - double(b.y) * double(a.x);
    if (!((vExact > 0.0 && wExact > 0.0) || (vExact < 0.0 && wExact < 0.0))) continue;
    const bool hit = (uExact > 0.0) == (vExact > 0.0);
    const glm::vec3 A(a, 1.0f), B(b, 1.0f), C(c, 1.0f);
    switch (out.size() % 3) {  // the same triangle with the zero on u, w or v
      case 0: out.push_back({A, B, C, hit}); break;
      case 1: out.push_back({B, C, A, hit}); break;
      default: out.push_back({C, A, B, hit}); break;
    }
  }
  return out;
}

const char* const kFallbackMain = R"(
layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer TriBuffer { vec4 tris[]; };
layout(std430, binding = 1) writeonly buffer HitBuffer { uint hits[]; };
uniform int u_count;
void main() {
  int i = int(gl_GlobalInvocationID.x);
  if (i >= u_count) return;
  float t;
  vec2 bary;
  Ray ray = Ray(vec3(0.0), vec3(0.0, 0.0, 1.0));
  hits[i] = intersectTriangle(ray, tris[3 * i].xyz, tris[3 * i + 1].xyz, tris[3 * i + 2].xyz, 0.0, 10.0, t, bary)
                ? 1u : 0u;
}
)";

std::vector<bool> fallbackOnGpu(const std::vector<FallbackCase>& cases) {
  const std::string source = "#version 450 core\n" + glslModule("common.glsl") +
                             glslModule("ray_triangle_watertight.glsl") + kFallbackMain;
  const GLuint program = compileCompute(source);
  std::vector<glm::vec4> in;
  for (const FallbackCase& c : cases)
    for (glm::vec3 v : {c.v0, c.v1, c.v2}) in.emplace_back(v, 0.0f);
  const std::vector<GLuint> out = dispatchCompute<GLuint>(program, in, cases.size(), cases.size(), "fallback dispatch");
  glDeleteProgram(program);
  return std::vector<bool>(out.begin(), out.end());
}

TEST(RobustGpu, WatertightDoubleFallbackDecidesEdgeFunctionsThatRoundToZero) {
  glContext();
  const std::vector<FallbackCase> cases = fallbackCases();
  int misses = 0;
  for (const FallbackCase& c : cases) misses += !c.exactHit;
  // Every kept case has a float edge function of exactly 0, which the float-only test counts as "on the
  // edge" (inside): without the fallback every one of them would hit, so the exact misses are the cases
  // that fail if the fallback goes.
  ASSERT_GE(cases.size(), 300u);
  ASSERT_GE(misses, 50);
  ASSERT_GE(int(cases.size()) - misses, 50);
  const std::vector<bool> gpu = fallbackOnGpu(cases);
  int gpuWrong = 0, mirrorWrong = 0;
  for (size_t i = 0; i < cases.size(); ++i) {
    const FallbackCase& c = cases[i];
    float t;
    glm::vec2 bary;
    const bool mirror = glsl::watertight::intersectTriangle(glsl::Ray{glm::vec3(0.0f), glm::vec3(0.0f, 0.0f, 1.0f)},
                                                            c.v0, c.v1, c.v2, 0.0f, 10.0f, t, bary);
    mirrorWrong += mirror != c.exactHit;
    gpuWrong += gpu[i] != c.exactHit;
  }
  std::cout << "[ fallback ] " << cases.size() << " rays with a float edge function of 0 (" << misses
            << " exact misses): mirror wrong " << mirrorWrong << ", GLSL wrong " << gpuWrong << "\n";
  EXPECT_EQ(mirrorWrong, 0);
  EXPECT_EQ(gpuWrong, 0);
}

}  // namespace
}  // namespace bvhlab::test
