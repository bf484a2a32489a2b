#include "render/smaa.hpp"

#include <algorithm>
#include <chrono>
#include <stdexcept>

#include <glad/gl.h>

#include "render/gl_context.hpp"
#include "render/gpu_renderer.hpp"
#include "shaders/assemble.hpp"
#include "shaders/smaa_textures.hpp"

namespace bvhlab {

namespace {

// Texture units of the passes (each pass declares its bindings).
enum Unit { kUnit0 = 0, kUnit1 = 1, kUnit2 = 2, kUnit3 = 3 };

GLuint linkSmaaProgram(const std::string& module, const std::string& defines) {
  return compileFullscreenProgram(assembleModule(defines, module));
}

GLuint makeTarget(GLenum format, int width, int height, GLuint* fbo) {
  GLuint tex = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &tex);
  glTextureStorage2D(tex, 1, format, width, height);
  glCreateFramebuffers(1, fbo);
  glNamedFramebufferTexture(*fbo, GL_COLOR_ATTACHMENT0, tex, 0);
  glNamedFramebufferDrawBuffer(*fbo, GL_COLOR_ATTACHMENT0);
  if (glCheckNamedFramebufferStatus(*fbo, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw std::runtime_error("SMAA framebuffer incomplete");
  return tex;
}

template <typename T>
std::vector<T> readTarget(GLuint fbo, int width, int height, GLenum format, GLenum type) {
  std::vector<T> px(size_t(width) * height);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo);
  glReadBuffer(GL_COLOR_ATTACHMENT0);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, width, height, format, type, px.data());
  checkGl("SmaaPass read-back");
  return px;
}

}  // namespace

SmaaPreset parseSmaaPreset(const std::string& name) {
  if (name == "low") return SmaaPreset::Low;
  if (name == "medium") return SmaaPreset::Medium;
  if (name == "high") return SmaaPreset::High;
  if (name == "ultra") return SmaaPreset::Ultra;
  throw std::invalid_argument("unknown SMAA preset '" + name + "' (valid: low, medium, high, ultra)");
}

SmaaEdgeMode parseSmaaEdgeMode(const std::string& name) {
  if (name == "luma") return SmaaEdgeMode::Luma;
  if (name == "color") return SmaaEdgeMode::Color;
  if (name == "geometry") return SmaaEdgeMode::Geometry;
  throw std::invalid_argument("unknown mode '" + name + "' (valid: luma, color, geometry)");
}

const char* smaaPresetName(SmaaPreset preset) {
  switch (preset) {
    case SmaaPreset::Low: return "low";
    case SmaaPreset::Medium: return "medium";
    case SmaaPreset::High: return "high";
    case SmaaPreset::Ultra: return "ultra";
  }
  return "?";
}

SmaaSettings SmaaSettings::preset(SmaaPreset preset) {
  SmaaSettings s;
  switch (preset) {
    case SmaaPreset::Low: s.threshold = 0.15f, s.maxSearchSteps = 4, s.maxDiagSearchSteps = 0, s.cornerRounding = 100; break;
    case SmaaPreset::Medium: s.threshold = 0.1f, s.maxSearchSteps = 8, s.maxDiagSearchSteps = 0, s.cornerRounding = 100; break;
    case SmaaPreset::High: s.threshold = 0.1f, s.maxSearchSteps = 16, s.maxDiagSearchSteps = 8, s.cornerRounding = 25; break;
    case SmaaPreset::Ultra: s.threshold = 0.05f, s.maxSearchSteps = 32, s.maxDiagSearchSteps = 16, s.cornerRounding = 25; break;
  }
  return s;
}

