// The GLSL traversal kernels compiled by the driver and run on its device (OSMesa's llvmpipe here,
// BVHLAB_GL_BACKEND=egl on a GPU), against their C++ mirrors ray by ray: hits, triangles and
// counters. Labelled "gl" (tests/CMakeLists.txt); the mirrors' own checks are test_traversal.cpp.
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
#include "gl_compute.hpp"
#include "builders/builder.hpp"
#include "datasets/mesh_io.hpp"
#include "layout/layout.hpp"
#include "render/gl_context.hpp"
#include "render/gpu_renderer.hpp"
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

// ---- the GLSL on a GL device, against the mirror ------------------------------------------------

// One compute invocation per ray: closest hit, then any hit, with the counters of each.
// in: 2 vec4 per ray (origin, tMin), (dir, tMax); out: 3 uvec4 per ray.
const char* const kCrossCheckMain = R"(
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
  uvec4 closestCounts = uvec4(g_nodeVisits, g_triTests, g_stackOverflow ? 1u : 0u, 0u);
  g_nodeVisits = 0u;
  g_triTests = 0u;
  g_stackOverflow = false;
  bool any = traceAny(ray, tMin, tMax);
  results[3 * i + 0] = uvec4(closest ? 1u : 0u, uint(hit.tri), floatBitsToUint(hit.t), any ? 1u : 0u);
  results[3 * i + 1] = closestCounts;
  results[3 * i + 2] = uvec4(g_nodeVisits, g_triTests, g_stackOverflow ? 1u : 0u, 0u);
}
)";


// The three streams in one storage kind: textures bound to units 0..2, or (ssbo) buffers bound to
// shader storage bindings kFirstStreamBinding.. (traversal/storage_ssbo.glsl).
struct GlStreams {
  std::vector<GLuint> buffers, textures;

  GlStreams(const PackedBvh& p, Storage storage) {
    const std::vector<glm::uvec4>* streams[3] = {&p.nodes, &p.triangles, &p.attributes};
    for (GLuint unit = 0; unit < 3; ++unit) {
      const std::vector<glm::uvec4>& texels = *streams[unit];
      GLuint tex = 0;
      if (storage == Storage::Tex2D) {
        const GLsizei w = GLsizei(kTex2DWidth), h = GLsizei((texels.size() + kTex2DWidth - 1) / kTex2DWidth);
        std::vector<glm::uvec4> padded(size_t(w) * size_t(h), glm::uvec4(0));
        std::copy(texels.begin(), texels.end(), padded.begin());
        glCreateTextures(GL_TEXTURE_2D, 1, &tex);
        glTextureStorage2D(tex, 1, GL_RGBA32UI, w, h);
        glTextureSubImage2D(tex, 0, 0, 0, w, h, GL_RGBA_INTEGER, GL_UNSIGNED_INT, padded.data());
        glTextureParameteri(tex, GL_TEXTURE_MIN_FILTER, GL_NEAREST);  // integer textures: no filtering
        glTextureParameteri(tex, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
      } else {
        GLuint buf = 0;
        glCreateBuffers(1, &buf);
        glNamedBufferData(buf, GLsizeiptr(texels.size() * sizeof(glm::uvec4)), texels.data(), GL_STATIC_DRAW);
        buffers.push_back(buf);
        if (storage == Storage::Ssbo) {
          glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kFirstStreamBinding + unit, buf);
          continue;
        }
        glCreateTextures(GL_TEXTURE_BUFFER, 1, &tex);
        glTextureBuffer(tex, GL_RGBA32UI, buf);
      }
      glBindTextureUnit(unit, tex);
      textures.push_back(tex);
    }
    checkGl("uploading the BVH streams");
  }
  ~GlStreams() {
    glDeleteTextures(GLsizei(textures.size()), textures.data());
    glDeleteBuffers(GLsizei(buffers.size()), buffers.data());
  }
};

struct GpuRun {
  bool closestFound, anyFound;
  int tri;
  float t;
  Counters closest, any;
};

