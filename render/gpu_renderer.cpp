#include "render/gpu_renderer.hpp"

#include <chrono>
#include <initializer_list>
#include <iterator>
#include <stdexcept>

#include <glad/gl.h>

#include "render/gl_context.hpp"
#include "shaders/texture_mips.hpp"

namespace bvhlab {

namespace {

enum Unit { kUnitNodes = 0, kUnitTriangles = 1, kUnitAttributes = 2, kUnitTextures = 3, kUnitWorld = 4, kUnitVertices = 5 };

GLuint compileStage(GLenum stage, const std::string& source, const AssembledShader* map) {
  GLuint s = glCreateShader(stage);
  const char* text = source.c_str();
  glShaderSource(s, 1, &text, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    GLint len = 0;
    glGetShaderiv(s, GL_INFO_LOG_LENGTH, &len);
    std::string log(std::max(len, 1), '\0');
    glGetShaderInfoLog(s, len, nullptr, log.data());
    glDeleteShader(s);
    throw ShaderError(std::string(stage == GL_VERTEX_SHADER ? "vertex" : stage == GL_COMPUTE_SHADER ? "compute" : "fragment") +
                      " shader failed to compile:\n" + (map ? map->mapLog(log) : log));
  }
  return s;
}

// Links compiled stages (and deletes them); ShaderError with the mapped log on failure.
GLuint linkProgram(std::initializer_list<GLuint> stages, const AssembledShader& shader, const char* what) {
  GLuint program = glCreateProgram();
  for (GLuint st : stages) glAttachShader(program, st);
  glLinkProgram(program);
  for (GLuint st : stages) glDeleteShader(st);
  GLint ok = 0;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    GLint len = 0;
    glGetProgramiv(program, GL_INFO_LOG_LENGTH, &len);
    std::string log(std::max(len, 1), '\0');
    glGetProgramInfoLog(program, len, nullptr, log.data());
    glDeleteProgram(program);
    throw ShaderError(std::string(what) + " program failed to link:\n" + shader.mapLog(log));
  }
  return program;
}

}  // namespace

unsigned uploadBvhStream(const std::vector<glm::uvec4>& texels, Storage storage, const char* name, unsigned* buffer) {
  static const glm::uvec4 kDummy(0u);  // streams of a mesh-less scene in the uber shader
  const glm::uvec4* data = texels.empty() ? &kDummy : texels.data();
  const GLsizeiptr count = texels.empty() ? 1 : static_cast<GLsizeiptr>(texels.size());
  GLuint tex = 0;
  if (storage == Storage::Ssbo) {
    GLint64 maxBytes = 0;
    glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &maxBytes);
    const GLint64 bytes = GLint64(count) * GLint64(sizeof(glm::uvec4));
    if (bytes > maxBytes)
      throw std::runtime_error(std::string(name) + " stream has " + std::to_string(bytes) +
                               " bytes, above GL_MAX_SHADER_STORAGE_BLOCK_SIZE = " + std::to_string(maxBytes) +
                               " (try --storage tbo or tex2d)");
    glCreateBuffers(1, buffer);
    glNamedBufferStorage(*buffer, count * sizeof(glm::uvec4), data, 0);
  } else if (storage == Storage::Tbo) {
    GLint maxTexels = 0;
    glGetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &maxTexels);
    if (count > maxTexels)
      throw std::runtime_error(std::string(name) + " stream has " + std::to_string(count) +
                               " texels, above GL_MAX_TEXTURE_BUFFER_SIZE = " + std::to_string(maxTexels) +
                               " (try --storage tex2d)");
    glCreateBuffers(1, buffer);
    glNamedBufferStorage(*buffer, count * sizeof(glm::uvec4), data, 0);
    glCreateTextures(GL_TEXTURE_BUFFER, 1, &tex);
    glTextureBuffer(tex, GL_RGBA32UI, *buffer);
  } else {
    GLint maxSize = 0;
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &maxSize);
    const GLsizeiptr width = kTex2DWidth, height = (count + width - 1) / width;
    if (height > maxSize)
      throw std::runtime_error(std::string(name) + " stream needs " + std::to_string(height) + " rows of " +
                               std::to_string(width) + " texels, above GL_MAX_TEXTURE_SIZE = " +
                               std::to_string(maxSize));
    std::vector<glm::uvec4> padded(width * height, glm::uvec4(0u));
    std::copy(data, data + count, padded.begin());
    glCreateTextures(GL_TEXTURE_2D, 1, &tex);
    glTextureStorage2D(tex, 1, GL_RGBA32UI, GLsizei(width), GLsizei(height));
    glTextureSubImage2D(tex, 0, 0, 0, GLsizei(width), GLsizei(height), GL_RGBA_INTEGER, GL_UNSIGNED_INT,
                        padded.data());
    glTextureParameteri(tex, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(tex, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  }
  checkGl(name);
  return tex;
}

