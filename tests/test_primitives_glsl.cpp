// The GLSL of the analytic ray-primitive intersections (shaders/prim_*.glsl): it compiles with
// glslangValidator, reads statement by statement like its C++ mirror (shaders/primitives.hpp), and, run on
// the GL device (a compute shader; llvmpipe here), passes the mirror's random property test against the
// double-precision reference (tests/primitives_test_util.hpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include <glm/glm.hpp>

#include <glad/gl.h>

#include "gl_compute.hpp"
#include "primitives_test_util.hpp"
#include "render/gl_context.hpp"
#include "require.hpp"

namespace {

using namespace bvhlab::primtest;
using bvhlab::test::compileCompute;
using bvhlab::test::dispatchCompute;

std::string readText(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

const char* const kPrimitiveModules[] = {"prim_sphere.glsl", "prim_box.glsl", "prim_cylinder.glsl",
                                         "prim_cone.glsl",   "prim_torus.glsl", "prim_plane.glsl"};

// common.glsl + every prim_*.glsl, without #version.
std::string primitiveSources() {
  const std::filesystem::path shaders = std::filesystem::path(BVHLAB_SOURCE_DIR) / "shaders";
  std::string source = readText(shaders / "common.glsl");
  for (const char* name : kPrimitiveModules) {
    if (!std::filesystem::exists(shaders / name)) throw std::runtime_error(std::string("missing ") + name);
    source += '\n';
    source += readText(shaders / name);
  }
  return source;
}

TEST(Glsl, PrimitivesCompileWithGlslang) {
  if (std::system("glslangValidator --version > /dev/null 2>&1") != 0)
    BVHLAB_SKIP_OR_FAIL("glslangValidator is not on PATH (Debian: glslang-tools); GLSL not validated");
  namespace fs = std::filesystem;
  std::string source = "#version 450 core\n" + primitiveSources();
  source += R"(
layout(location = 0) out vec4 fragColor;
void main() {
  Ray ray = Ray(vec3(gl_FragCoord.xy * 0.01 - 1.0, 3.0), vec3(0.0, 0.0, -1.0));
  float t;
  vec3 n;
  vec2 uv;
  vec4 sum = vec4(0.0);
  if (intersectSphere(ray, 0.0, INF, t, n, uv)) sum += vec4(n, t) + uv.xyxy;
  if (intersectBox(ray, 0.0, INF, t, n, uv)) sum += vec4(n, t) + uv.xyxy;
  if (intersectCylinder(ray, 0.0, INF, t, n, uv)) sum += vec4(n, t) + uv.xyxy;
  if (intersectCone(ray, 0.0, INF, t, n, uv)) sum += vec4(n, t) + uv.xyxy;
  if (intersectTorus(ray, vec2(1.0, 0.25), 0.0, INF, t, n, uv)) sum += vec4(n, t) + uv.xyxy;
  if (intersectPlane(ray, false, 0.0, INF, t, n, uv)) sum += vec4(n, t) + uv.xyxy;
  if (intersectPlane(ray, true, 0.0, INF, t, n, uv)) sum += vec4(n, t) + uv.xyxy;
  fragColor = sum;
}
)";
  const fs::path dir = fs::temp_directory_path() / ("bvhlab_prims_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path file = dir / "primitives.frag", log = dir / "glslang.log";
  std::ofstream(file) << source;
  const std::string command = "glslangValidator -S frag \"" + file.string() + "\" > \"" + log.string() + "\" 2>&1";
  const int rc = std::system(command.c_str());
  EXPECT_EQ(rc, 0) << readText(log);
  fs::remove_all(dir);
}

// The mirror reads like the GLSL: with comments dropped and the purely syntactic differences normalised
// (float suffixes, `inline`/`constexpr`, out parameters as references, swizzles as constructors, array
// initialisers), primitives.hpp holds the prim_*.glsl statements in the same order.
TEST(Glsl, MirrorMatchesTheGlslStatementByStatement) {
  const std::filesystem::path shaders = std::filesystem::path(BVHLAB_SOURCE_DIR) / "shaders";
  auto normalise = [](std::string line) {
    line = std::regex_replace(line, std::regex("//.*"), "");
    line = std::regex_replace(line, std::regex("(\\d)f\\b"), "$1");
    line = std::regex_replace(line, std::regex("\\binline "), "");
    line = std::regex_replace(line, std::regex("\\bconstexpr "), "const ");
    line = std::regex_replace(line, std::regex("(float|vec2|vec3)& (\\w+)"), "out $1 $2");
    line = std::regex_replace(line, std::regex("([\\w.]+)\\.xz\\b"), "vec2($1.x, $1.z)");
    line = std::regex_replace(line, std::regex("float\\[4\\]\\((.*)\\);"), "{$1};");
    line = std::regex_replace(line, std::regex("^\\s+|\\s+$"), "");
    return line;
  };
  auto statements = [&](const std::string& text, const std::string& from) {
    std::vector<std::string> out;
    std::istringstream in(text);
    bool started = from.empty();
    for (std::string line; std::getline(in, line);) {
      if (line.find("// namespace") != std::string::npos) continue;
      line = normalise(line);
      if (!started && line.rfind(from, 0) == 0) started = true;
      if (started && !line.empty()) out.push_back(line);
    }
    return out;
  };
  std::vector<std::string> glsl;
  for (const char* name : kPrimitiveModules) {
    std::vector<std::string> module = statements(readText(shaders / name), "");
    glsl.insert(glsl.end(), module.begin(), module.end());
  }
  std::vector<std::string> cpp = statements(readText(shaders / "primitives.hpp"), "bool intersectSphere(");
  ASSERT_GT(glsl.size(), 300u);
  for (size_t i = 0; i < std::min(glsl.size(), cpp.size()); ++i)
    ASSERT_EQ(cpp[i], glsl[i]) << "statement " << i << " differs (GLSL first, then the mirror)";
  EXPECT_EQ(cpp.size(), glsl.size());
}

// One compute-shader invocation per ray: in, 3 vec4 (origin + tMin, dir + tMax, kind + radii + infinite);
// out, 2 vec4 (hit + t + uv, normal).
const char* const kCrossCheckMain = R"(
layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer RayBuffer { vec4 rays[]; };
layout(std430, binding = 1) writeonly buffer HitBuffer { vec4 hits[]; };
uniform int u_count;
void main() {
  int i = int(gl_GlobalInvocationID.x);
  if (i >= u_count) return;
  vec4 a = rays[3 * i];
  vec4 b = rays[3 * i + 1];
  vec4 c = rays[3 * i + 2];
  Ray ray = Ray(a.xyz, b.xyz);
  float t = 0.0;
  vec3 n = vec3(0.0);
  vec2 uv = vec2(0.0);
  bool hit = false;
  int kind = int(c.x);
  if (kind == 0) hit = intersectSphere(ray, a.w, b.w, t, n, uv);
  if (kind == 1) hit = intersectBox(ray, a.w, b.w, t, n, uv);
  if (kind == 2) hit = intersectCylinder(ray, a.w, b.w, t, n, uv);
  if (kind == 3) hit = intersectCone(ray, a.w, b.w, t, n, uv);
  if (kind == 4) hit = intersectTorus(ray, c.yz, a.w, b.w, t, n, uv);
  if (kind == 5) hit = intersectPlane(ray, c.w > 0.5, a.w, b.w, t, n, uv);
  hits[2 * i] = vec4(hit ? 1.0 : 0.0, t, uv);
  hits[2 * i + 1] = vec4(n, 0.0);
}
)";


// Runs the GLSL functions on the GPU for every case (shape per case) and returns their results.
std::vector<Hit> traceOnGpu(const std::vector<Shape>& shapes, const std::vector<Case>& cases) {
  static const GLuint program = compileCompute("#version 450 core\n" + primitiveSources() + kCrossCheckMain);
  std::vector<glm::vec4> in;
  for (size_t i = 0; i < cases.size(); ++i) {
    const Case& c = cases[i];
    const Shape& s = shapes[i];
    const int kind = s.kind == Kind::InfinitePlane ? 5 : int(s.kind);
    in.emplace_back(c.ray.origin, c.tMin);
    in.emplace_back(c.ray.dir, c.tMax);
    in.emplace_back(float(kind), s.radii.x, s.radii.y, s.kind == Kind::InfinitePlane ? 1.0f : 0.0f);
  }
  const std::vector<glm::vec4> out =
      dispatchCompute<glm::vec4>(program, in, cases.size() * 2, cases.size(), "primitive cross-check dispatch");
  std::vector<Hit> hits(cases.size());
  for (size_t i = 0; i < cases.size(); ++i) {
    hits[i].hit = out[2 * i].x > 0.5f;
    hits[i].t = out[2 * i].y;
    hits[i].uv = vec2(out[2 * i].z, out[2 * i].w);
    hits[i].normal = vec3(out[2 * i + 1]);
  }
  return hits;
}

// The GLSL, compiled by the driver and run on its hardware, passes the random property test of the mirror
// and agrees with the mirror on nearly every ray. OSMesa (llvmpipe) by default; BVHLAB_GL_BACKEND=egl runs
// it through EGL (the NVIDIA driver on a GPU machine).
TEST(Glsl, GpuResultsPassThePropertyTest) {
  std::unique_ptr<bvhlab::GlContext> context;
  try {
    const char* backend = std::getenv("BVHLAB_GL_BACKEND");
    context = bvhlab::createContext(backend && *backend ? bvhlab::parseBackend(backend) : bvhlab::Backend::OSMesa);
  } catch (const std::exception& e) {
    BVHLAB_SKIP_OR_FAIL("no OpenGL 4.5 context (" << e.what() << "): GLSL not run");
  }
  std::vector<Shape> shapes;
  std::vector<Case> cases;
  uint32_t seed = 1000;
  for (Kind kind : {Kind::Sphere, Kind::Box, Kind::Cylinder, Kind::Cone, Kind::Torus, Kind::Plane,
                    Kind::InfinitePlane}) {
    for (const Shape& shape : randomShapes(kind)) {
      for (const RandomConfig& config : kRandomConfigs) {
        for (const Case& c : randomCases(shape, config, 500, seed++)) {
          shapes.push_back(shape);
          cases.push_back(c);
        }
      }
    }
  }
  std::vector<Hit> gpu = traceOnGpu(shapes, cases);
  Stats stats;
  int failures = 0, sameHit = 0, sameT = 0;
  double maxUvDiff = 0.0;
  for (size_t i = 0; i < cases.size(); ++i) {
    const Case& c = cases[i];
    std::string failure = checkHit(shapes[i], c.ray, c.tMin, c.tMax, gpu[i], stats);
    if (!failure.empty() && ++failures <= 10) ADD_FAILURE() << "GLSL: " << failure;
    Hit cpu = trace(shapes[i], c.ray, c.tMin, c.tMax);
    if (cpu.hit != gpu[i].hit) continue;
    ++sameHit;
    if (!cpu.hit) continue;
    if (cpu.t == gpu[i].t) ++sameT;
    // uv: compared where both found the same point of the same face near the object (from far away the
    // float hit points themselves differ by ~eps |o|), away from the sphere's poles where u is singular.
    const double S = shapes[i].boundingRadius();
    const bool samePoint = std::abs(double(cpu.t) - double(gpu[i].t)) * length(dvec3(c.ray.dir)) <= 1e-6 * S;
    const double sameFace = dot(normalize(dvec3(cpu.normal)), normalize(dvec3(gpu[i].normal)));
    const bool pole = shapes[i].kind == Kind::Sphere && std::abs(normalize(cpu.normal).y) > 0.999f;
    if (samePoint && sameFace > 0.9999 && length(dvec3(c.ray.origin)) <= 10.0 * S && !pole) {
      for (int k = 0; k < 2; ++k) {  // the seams (u = 0 ~ 1, and the torus's v) may land either side
        double du = std::abs(double(cpu.uv[k]) - double(gpu[i].uv[k]));
        maxUvDiff = std::max(maxUvDiff, std::min(du, 1.0 - du));
      }
    }
  }
  std::printf("GLSL on %s: %zu rays, %d hits, %d grazing; same hit/miss as the mirror on %d, bit-identical t on "
              "%d of the hits; max position err %.2f, normal err %.2f (eps*L/cos); max uv difference %.2g\n",
              context->renderer().c_str(), cases.size(), stats.hits, stats.graze, sameHit, sameT,
              stats.maxPosition, stats.maxNormal, maxUvDiff);
  EXPECT_EQ(failures, 0);
  EXPECT_GE(sameHit, int(cases.size()) - int(cases.size()) / 200);  // disagreements only on grazing rays
  // GLSL's atan is an approximation, the mirror's is libm's: measured 1e-5 on llvmpipe.
  EXPECT_LE(maxUvDiff, 1e-4);
}

}  // namespace