// The kernel over one storage kind, compiled once per (kernel, storage, stack size): llvmpipe
// compiles a kernel in ~0.5 s without its disk cache.
GLuint crossCheckProgram(const KernelInfo& kernel, Storage storage, int stackSize) {
  static std::map<std::string, GLuint> programs;
  const std::string key = kernel.name + "/" + storageName(storage) + "/" + std::to_string(stackSize);
  if (auto it = programs.find(key); it != programs.end()) return it->second;
  std::string source = "#version 450 core\n#define BVH_STACK_SIZE " + std::to_string(stackSize) + "\n";
  for (const std::string& module : {std::string("common.glsl"), std::string(storageModule(storage)),
                                    std::string("layout.glsl"), std::string("ray_box.glsl"),
                                    std::string("ray_triangle.glsl"), std::string("triangles_raw.glsl"),
                                    kernel.glslFile})
    source += glslModule(module);
  return programs[key] = compileCompute(source + kCrossCheckMain);
}

std::vector<GpuRun> traceOnGl(const KernelInfo& kernel, Storage storage, const PackedBvh& packed, int stackSize,
                              const std::vector<RayQuery>& rays) {
  const GLuint program = crossCheckProgram(kernel, storage, stackSize);
  const GlStreams streams(packed, storage);
  std::vector<glm::vec4> in;
  for (const RayQuery& q : rays) {
    in.emplace_back(q.ray.origin, q.tMin);
    in.emplace_back(q.ray.dir, q.tMax);
  }
  GLuint io[2];
  glCreateBuffers(2, io);
  glNamedBufferData(io[0], GLsizeiptr(in.size() * sizeof(glm::vec4)), in.data(), GL_STATIC_DRAW);
  glNamedBufferData(io[1], GLsizeiptr(rays.size() * 3 * sizeof(glm::uvec4)), nullptr, GL_STATIC_READ);
  glUseProgram(program);
  glUniform1i(glGetUniformLocation(program, "u_count"), GLint(rays.size()));
  const char* names[3] = {"u_nodes", "u_triangles", "u_attributes"};
  for (int unit = 0; unit < 3; ++unit) glUniform1i(glGetUniformLocation(program, names[unit]), unit);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, io[0]);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, io[1]);
  glDispatchCompute(GLuint((rays.size() + 63) / 64), 1, 1);
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  std::vector<glm::uvec4> out(rays.size() * 3);
  glGetNamedBufferSubData(io[1], 0, GLsizeiptr(out.size() * sizeof(glm::uvec4)), out.data());
  checkGl("traversal cross-check dispatch");
  glDeleteBuffers(2, io);
  std::vector<GpuRun> runs(rays.size());
  for (size_t i = 0; i < rays.size(); ++i) {
    const glm::uvec4 a = out[3 * i], b = out[3 * i + 1], c = out[3 * i + 2];
    runs[i].closestFound = a.x != 0;
    runs[i].tri = int(a.y);
    runs[i].t = std::bit_cast<float>(a.z);
    runs[i].anyFound = a.w != 0;
    runs[i].closest = Counters{b.x, b.y, 0, b.z != 0};
    runs[i].any = Counters{c.x, c.y, 0, c.z != 0};
  }
  return runs;
}