unsigned viewBvhStream(unsigned buffer, size_t texels, Storage storage, const char* name) {
  if (storage == Storage::Tex2D)
    throw std::invalid_argument(std::string(name) + " stream: streams on the GPU are bound with --storage tbo or "
                                                    "ssbo; tex2d would copy them into a texture");
  if (storage == Storage::Ssbo) return 0;
  GLint maxTexels = 0;
  glGetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &maxTexels);
  const GLsizeiptr count = GLsizeiptr(std::max<size_t>(1, texels));
  if (count > maxTexels)
    throw std::runtime_error(std::string(name) + " stream has " + std::to_string(count) +
                             " texels, above GL_MAX_TEXTURE_BUFFER_SIZE = " + std::to_string(maxTexels));
  GLuint tex = 0;
  glCreateTextures(GL_TEXTURE_BUFFER, 1, &tex);
  glTextureBufferRange(tex, GL_RGBA32UI, buffer, 0, count * GLsizeiptr(sizeof(glm::uvec4)));
  checkGl(name);
  return tex;
}

void bindBvhStorageBuffers(const unsigned buffers[4]) {
  for (GLuint k = 0; k < 4; ++k) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kFirstStreamBinding + k, buffers[k]);
}

unsigned compileComputeProgram(const AssembledShader& shader) {
  GLuint cs = compileStage(GL_COMPUTE_SHADER, shader.source, &shader);
  return linkProgram({cs}, shader, "compute");
}

GpuRenderer::GpuRenderer(const PreparedScene& scene, const ShaderOptions& shader, const FrameOptions& frame,
                         ProgramCache* programs)
    : scene_(scene), options_(shader), frame_(frame), programs_(programs) {
  if (frame.width < 1 || frame.height < 1) throw std::invalid_argument("image size must be at least 1x1");
  compile();
  upload();
  createFramebuffer();
  setUniforms();
  checkGl("GpuRenderer setup");
}

GpuRenderer::~GpuRenderer() {
  if (!programs_) glDeleteProgram(program_);  // a cached program belongs to its cache
  glDeleteVertexArrays(1, &vao_);
  glDeleteFramebuffers(1, &fbo_);
  GLuint textures[] = {colorTex_, statsTex_, boxTestsTex_, primaryIdTex_, streams_[0], streams_[1], streams_[2], streams_[3], texArray_, worldTex_};
  glDeleteTextures(GLsizei(std::size(textures)), textures);
  glDeleteBuffers(borrowed_ ? 0 : 3, streamBuffers_);  // borrowed: PreparedScene::gpuStreams' owner deletes them
  glDeleteBuffers(1, &streamBuffers_[3]);
  glDeleteBuffers(1, &ubo_);
}

unsigned compileFullscreenProgram(const AssembledShader& shader) {
  GLuint vs = compileStage(GL_VERTEX_SHADER, fullscreenVertexShader(), nullptr);
  GLuint fs = 0;
  try {
    fs = compileStage(GL_FRAGMENT_SHADER, shader.source, &shader);
  } catch (...) {
    glDeleteShader(vs);
    throw;
  }
  return linkProgram({vs, fs}, shader, "tracer");
}

void GpuRenderer::compile() {
  SceneFeatures features = analyzeScene(scene_.scene);
  // The shader decodes the NODE stream with its layout's accessors: they must be the tree's.
  if (options_.layout != scene_.packed.layout)
    throw std::invalid_argument("the shader is assembled for layout " + options_.layout + " but the tree is packed in " +
                                scene_.packed.layout + " (prepareScene's layout)");
  if (options_.triangles != scene_.packed.triangleFormat)
    throw std::invalid_argument("the shader is assembled for triangle format " + options_.triangles +
                                " but the tree's triangles are packed as " + scene_.packed.triangleFormat);
  if (options_.bvhStackSize < 1) options_.bvhStackSize = 1;
  shader_ = assembleTracer(features, options_);
  if (programs_) {
    const ProgramCache::Program p = programs_->get(shader_);
    program_ = p.id;
    programIndex_ = p.index;
  } else {
    program_ = compileFullscreenProgram(shader_);
  }
  glCreateVertexArrays(1, &vao_);
}

