// The GPU builders' registration, context handling and timing (builders/gpu/gpu_builders.hpp).
#include "builders/gpu/gpu_builders.hpp"

#include <array>
#include <cstdlib>
#include <memory>
#include <stdexcept>

#include <glad/gl.h>
#include <GL/osmesa.h>
#include <EGL/egl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include "builders/builder.hpp"
#include "builders/gpu/gpu_clip_builder.hpp"
#include "builders/gpu/gpu_hploc.hpp"
#include "builders/gpu/gpu_lbvh.hpp"
#include "builders/gpu/gpu_pack.hpp"
#include "builders/gpu/gpu_ploc.hpp"
#include "layout/layout_bvh2cb.hpp"
#include "render/gl_context.hpp"

namespace bvhlab {

namespace {

// A current GL context for the duration of a build: the caller's (its program and storage-buffer
// bindings put back afterwards) or a headless one of our own.
class BuildContext {
 public:
  BuildContext() {
    // OSMesa and EGL: the headless contexts (render/gl_context.hpp); GLFW: the viewer's window.
    if (OSMesaGetCurrentContext() == nullptr && eglGetCurrentContext() == EGL_NO_CONTEXT &&
        glfwGetCurrentContext() == nullptr) {
      const char* env = std::getenv("BVHLAB_GPU_BUILD_BACKEND");
      own_ = createContext(env && *env ? parseBackend(env) : Backend::OSMesa);
      return;
    }
    glGetIntegerv(GL_CURRENT_PROGRAM, &program_);
    glGetIntegerv(GL_SHADER_STORAGE_BUFFER_BINDING, &generic_);
    for (GLuint i = 0; i < bindings_.size(); ++i) {
      glGetIntegeri_v(GL_SHADER_STORAGE_BUFFER_BINDING, i, &bindings_[i].buffer);
      glGetInteger64i_v(GL_SHADER_STORAGE_BUFFER_START, i, &bindings_[i].start);
      glGetInteger64i_v(GL_SHADER_STORAGE_BUFFER_SIZE, i, &bindings_[i].size);
    }
  }
  ~BuildContext() {
    if (own_) return;
    glUseProgram(glIsProgram(GLuint(program_)) ? GLuint(program_) : 0);  // a deleted one was current until now
    for (GLuint i = 0; i < bindings_.size(); ++i) {
      const Binding& b = bindings_[i];
      const GLuint buffer = GLuint(b.buffer);
      GLint64 bytes = 0;
      if (buffer != 0 && glIsBuffer(buffer)) glGetNamedBufferParameteri64v(buffer, GL_BUFFER_SIZE, &bytes);
      if (bytes == 0)  // none, deleted since, or empty: nothing to put back
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, i, 0);
      else if (b.size > 0 && b.start + b.size <= bytes)  // a range (glBindBufferRange)
        glBindBufferRange(GL_SHADER_STORAGE_BUFFER, i, buffer, GLintptr(b.start), GLsizeiptr(b.size));
      else
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, i, buffer);
    }
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, glIsBuffer(GLuint(generic_)) ? GLuint(generic_) : 0);
  }
  BuildContext(const BuildContext&) = delete;
  BuildContext& operator=(const BuildContext&) = delete;

 private:
  struct Binding {
    GLint buffer = 0;
    GLint64 start = 0, size = 0;
  };
  std::unique_ptr<GlContext> own_;
  GLint program_ = 0, generic_ = 0;
  std::array<Binding, 8> bindings_{};  // the slots the passes bind (0..7)
};

}  // namespace

Bvh buildLbvhGpu(const BuildInput& input, const BuildOptions& options) {
  BuildContext context;
  return gpubuild::makeGpuBuilder("lbvh-gpu")->build(input, options, nullptr, nullptr);
}

Bvh buildPlocGpu(const BuildInput& input, const BuildOptions& options) {
  BuildContext context;
  return gpubuild::makeGpuBuilder("ploc-gpu")->build(input, options, nullptr, nullptr);
}