// The GLSL kernels, compiled by the driver and run on its device, give the mirror's hits and
// counters. OSMesa (llvmpipe) by default; BVHLAB_GL_BACKEND=egl runs them through EGL (the NVIDIA
// driver on a GPU machine), where fused multiply-adds may move a few grazing hits.
TEST(TraversalGlsl, GpuAgreesWithTheMirror) {
  std::unique_ptr<GlContext> context;
  try {
    const char* backend = std::getenv("BVHLAB_GL_BACKEND");
    context = createContext(backend && *backend ? parseBackend(backend) : Backend::OSMesa);
  } catch (const std::exception& e) {
    BVHLAB_SKIP_OR_FAIL("no OpenGL 4.5 context (" << e.what() << "): GLSL not run");
  }
  struct SceneRays {
    std::string name;
    TriangleSoup soup;
    std::vector<RayQuery> rays;
  };
  std::vector<SceneRays> scenes;
  {
    SceneRays sphere{"sphere", soupOf({sphereMesh(16, 32, 1.0f)}), {}};
    sphere.rays = mixedRays(sphere.soup, 500, 11);
    scenes.push_back(std::move(sphere));
    SceneRays grid{"grid", soupOf({gridMesh(12)}), {}};
    grid.rays = mixedRays(grid.soup, 300, 12);
    for (int i = 0; i <= 12; ++i)
      for (int j = 0; j <= 12; ++j)
        grid.rays.push_back({{glm::vec3(-1.0f + float(i) / 6.0f, 1.0f, -1.0f + float(j) / 6.0f), glm::vec3(0, -1, 0)}, 0.0f, glsl::INF});
    scenes.push_back(std::move(grid));
  }
  // One stack size for every tree (the deepest one's), so each kernel compiles once per storage.
  std::vector<std::vector<Tree>> trees;
  uint32_t maxDepth = 1;
  for (const SceneRays& scene : scenes) {
    const std::vector<Aabb> boxes = triangleBoxes(scene.soup);
    const std::vector<glm::vec3> centroids = triangleCentroids(scene.soup);
    trees.push_back({{"sah-binned", packBvh(buildBvh("sah-binned", BuildInput{boxes, centroids}, BuildOptions{}), scene.soup)},
                     {"test-chain", packBvh(chainBvh(boxes), scene.soup)}});
    for (const Tree& tree : trees.back()) maxDepth = std::max(maxDepth, tree.packed.depth);
  }
  const int stackSize = stackSizeFor(maxDepth);
  size_t compared = 0, identical = 0, diffT = 0;
  double maxRelativeT = 0.0;
  for (size_t s = 0; s < scenes.size(); ++s) {
    const SceneRays& scene = scenes[s];
    for (const Tree& tree : trees[s])
      for (const KernelInfo& k : kernels())
        for (Storage storage : {Storage::Tbo, Storage::Tex2D, Storage::Ssbo}) {
          SCOPED_TRACE(scene.name + " / " + tree.name + " / " + k.name + " / " + storageName(storage));
          const std::vector<GpuRun> gpu = traceOnGl(k, storage, tree.packed, stackSize, scene.rays);
          int failures = 0;
          for (size_t i = 0; i < scene.rays.size(); ++i) {
            const KernelRun cpu = runKernel(k, glsl::Storage(tree.packed, stackSize), scene.rays[i]);
            const GpuRun& g = gpu[i];
            ++compared;
            // Hits, triangles and counters must be identical. t may differ in its last bits: the driver
            // evaluates dot and cross in its own order (llvmpipe: up to 3 ulp on ~6% of hits here).
            const double relativeT = g.t == cpu.hit.t ? 0.0  // also both tMax = inf on a miss
                                     : std::abs(double(g.t) - double(cpu.hit.t)) / std::abs(double(cpu.hit.t));
            const bool same = g.closestFound == cpu.closestFound && g.anyFound == cpu.anyFound && g.tri == cpu.hit.tri &&
                              relativeT <= 1e-6 && g.closest.nodeVisits == cpu.closest.nodeVisits &&
                              g.closest.triTests == cpu.closest.triTests && g.any.nodeVisits == cpu.any.nodeVisits &&
                              g.any.triTests == cpu.any.triTests && !g.closest.stackOverflow && !g.any.stackOverflow;
            identical += same;
            diffT += g.t != cpu.hit.t;
            maxRelativeT = std::max(maxRelativeT, relativeT);
            if (!same && ++failures <= 3)
              ADD_FAILURE() << "GLSL: found " << g.closestFound << "/" << g.anyFound << " tri " << g.tri << " t " << g.t
                            << " visits " << g.closest.nodeVisits << "/" << g.any.nodeVisits << " tests " << g.closest.triTests
                            << "/" << g.any.triTests << "; mirror: found " << cpu.closestFound << "/" << cpu.anyFound << " tri "
                            << cpu.hit.tri << " t " << cpu.hit.t << " visits " << cpu.closest.nodeVisits << "/"
                            << cpu.any.nodeVisits << " tests " << cpu.closest.triTests << "/" << cpu.any.triTests << "; "
                            << describe(scene.rays[i]);
          }
        }
  }
  std::printf("GLSL vs mirror on %s: %zu of %zu ray queries agree; t differs in %zu (max relative %.2g)\n",
              context->renderer().c_str(), identical, compared, diffT, maxRelativeT);
  EXPECT_EQ(identical, compared);
}

}  // namespace
}  // namespace bvhlab