void GpuRenderer::upload() {
  const SceneData& d = scene_.data;
  std::vector<uint8_t> block = d.uniformBlock();
  glCreateBuffers(1, &ubo_);
  glNamedBufferStorage(ubo_, GLsizeiptr(block.size()), block.data(), 0);
  GLint maxBlock = 0;
  glGetIntegerv(GL_MAX_UNIFORM_BLOCK_SIZE, &maxBlock);
  if (GLint(block.size()) > maxBlock)
    throw std::runtime_error("scene has too many objects/materials/lights for one uniform block (" +
                             std::to_string(block.size()) + " > " + std::to_string(maxBlock) + " bytes)");

  const PackedBvh& p = scene_.packed;
  const std::vector<glm::uvec4>* sized[3] = {&p.nodes, &p.triangles, &p.attributes};
  const char* names[3] = {"node", "triangle", "attribute"};
  borrowed_ = scene_.gpuStreams[0] != 0;
  for (int k = 0; k < 3; ++k)
    if (borrowed_) {  // built and packed on the GPU: bound as they lie
      streamBuffers_[k] = scene_.gpuStreams[k];
      streams_[k] = viewBvhStream(streamBuffers_[k], sized[k]->size(), options_.storage, names[k]);
    } else {
      streams_[k] = uploadBvhStream(*sized[k], options_.storage, names[k], &streamBuffers_[k]);
    }
  streams_[3] = uploadBvhStream(p.vertices, options_.storage, "vertex", &streamBuffers_[3]);  // indexed only
  if (borrowed_) glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);

  // Material textures (a 1x1x1 dummy keeps the uber shader's sampler complete) and the world map.
  // With ray cones (texture_lod.glsl) both carry the host's mip chains (shaders/texture_mips.hpp, the
  // mirror's texels) and filter trilinearly (cones-aniso takes its own taps). Without, one level.
  const bool mipmapped = usesTextureLod(analyzeScene(scene_.scene), options_);
  const GLint minFilter = mipmapped ? GL_LINEAR_MIPMAP_LINEAR : GL_LINEAR;
  const TextureArray& ta = d.textures;
  const int layers = std::max(1, ta.layers);
  std::vector<glm::vec4> texels = ta.texels;
  if (texels.empty()) texels.assign(size_t(ta.width) * ta.height, glm::vec4(1.0f));
  const TextureMips mips = mipmapped ? buildTextureMips(d) : TextureMips{};  // the mirror's levels
  glCreateTextures(GL_TEXTURE_2D_ARRAY, 1, &texArray_);
  if (mipmapped) {
    const std::vector<MipLevel>& chain = mips.textures;
    glTextureStorage3D(texArray_, GLsizei(chain.size()), GL_RGBA32F, ta.width, ta.height, layers);
    for (size_t k = 0; k < chain.size(); ++k)
      glTextureSubImage3D(texArray_, GLint(k), 0, 0, 0, chain[k].width, chain[k].height, layers, GL_RGBA, GL_FLOAT,
                          chain[k].texels.data());
  } else {
    glTextureStorage3D(texArray_, 1, GL_RGBA32F, ta.width, ta.height, layers);
    glTextureSubImage3D(texArray_, 0, 0, 0, 0, ta.width, ta.height, layers, GL_RGBA, GL_FLOAT, texels.data());
  }
  glTextureParameteri(texArray_, GL_TEXTURE_MIN_FILTER, minFilter);
  glTextureParameteri(texArray_, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTextureParameteri(texArray_, GL_TEXTURE_WRAP_S, GL_REPEAT);
  glTextureParameteri(texArray_, GL_TEXTURE_WRAP_T, GL_REPEAT);

  glCreateTextures(GL_TEXTURE_2D, 1, &worldTex_);
  if (d.worldMap && mipmapped) {
    const std::vector<MipLevel>& chain = mips.world;
    glTextureStorage2D(worldTex_, GLsizei(chain.size()), GL_RGBA32F, d.worldMap->width, d.worldMap->height);
    for (size_t k = 0; k < chain.size(); ++k)
      glTextureSubImage2D(worldTex_, GLint(k), 0, 0, chain[k].width, chain[k].height, GL_RGBA, GL_FLOAT,
                          chain[k].texels.data());
  } else if (d.worldMap) {
    glTextureStorage2D(worldTex_, 1, GL_RGBA32F, d.worldMap->width, d.worldMap->height);
    glTextureSubImage2D(worldTex_, 0, 0, 0, d.worldMap->width, d.worldMap->height, GL_RGBA, GL_FLOAT,
                        d.worldMap->texels.data());
  } else {
    const glm::vec4 black(0.0f);
    glTextureStorage2D(worldTex_, 1, GL_RGBA32F, 1, 1);
    glTextureSubImage2D(worldTex_, 0, 0, 0, 1, 1, GL_RGBA, GL_FLOAT, &black);
  }
  glTextureParameteri(worldTex_, GL_TEXTURE_MIN_FILTER, d.worldMap ? minFilter : GL_LINEAR);
  glTextureParameteri(worldTex_, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTextureParameteri(worldTex_, GL_TEXTURE_WRAP_S, GL_REPEAT);
  glTextureParameteri(worldTex_, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  checkGl("scene upload");
}

// Uniforms live in the program: a program shared through a ProgramCache gets this renderer's values
// again before each of its frames (drawFrame), so renderers never see each other's settings.
void GpuRenderer::setUniforms(bool samplers) {
  const SceneData& d = scene_.data;
  const PackedBvh& p = scene_.packed;
  glUseProgram(program_);
  auto seti = [&](const char* n, int v) { glUniform1i(glGetUniformLocation(program_, n), v); };
  auto setf = [&](const char* n, float v) { glUniform1f(glGetUniformLocation(program_, n), v); };
  auto set3 = [&](const char* n, glm::vec3 v) { glUniform3f(glGetUniformLocation(program_, n), v.x, v.y, v.z); };
  if (samplers) {
    seti("u_nodes", kUnitNodes);
    seti("u_triangles", kUnitTriangles);
    seti("u_attributes", kUnitAttributes);
    seti("u_vertices", kUnitVertices);
    seti("u_textures", kUnitTextures);
    seti("u_worldMap", kUnitWorld);
  }
  seti("u_meshPresent", p.triangles.empty() ? 0 : 1);
  const World& w = scene_.scene.world;
  seti("u_worldKind", static_cast<int>(w.kind));
  setf("u_worldIntensity", w.intensity);
  setf("u_worldRotation", glm::radians(w.rotationDeg));
  set3("u_worldColor", w.color);
  set3("u_skyZenith", w.zenith);
  set3("u_skyHorizon", w.horizon);
  set3("u_skyGround", w.ground);
  setf("u_exposure", frame_.exposure);
  setf("u_sceneRadius", d.sceneRadius);
  glUniform2f(glGetUniformLocation(program_, "u_resolution"), float(frame_.width), float(frame_.height));
  setCamera(frame_.camera);
  checkGl("uniforms");
}

void GpuRenderer::setCamera(const Camera& camera) {
  frame_.camera = camera;
  CameraBasis b = cameraBasis(camera, frame_.width, frame_.height);
  glUseProgram(program_);
  glUniform3fv(glGetUniformLocation(program_, "u_eye"), 1, &b.eye.x);
  glUniform3fv(glGetUniformLocation(program_, "u_forward"), 1, &b.forward.x);
  glUniform3fv(glGetUniformLocation(program_, "u_right"), 1, &b.right.x);
  glUniform3fv(glGetUniformLocation(program_, "u_up"), 1, &b.up.x);
}

void GpuRenderer::createFramebuffer() {
  glCreateFramebuffers(1, &fbo_);
  glCreateTextures(GL_TEXTURE_2D, 1, &colorTex_);
  glTextureStorage2D(colorTex_, 1, GL_RGBA8, frame_.width, frame_.height);
  glNamedFramebufferTexture(fbo_, GL_COLOR_ATTACHMENT0, colorTex_, 0);
  // main.glsl's outputs: 0 colour, 1 and 2 the counters (COUNT_STATS), 3 the primary id (PRIMARY_ID_OUT).
  GLenum bufs[] = {GL_COLOR_ATTACHMENT0, GL_NONE, GL_NONE, GL_NONE};
  if (options_.countStats) {
    glCreateTextures(GL_TEXTURE_2D, 1, &statsTex_);
    glTextureStorage2D(statsTex_, 1, GL_RGBA32UI, frame_.width, frame_.height);
    glNamedFramebufferTexture(fbo_, GL_COLOR_ATTACHMENT1, statsTex_, 0);
    glCreateTextures(GL_TEXTURE_2D, 1, &boxTestsTex_);
    glTextureStorage2D(boxTestsTex_, 1, GL_R32UI, frame_.width, frame_.height);
    glNamedFramebufferTexture(fbo_, GL_COLOR_ATTACHMENT2, boxTestsTex_, 0);
    bufs[1] = GL_COLOR_ATTACHMENT1;
    bufs[2] = GL_COLOR_ATTACHMENT2;
  }
  if (options_.primaryIdOut) {
    glCreateTextures(GL_TEXTURE_2D, 1, &primaryIdTex_);
    glTextureStorage2D(primaryIdTex_, 1, GL_R32UI, frame_.width, frame_.height);
    // An integer texture is incomplete (texelFetch reads 0) under the default mipmapped min filter.
    glTextureParameteri(primaryIdTex_, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(primaryIdTex_, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glNamedFramebufferTexture(fbo_, GL_COLOR_ATTACHMENT3, primaryIdTex_, 0);
    bufs[3] = GL_COLOR_ATTACHMENT3;
  }
  const GLsizei drawn = options_.primaryIdOut ? 4 : options_.countStats ? 3 : 1;
  glNamedFramebufferDrawBuffers(fbo_, drawn, bufs);
  if (glCheckNamedFramebufferStatus(fbo_, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw std::runtime_error("offscreen framebuffer incomplete");
}

double GpuRenderer::drawFrame() {
  // A shared program holds the last renderer's uniforms: this one's again (not timed). Its samplers'
  // units are the same constants for every renderer, set once at construction: re-setting them each
  // frame is state a driver may revalidate at the draw, inside the timed span (docs/gpu.md, section 6).
  if (programs_) setUniforms(false);
  auto start = std::chrono::steady_clock::now();
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
  glViewport(0, 0, frame_.width, frame_.height);
  glUseProgram(program_);
  glBindBufferBase(GL_UNIFORM_BUFFER, 0, ubo_);
  if (options_.storage == Storage::Ssbo) {
    bindBvhStorageBuffers(streamBuffers_);
  } else {
    glBindTextureUnit(kUnitNodes, streams_[0]);
    glBindTextureUnit(kUnitTriangles, streams_[1]);
    glBindTextureUnit(kUnitAttributes, streams_[2]);
    glBindTextureUnit(kUnitVertices, streams_[3]);
  }
  glBindTextureUnit(kUnitTextures, texArray_);
  glBindTextureUnit(kUnitWorld, worldTex_);
  glBindVertexArray(vao_);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glFinish();
  auto end = std::chrono::steady_clock::now();
  checkGl("drawFrame");
  return std::chrono::duration<double, std::milli>(end - start).count();
}

std::vector<uint8_t> GpuRenderer::readColor() const {
  std::vector<uint8_t> px(size_t(frame_.width) * frame_.height * 4);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo_);
  glReadBuffer(GL_COLOR_ATTACHMENT0);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, frame_.width, frame_.height, GL_RGBA, GL_UNSIGNED_BYTE, px.data());
  checkGl("readColor");
  return px;
}

std::vector<glm::uvec4> GpuRenderer::readStats() const {
  if (!options_.countStats) throw std::logic_error("readStats needs a renderer built with countStats");
  std::vector<glm::uvec4> px(size_t(frame_.width) * frame_.height);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo_);
  glReadBuffer(GL_COLOR_ATTACHMENT1);
  glReadPixels(0, 0, frame_.width, frame_.height, GL_RGBA_INTEGER, GL_UNSIGNED_INT, px.data());
  checkGl("readStats");
  return px;
}

std::vector<uint32_t> GpuRenderer::readBoxTests() const {
  if (!options_.countStats) throw std::logic_error("readBoxTests needs a renderer built with countStats");
  std::vector<uint32_t> px(size_t(frame_.width) * frame_.height);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo_);
  glReadBuffer(GL_COLOR_ATTACHMENT2);
  glReadPixels(0, 0, frame_.width, frame_.height, GL_RED_INTEGER, GL_UNSIGNED_INT, px.data());
  checkGl("readBoxTests");
  return px;
}

std::vector<uint32_t> GpuRenderer::readPrimaryIds() const {
  if (!options_.primaryIdOut) throw std::logic_error("readPrimaryIds needs a renderer built with primaryIdOut");
  std::vector<uint32_t> px(size_t(frame_.width) * frame_.height);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo_);
  glReadBuffer(GL_COLOR_ATTACHMENT3);
  glReadPixels(0, 0, frame_.width, frame_.height, GL_RED_INTEGER, GL_UNSIGNED_INT, px.data());
  checkGl("readPrimaryIds");
  return px;
}

}  // namespace bvhlab