Bvh buildPlocppGpu(const BuildInput& input, const BuildOptions& options) {
  BuildContext context;
  return gpubuild::makeGpuBuilder("plocpp-gpu")->build(input, options, nullptr, nullptr);
}

Bvh buildHplocGpu(const BuildInput& input, const BuildOptions& options) {
  BuildContext context;
  return gpubuild::makeGpuBuilder("hploc-gpu")->build(input, options, nullptr, nullptr);
}

namespace gpubuild {

namespace {
template <class Builder>
class GpuBuilderOf : public AnyGpuBuilder {
 public:
  template <class... Args>
  explicit GpuBuilderOf(Args&&... args) : builder_(std::forward<Args>(args)...) {}
  Bvh build(const BuildInput& input, const BuildOptions& options, GpuPhaseTimes* times,
            const GpuPackRequest* pack) const override {
    return builder_.build(input, options, times, pack);
  }
  void checkLimits(size_t primitives, bool pack) const override { builder_.checkLimits(primitives, pack); }

 private:
  Builder builder_;
};
}  // namespace

std::unique_ptr<AnyGpuBuilder> makeGpuBuilder(const std::string& builder) {
  if (builder == "lbvh-gpu") return std::make_unique<GpuBuilderOf<GpuLbvh>>();
  if (builder == "ploc-gpu") return std::make_unique<GpuBuilderOf<GpuPloc>>(std::nullopt, PlocPasses::Split);
  if (builder == "plocpp-gpu") return std::make_unique<GpuBuilderOf<GpuPloc>>(std::nullopt, PlocPasses::Fused);
  if (builder == "hploc-gpu") return std::make_unique<GpuBuilderOf<GpuHploc>>();
  throw std::invalid_argument(builder + " does not build on the GPU");
}

}  // namespace gpubuild

void registerGpuBuilders() {
  static const bool once = [] {
    BuilderInfo info{"lbvh-gpu",
                     "lbvh's tree built in GLSL compute shaders (Morton codes, radix sort, Karras radix tree, fit, "
                     "SAH collapse); a GL 4.5 context (made when none is current)",
                     buildLbvhGpu,
                     false,
                     false,
                     false,
                     kMaxLeafSize,
                     /*usesMortonSizeBits=*/true};
    info.gpu = true;
    registerBuilder(std::move(info));
    BuilderInfo ploc{"ploc-gpu",
                     "ploc's tree built in GLSL compute shaders (Morton codes, radix sort, nearest neighbours within "
                     "+-plocRadius, mutual pairs merged, compaction by prefix scan, SAH collapse); a GL 4.5 context",
                     buildPlocGpu,
                     false,
                     false,
                     /*usesPlocRadius=*/true,
                     kMaxLeafSize,
                     /*usesMortonSizeBits=*/true};
    ploc.gpu = true;
    registerBuilder(std::move(ploc));
    BuilderInfo plocpp{"plocpp-gpu",
                       "ploc-gpu with each clustering pass one kernel, as PLOC++ fuses it (nearest neighbours over "
                       "a halo, merge and compaction by a decoupled look-back scan): the same tree",
                       buildPlocppGpu,
                       false,
                       false,
                       /*usesPlocRadius=*/true,
                       kMaxLeafSize,
                       /*usesMortonSizeBits=*/true};
    plocpp.gpu = true;
    registerBuilder(std::move(plocpp));
    BuilderInfo hploc{"hploc-gpu",
                      "hploc's tree built in GLSL compute shaders: the radix tree climbed bottom-up and its subtrees "
                      "clustered by ploc's passes within workgroups of 32, in one dispatch; SAH collapse",
                      buildHplocGpu,
                      false,
                      false,
                      /*usesPlocRadius=*/true,
                      kMaxLeafSize,
                      /*usesMortonSizeBits=*/true};
    hploc.gpu = true;
    registerBuilder(std::move(hploc));
    setGpuBuildTimer([](const std::string& builder, const BuildInput& input, const BuildOptions& options, size_t builds,
                        const std::string& layout, const std::string& triangleFormat, const TriangleSoup& soup) {
      const bool pack = gpubuild::gpuPackable(layout) && triangleFormat == "raw";
      return timeGpuBuild(builder, input, options, builds, pack ? layout : std::string(), &soup);
    });
    setGpuClipBuilderFactory(makeResidentClipBuilder);
    return true;
  }();
  (void)once;
}

