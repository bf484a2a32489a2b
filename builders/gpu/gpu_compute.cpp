// The GL glue of the GPU builders (builders/gpu/gpu_compute.hpp).
#include "builders/gpu/gpu_compute.hpp"

#include <mutex>
#include <stdexcept>

#include "render/gl_context.hpp"
#include "shaders/assemble.hpp"

namespace bvhlab::gpubuild {

namespace {
std::mutex sourcesMutex;
std::map<std::string, std::string>& sourcesMade() {
  static std::map<std::string, std::string> made;
  return made;
}
}  // namespace

std::map<std::string, std::string> computeSourcesMade() {
  std::lock_guard<std::mutex> lock(sourcesMutex);
  return sourcesMade();
}

ComputeProgram::ComputeProgram(const std::string& module, const std::string& defines,
                               const std::vector<std::string>& prelude)
    : module_(module) {
  const auto& sources = glslSources();
  auto moduleText = [&](const std::string& name) -> const std::string& {
    const auto found = sources.find(name);
    if (found == sources.end()) throw std::runtime_error("GPU builder: no embedded GLSL module " + name);
    return found->second;
  };
  std::string source = "#version 450\n" + defines;
  for (size_t k = 0; k < prelude.size(); ++k) {
    source += "#line 1 " + std::to_string(k + 1) + "\n" + moduleText(prelude[k]);
    module_ += (k == 0 ? " (source strings 1.. in messages: " : ", ") + prelude[k] + (k + 1 == prelude.size() ? ")" : "");
  }
  source += "#line 1 0\n" + moduleText(module);
  {
    std::lock_guard<std::mutex> lock(sourcesMutex);
    sourcesMade()[module_ + (defines.empty() ? "" : " with " + defines)] = source;
  }
  GLuint shader = glCreateShader(GL_COMPUTE_SHADER);
  const char* text = source.c_str();
  glShaderSource(shader, 1, &text, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  char log[4096] = {};
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    glGetShaderInfoLog(shader, sizeof log, nullptr, log);
    glDeleteShader(shader);
    throw std::runtime_error("GPU builder: " + module_ + " does not compile: " + log);
  }
  program_ = glCreateProgram();
  glAttachShader(program_, shader);
  glLinkProgram(program_);
  glDeleteShader(shader);
  glGetProgramiv(program_, GL_LINK_STATUS, &ok);
  if (!ok) {
    glGetProgramInfoLog(program_, sizeof log, nullptr, log);
    glDeleteProgram(program_);
    throw std::runtime_error("GPU builder: " + module_ + " does not link: " + log);
  }
}

ComputeProgram::~ComputeProgram() { glDeleteProgram(program_); }

void ComputeProgram::set(const char* name, uint32_t v) const { glProgramUniform1ui(program_, glGetUniformLocation(program_, name), v); }
void ComputeProgram::set(const char* name, int32_t v) const { glProgramUniform1i(program_, glGetUniformLocation(program_, name), v); }
void ComputeProgram::set(const char* name, float v) const { glProgramUniform1f(program_, glGetUniformLocation(program_, name), v); }

// The barrier after every pass: storage written by a pass is read by the next pass, by buffer reads
// and copies, and (ploc-gpu's pass state) as the next dispatch's indirect command.
constexpr GLbitfield kPassBarrier = GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT;

void ComputeProgram::dispatch(uint32_t groups, const char* pass) const {
  glUseProgram(program_);
  glDispatchCompute(groups, 1, 1);
  glMemoryBarrier(kPassBarrier);
  checkGl(pass);
}

void ComputeProgram::dispatchIndirect(GLintptr offset, const char* pass) const {
  glUseProgram(program_);
  glDispatchComputeIndirect(offset);
  glMemoryBarrier(kPassBarrier);
  checkGl(pass);
}

GpuLimits queryGpuLimits() {
  GLint64 block = 0;
  glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &block);
  GLint groups = 0;
  glGetIntegeri_v(GL_MAX_COMPUTE_WORK_GROUP_COUNT, 0, &groups);
  checkGl("GPU builder: querying GL_MAX_SHADER_STORAGE_BLOCK_SIZE and GL_MAX_COMPUTE_WORK_GROUP_COUNT");
  return {uint64_t(block), uint32_t(groups)};
}

GLuint makeStorageBuffer(uint64_t bytes, const void* data) {
  GLuint buffer = 0;
  glCreateBuffers(1, &buffer);
  glNamedBufferData(buffer, GLsizeiptr(bytes < 4 ? 4 : bytes), data, GL_DYNAMIC_COPY);
  return buffer;
}

}  // namespace bvhlab::gpubuild