SmaaPass::SmaaPass(int width, int height, const SmaaSettings& settings)
    : width_(width), height_(height), settings_(settings) {
  if (width < 1 || height < 1) throw std::invalid_argument("SMAA frame size must be at least 1x1");
  if (!(settings.threshold > 0.0f && settings.threshold <= 1.0f))
    throw std::invalid_argument("SMAA threshold must be in (0, 1]");
  // Search distances beyond the area texture's reach (225 pixels) would all read its last texel.
  if (settings.maxSearchSteps < 1 || 2 * settings.maxSearchSteps > smaa::kAreaMaxDistance)
    throw std::invalid_argument("SMAA maxSearchSteps must be in 1.." + std::to_string(smaa::kAreaMaxDistance / 2));
  if (settings.maxDiagSearchSteps < 0 || settings.maxDiagSearchSteps > smaa::kDiagMaxDistance)
    throw std::invalid_argument("SMAA maxDiagSearchSteps must be in 0.." + std::to_string(smaa::kDiagMaxDistance));
  if (settings.cornerRounding < 0 || settings.cornerRounding > 100)
    throw std::invalid_argument("SMAA cornerRounding must be a percentage in 0..100");

  std::string defines = "#define SMAA_THRESHOLD " + std::to_string(settings.threshold) + "\n" +
                        "#define SMAA_EDGE_COLOR " + (settings.edgeMode == SmaaEdgeMode::Color ? "1" : "0") +
                        "\n#define SMAA_EDGE_GEOMETRY " + (settings.edgeMode == SmaaEdgeMode::Geometry ? "1" : "0") +
                        "\n#define SMAA_MAX_SEARCH_STEPS " + std::to_string(settings.maxSearchSteps) +
                        "\n#define SMAA_CORNER_ROUNDING " + std::to_string(settings.cornerRounding) +
                        "\n#define SMAA_MAX_SEARCH_STEPS_DIAG " + std::to_string(settings.maxDiagSearchSteps) + "\n";
  edgesProgram_ = linkSmaaProgram("smaa_edges.glsl", defines);
  weightsProgram_ = linkSmaaProgram("smaa_weights.glsl", defines);
  blendProgram_ = linkSmaaProgram("smaa_blend.glsl", defines);
  glProgramUniform1i(weightsProgram_, 0, settings.maxSearchSteps);  // see smaa_weights.glsl
  if (settings.maxDiagSearchSteps > 0) glProgramUniform1i(weightsProgram_, 1, settings.maxDiagSearchSteps);
  glCreateVertexArrays(1, &vao_);

  edgesTex_ = makeTarget(GL_RG8, width, height, &edgesFbo_);
  weightsTex_ = makeTarget(GL_RGBA16F, width, height, &weightsFbo_);
  outputTex_ = makeTarget(GL_RGBA8, width, height, &outputFbo_);

  // Generated once per process, on first use (the same for every size and preset).
  static const smaa::AreaTexture area = smaa::makeOrthogonalAreaTexture();
  glCreateTextures(GL_TEXTURE_2D, 1, &areaTex_);
  glTextureStorage2D(areaTex_, 1, GL_RG32F, area.width, area.height);
  glTextureSubImage2D(areaTex_, 0, 0, 0, area.width, area.height, GL_RG, GL_FLOAT, area.texels.data());

  static const smaa::DiagonalAreaTexture areaDiag = smaa::makeDiagonalAreaTexture();
  glCreateTextures(GL_TEXTURE_2D, 1, &areaDiagTex_);
  glTextureStorage2D(areaDiagTex_, 1, GL_RGBA32F, areaDiag.width, areaDiag.height);
  glTextureSubImage2D(areaDiagTex_, 0, 0, 0, areaDiag.width, areaDiag.height, GL_RGBA, GL_FLOAT,
                      areaDiag.texels.data());
  glTextureParameteri(areaDiagTex_, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTextureParameteri(areaDiagTex_, GL_TEXTURE_MAG_FILTER, GL_NEAREST);

  static const smaa::SearchTexture search = smaa::makeSearchTexture();
  glCreateTextures(GL_TEXTURE_2D, 1, &searchTex_);
  glTextureStorage2D(searchTex_, 1, GL_R8UI, search.width, search.height);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTextureSubImage2D(searchTex_, 0, 0, 0, search.width, search.height, GL_RED_INTEGER, GL_UNSIGNED_BYTE,
                      search.texels.data());
  // An integer texture is incomplete (reads 0) under the default linear filters.
  glTextureParameteri(searchTex_, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTextureParameteri(searchTex_, GL_TEXTURE_MAG_FILTER, GL_NEAREST);

  // The bilinear fetches of the search and the area lookup need linear filtering, clamped at the border.
  glCreateSamplers(1, &linearClamp_);
  glSamplerParameteri(linearClamp_, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glSamplerParameteri(linearClamp_, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glSamplerParameteri(linearClamp_, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glSamplerParameteri(linearClamp_, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  checkGl("SmaaPass setup");
}

SmaaPass::~SmaaPass() {
  glDeleteProgram(edgesProgram_);
  glDeleteProgram(weightsProgram_);
  glDeleteProgram(blendProgram_);
  glDeleteVertexArrays(1, &vao_);
  GLuint fbos[] = {edgesFbo_, weightsFbo_, outputFbo_};
  glDeleteFramebuffers(3, fbos);
  GLuint textures[] = {edgesTex_, weightsTex_, outputTex_, areaTex_, searchTex_, uploadTex_, areaDiagTex_};
  glDeleteTextures(7, textures);
  glDeleteSamplers(1, &linearClamp_);
}

void SmaaPass::checkPrimaryId(unsigned primaryIdTexture) const {
  if (settings_.edgeMode == SmaaEdgeMode::Geometry && primaryIdTexture == 0)
    throw std::invalid_argument("SMAA geometry edges need the tracer's primary id texture (ShaderOptions::primaryIdOut)");
}

void SmaaPass::runPass(int pass, unsigned colorTexture, unsigned primaryIdTexture) {
  const GLfloat zero[4] = {0.0f, 0.0f, 0.0f, 0.0f};
  glViewport(0, 0, width_, height_);
  glDisable(GL_BLEND);
  glDisable(GL_DEPTH_TEST);
  glBindVertexArray(vao_);
  if (pass == 0) {
    glBindFramebuffer(GL_FRAMEBUFFER, edgesFbo_);
    glClearNamedFramebufferfv(edgesFbo_, GL_COLOR, 0, zero);
    glUseProgram(edgesProgram_);
    glBindTextureUnit(kUnit0, colorTexture);
    glBindSampler(kUnit0, 0);
    if (settings_.edgeMode == SmaaEdgeMode::Geometry) {
      glBindTextureUnit(kUnit1, primaryIdTexture);
      glBindSampler(kUnit1, 0);
    }
  } else if (pass == 1) {
    glBindFramebuffer(GL_FRAMEBUFFER, weightsFbo_);
    glClearNamedFramebufferfv(weightsFbo_, GL_COLOR, 0, zero);
    glUseProgram(weightsProgram_);
    glBindTextureUnit(kUnit0, edgesTex_);
    glBindSampler(kUnit0, linearClamp_);
    glBindTextureUnit(kUnit1, areaTex_);
    glBindSampler(kUnit1, linearClamp_);
    glBindTextureUnit(kUnit2, searchTex_);
    glBindSampler(kUnit2, 0);
    glBindTextureUnit(kUnit3, areaDiagTex_);
    glBindSampler(kUnit3, 0);
  } else {
    glBindFramebuffer(GL_FRAMEBUFFER, outputFbo_);
    glClearNamedFramebufferfv(outputFbo_, GL_COLOR, 0, zero);
    glUseProgram(blendProgram_);
    glBindTextureUnit(kUnit0, colorTexture);
    glBindSampler(kUnit0, 0);
    glBindTextureUnit(kUnit1, weightsTex_);
    glBindSampler(kUnit1, 0);
  }
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glBindSampler(kUnit0, 0);
  glBindSampler(kUnit1, 0);
  checkGl("SmaaPass pass");
}

unsigned SmaaPass::apply(unsigned colorTexture, unsigned primaryIdTexture) {
  checkPrimaryId(primaryIdTexture);
  for (int pass = 0; pass < 3; ++pass) runPass(pass, colorTexture, primaryIdTexture);
  return outputTex_;
}

std::array<double, 3> SmaaPass::applyProfiled(unsigned colorTexture, unsigned primaryIdTexture) {
  checkPrimaryId(primaryIdTexture);
  std::array<double, 3> ms{};
  glFinish();  // whatever was queued before (the tracer's frame) is not the passes' time
  for (int pass = 0; pass < 3; ++pass) {
    const auto start = std::chrono::steady_clock::now();
    runPass(pass, colorTexture, primaryIdTexture);
    glFinish();
    ms[pass] = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  }
  return ms;
}

std::vector<uint8_t> SmaaPass::apply(const std::vector<uint8_t>& rgbaBottomUp) {
  if (rgbaBottomUp.size() != size_t(width_) * height_ * 4)
    throw std::invalid_argument("SmaaPass::apply: expected " + std::to_string(size_t(width_) * height_ * 4) +
                                " bytes (RGBA8 " + std::to_string(width_) + "x" + std::to_string(height_) +
                                "), got " + std::to_string(rgbaBottomUp.size()));
  if (!uploadTex_) {
    glCreateTextures(GL_TEXTURE_2D, 1, &uploadTex_);
    glTextureStorage2D(uploadTex_, 1, GL_RGBA8, width_, height_);
  }
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTextureSubImage2D(uploadTex_, 0, 0, 0, width_, height_, GL_RGBA, GL_UNSIGNED_BYTE, rgbaBottomUp.data());
  apply(uploadTex_);
  return readOutput();
}

std::vector<uint8_t> SmaaPass::readOutput() const {
  std::vector<glm::u8vec4> px = readTarget<glm::u8vec4>(outputFbo_, width_, height_, GL_RGBA, GL_UNSIGNED_BYTE);
  std::vector<uint8_t> out(px.size() * 4);
  std::copy_n(reinterpret_cast<const uint8_t*>(px.data()), out.size(), out.data());
  return out;
}

std::vector<glm::vec2> SmaaPass::readEdges() const {
  return readTarget<glm::vec2>(edgesFbo_, width_, height_, GL_RG, GL_FLOAT);
}

std::vector<glm::vec4> SmaaPass::readWeights() const {
  return readTarget<glm::vec4>(weightsFbo_, width_, height_, GL_RGBA, GL_FLOAT);
}

}  // namespace bvhlab