namespace {

// Throws naming the first texel where the GPU's stream differs from the CPU's.
void expectSameStreams(const PackedBvh& gpu, const PackedBvh& cpu, const std::string& builder) {
  const std::pair<const char*, std::pair<const std::vector<glm::uvec4>*, const std::vector<glm::uvec4>*>> streams[] = {
      {"node", {&gpu.nodes, &cpu.nodes}},
      {"triangle", {&gpu.triangles, &cpu.triangles}},
      {"attribute", {&gpu.attributes, &cpu.attributes}}};
  for (const auto& [name, pair] : streams) {
    const auto& [g, c] = pair;
    if (g->size() != c->size())
      throw std::runtime_error(builder + ": the GPU pack's " + name + " stream has " + std::to_string(g->size()) +
                               " texels, the CPU's " + std::to_string(c->size()));
    for (size_t i = 0; i < g->size(); ++i)
      if ((*g)[i] != (*c)[i])
        throw std::runtime_error(builder + ": the GPU pack's " + name + " stream differs from the CPU's at texel " +
                                 std::to_string(i));
  }
  if (gpu.depth != cpu.depth)
    throw std::runtime_error(builder + ": the GPU pack's depth " + std::to_string(gpu.depth) + " is not the CPU's " +
                             std::to_string(cpu.depth));
}

}  // namespace

GpuBuildTiming timeGpuBuild(const std::string& builder, const BuildInput& input, const BuildOptions& options,
                            size_t builds, const std::string& packLayout, const TriangleSoup* soup) {
  if (!findBuilder(builder).gpu) throw std::invalid_argument(builder + " does not build on the GPU");
  validateBuildInput(input, options);
  BuildContext context;
  GpuBuildTiming timing;
  timing.renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  const std::unique_ptr<gpubuild::AnyGpuBuilder> gpuBuilder = gpubuild::makeGpuBuilder(builder);
  gpubuild::GpuPhaseTimes times;
  PackedBvh packed;
  // The soup's texels uploaded once for all the builds (untimed in each, as a renderer keeps them).
  struct SoupBuffer {
    GLuint id = 0;
    ~SoupBuffer() { glDeleteBuffers(1, &id); }
  } soupBuffer;
  if (!packLayout.empty() && soup && soup->size() == input.boxes.size() && gpubuild::gpuPackable(packLayout))
    soupBuffer.id = gpubuild::uploadSoupTexels(*soup);
  const gpubuild::GpuPackRequest request{packLayout, soup, &packed, soupBuffer.id};
  const gpubuild::GpuPackRequest* pack = packLayout.empty() ? nullptr : &request;
  auto build = [&] { return gpuBuilder->build(input, options, &times, pack); };
  build();  // warm-up: the driver compiles at the first dispatch
  std::vector<double> totals;
  std::vector<std::vector<double>> phases;
  Bvh last;
  for (size_t k = 0; k < builds; ++k) {
    last = build();
    timing.fusedFallbacks += times.fusedFallbacks;
    totals.push_back(times.totalMs());
    phases.resize(times.phases.size());
    for (size_t p = 0; p < times.phases.size(); ++p) phases[p].push_back(times.phases[p].second);
  }
  timing.builds = builds;
  if (pack) {
    expectSameStreams(packed, gpubuild::cpuPackFor(last, *soup, packLayout), builder);
    timing.packLayout = packLayout;
  }
  timing.passes = times.passes;
  timing.passesIssued = times.passesIssued;
  timing.readbacks = times.readbacks;
  timing.totalMs = medianInterval(totals);
  timing.medianMs = medianOf(totals);
  for (size_t p = 0; p < phases.size(); ++p) timing.phaseMedianMs.emplace_back(times.phases[p].first, medianOf(phases[p]));
  return timing;
}

}  // namespace bvhlab
