// Persistent threads in `bvhlab trace`'s compute path (traversal/kernels.hpp persistentThreadsOn): which
// kernels and GL implementations get them, and the llvmpipe fact that keeps them off there by default:
// one budget of 65,535 loop iterations per shader invocation, shared by all its loops.
#include <cstdlib>
#include <memory>
#include <optional>
#include <string>

#include <gtest/gtest.h>
#include <glad/gl.h>

#include "builders/builder.hpp"
#include "layout/layout.hpp"
#include "layout/layouts.hpp"
#include "render/gl_context.hpp"
#include "render/gpu_renderer.hpp"
#include "render/ray_tracer_gl.hpp"
#include "shaders/assemble.hpp"
#include "traversal/kernels.hpp"
#include "traversal_test_util.hpp"

namespace bvhlab {
namespace {

// Sets BVHLAB_PERSISTENT_THREADS for one scope (unset with nullptr), then puts the old value back.
class PersistentEnv {
 public:
  explicit PersistentEnv(const char* value) {
    if (const char* old = std::getenv(kName)) old_ = old;
    if (value)
      setenv(kName, value, 1);
    else
      unsetenv(kName);
  }
  ~PersistentEnv() {
    if (old_)
      setenv(kName, old_->c_str(), 1);
    else
      unsetenv(kName);
  }

 private:
  static constexpr const char* kName = "BVHLAB_PERSISTENT_THREADS";
  std::optional<std::string> old_;
};

TEST(PersistentThreads, OnForTheirKernelOffLlvmpipeUnlessAsked) {
  const KernelInfo& aila = findKernel("bvh2-cb", "bvh2cb-aila-laine");
  const KernelInfo& stack = findKernel("bvh2-cb", "bvh2cb-stack-ordered");
  const std::string gpu = "NVIDIA H200/PCIe/SSE2", cpu = "llvmpipe (LLVM 15.0.6, 256 bits)";
  {
    PersistentEnv env(nullptr);
    EXPECT_TRUE(persistentThreadsOn(aila, gpu));
    EXPECT_FALSE(persistentThreadsOn(aila, cpu));
    EXPECT_FALSE(persistentThreadsOn(stack, gpu));  // not designed for them
  }
  {
    PersistentEnv env("1");
    EXPECT_TRUE(persistentThreadsOn(aila, cpu));
    EXPECT_FALSE(persistentThreadsOn(stack, cpu));
  }
  {
    PersistentEnv env("0");
    EXPECT_FALSE(persistentThreadsOn(aila, gpu));
  }
}

class PersistentThreadsGl : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { context_ = createContext(Backend::OSMesa); }
  static void TearDownTestSuite() { context_.reset(); }
  static std::unique_ptr<GlContext> context_;
};
std::unique_ptr<GlContext> PersistentThreadsGl::context_;

// One invocation runs two loops of 40,000 iterations each and counts the iterations it ran. A GL
// implementation runs all 80,000; llvmpipe stops every loop once the invocation has run 65,535 back
// edges in all (gallivm's loop limiter). If this changes, persistent threads may go back on there.
TEST_F(PersistentThreadsGl, LlvmpipeSharesOneLoopBudgetPerInvocation) {
  AssembledShader shader;
  shader.source = R"(#version 450
layout(local_size_x = 1) in;
layout(std430, binding = 0) buffer Out { uint ran; };
uniform uint u_n;
void main() {
  uint k = 0u;
  for (uint i = 0u; i < u_n; ++i) k++;
  for (uint i = 0u; i < u_n; ++i) k++;
  ran = k;
}
)";
  shader.modules.push_back(ShaderModule{"loop budget", 1, 11});
  const GLuint program = compileComputeProgram(shader);
  GLuint buffer = 0;
  glCreateBuffers(1, &buffer);
  const GLuint zero = 0;
  glNamedBufferData(buffer, 4, &zero, GL_DYNAMIC_READ);
  glUseProgram(program);
  glUniform1ui(glGetUniformLocation(program, "u_n"), 40000u);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, buffer);
  glDispatchCompute(1, 1, 1);
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  GLuint ran = 0;
  glGetNamedBufferSubData(buffer, 0, 4, &ran);
  glDeleteBuffers(1, &buffer);
  glDeleteProgram(program);
  const std::string renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  if (renderer.find("llvmpipe") != std::string::npos)
    EXPECT_NEAR(double(ran), 65535.0, 2.0) << renderer;  // the budget (65,534 measured: entries and exits count)
  else
    EXPECT_EQ(ran, 80000u) << renderer;
  EXPECT_GE(ran, 40000u) << "the first loop alone should finish";
}

// The tracer here (llvmpipe) does not use them by default, and says so.
TEST_F(PersistentThreadsGl, TheTracerLeavesThemOffOnLlvmpipe) {
  PersistentEnv env(nullptr);
  const TriangleSoup soup = traversaltest::soupOf({traversaltest::sphereMesh(8, 16, 1.0f)});
  const std::vector<Aabb> boxes = triangleBoxes(soup);
  const std::vector<glm::vec3> centroids = triangleCentroids(soup);
  const Bvh bvh = buildBvh("sah-binned", BuildInput{boxes, centroids, soup.v0, soup.v1, soup.v2}, BuildOptions{});
  const PackedBvh packed = findLayout("bvh2-cb").pack(bvh, soup);
  RayTracerOptions options;
  options.kernel = "bvh2cb-aila-laine";
  const GlRayTracer tracer(packed, options);
  EXPECT_FALSE(tracer.persistentThreads());
}

}  // namespace
}  // namespace bvhlab
