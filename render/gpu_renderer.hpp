// The GPU side: compiles the assembled tracer, uploads the scene and the packed BVH, draws frames
// into an offscreen FBO and reads back the image and the per-pixel traversal statistics.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "render/prepared_scene.hpp"
#include "render/program_cache.hpp"
#include "shaders/assemble.hpp"

namespace bvhlab {


// A shader that failed to compile or link; what() names the module and line of each message.
struct ShaderError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Compiles and links the full-screen vertex shader with an assembled fragment shader (the tracer or
// a post pass); returns the program.
// Throws ShaderError whose message names module:line for every driver message.
unsigned compileFullscreenProgram(const AssembledShader& shader);

// A compute program from one assembled compute shader (e.g. assembleRayTracer); ShaderError as above.
unsigned compileComputeProgram(const AssembledShader& shader);

// One packed-BVH stream as a texture of the storage kind (a texture buffer or a 2D texture, the
// layout's STORAGE kinds; 0 for ssbo, which reads the buffer itself); for tbo and ssbo, *buffer gets
// the buffer. An empty stream uploads one zero texel. Throws std::runtime_error naming the stream when it exceeds the kind's limit.
unsigned uploadBvhStream(const std::vector<glm::uvec4>& texels, Storage storage, const char* name, unsigned* buffer);
// A packed-BVH stream already on the GPU (a storage buffer of uvec4 texels holding at least `texels`,
// render/gpu_clip_build.hpp) made readable in the storage kind without a copy: a texture buffer over its
// first `texels` texels for tbo, 0 for ssbo (the buffer is bound itself). The buffer stays the caller's.
// Throws std::invalid_argument for tex2d (it would copy) and std::runtime_error naming the stream past
// GL_MAX_TEXTURE_BUFFER_SIZE.
unsigned viewBvhStream(unsigned buffer, size_t texels, Storage storage, const char* name);
// Storage::Ssbo: the node, triangle, attribute and vertex streams' buffers bound as shader storage
// buffers kFirstStreamBinding.. (traversal/storage_ssbo.glsl's bindings).
constexpr unsigned kFirstStreamBinding = 4;
void bindBvhStorageBuffers(const unsigned buffers[4]);

// Decoding of the statistics target (main.glsl's o_stats; the C++ mirror fills the same layout):
// x node visits, y triangle tests, z mesh rays | stack-overflow bit 31, w primary id + 1 | non-finite bit 31.
inline uint32_t statsPrimaryIdPlusOne(const glm::uvec4& s) { return s.w & 0x7FFFFFFFu; }  // 0: miss / shaded view
// The pixel's pre-tone-mapping radiance (shaded view) or view value was NaN or infinite.
inline bool statsNonFinite(const glm::uvec4& s) { return (s.w >> 31) != 0u; }

class GpuRenderer {
 public:
  // Needs a current GL context. Throws ShaderError / std::runtime_error. With `programs`, the tracer
  // program comes from that cache (shared with every renderer of the same shader source; the cache
  // owns it and must outlive this renderer); without, this renderer compiles and owns its own.
  GpuRenderer(const PreparedScene& scene, const ShaderOptions& shader, const FrameOptions& frame,
              ProgramCache* programs = nullptr);
  ~GpuRenderer();
  GpuRenderer(const GpuRenderer&) = delete;
  GpuRenderer& operator=(const GpuRenderer&) = delete;

  double drawFrame();  // draws one frame, waits for it (glFinish), returns wall-clock ms
  std::vector<uint8_t> readColor() const;      // RGBA8, rows bottom-up
  std::vector<glm::uvec4> readStats() const;   // needs ShaderOptions::countStats
  std::vector<uint32_t> readBoxTests() const;  // per pixel, main.glsl's o_boxTests; needs countStats
  std::vector<uint32_t> readPrimaryIds() const;  // per pixel, primary hit id + 1 (0: miss); needs primaryIdOut
  const AssembledShader& shader() const { return shader_; }
  int programIndex() const { return programIndex_; }  // its index in the cache; -1: its own program
  unsigned colorTexture() const { return colorTex_; }  // RGBA8 result, for post passes and viewers
  // R32UI primary hit id + 1 per pixel (0: miss); 0 unless built with ShaderOptions::primaryIdOut.
  unsigned primaryIdTexture() const { return primaryIdTex_; }
  void setCamera(const Camera& camera);

 private:
  void compile();
  void upload();
  void setUniforms(bool samplers = true);  // false: all but the sampler units
  void createFramebuffer();

  const PreparedScene& scene_;
  ShaderOptions options_;
  FrameOptions frame_;
  AssembledShader shader_;
  ProgramCache* programs_ = nullptr;
  int programIndex_ = -1;
  unsigned program_ = 0, vao_ = 0, fbo_ = 0, colorTex_ = 0, statsTex_ = 0, boxTestsTex_ = 0, ubo_ = 0;
  unsigned primaryIdTex_ = 0;  // R32UI, with ShaderOptions::primaryIdOut
  unsigned streams_[4] = {0, 0, 0, 0}, streamBuffers_[4] = {0, 0, 0, 0};  // node, triangle, attribute, vertex
  bool borrowed_ = false;  // streamBuffers_[0..2] are PreparedScene::gpuStreams (not deleted here)
  unsigned texArray_ = 0, worldTex_ = 0;
};

}  // namespace bvhlab
