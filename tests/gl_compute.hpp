// Shared by the tests that run GLSL functions in a compute shader (llvmpipe here, the GPU's driver
// through EGL elsewhere): compile + link with the driver's log, and one dispatch with an input and an
// output shader storage buffer.
#pragma once
#include <stdexcept>
#include <string>
#include <vector>

#include <glad/gl.h>

#include "render/gl_context.hpp"

namespace bvhlab::test {

// Throws std::runtime_error with the driver's log when the source does not compile or link.
inline GLuint compileCompute(const std::string& source) {
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
    throw std::runtime_error(std::string("compute shader: ") + log);
  }
  GLuint program = glCreateProgram();
  glAttachShader(program, shader);
  glLinkProgram(program);
  glDeleteShader(shader);
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    glGetProgramInfoLog(program, sizeof log, nullptr, log);
    glDeleteProgram(program);
    throw std::runtime_error(std::string("compute program: ") + log);
  }
  return program;
}

// Runs `program` (local_size_x = 64, uniform int u_count) for `count` invocations with `in` bound as
// shader storage buffer 0 and `outCount` elements of Out as buffer 1, and returns buffer 1.
template <class Out, class In>
std::vector<Out> dispatchCompute(GLuint program, const std::vector<In>& in, size_t outCount, size_t count,
                                 const char* what) {
  GLuint buffers[2];
  glCreateBuffers(2, buffers);
  glNamedBufferData(buffers[0], GLsizeiptr(in.size() * sizeof(In)), in.data(), GL_STATIC_DRAW);
  glNamedBufferData(buffers[1], GLsizeiptr(outCount * sizeof(Out)), nullptr, GL_STATIC_READ);
  glUseProgram(program);
  glUniform1i(glGetUniformLocation(program, "u_count"), GLint(count));
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, buffers[0]);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, buffers[1]);
  glDispatchCompute(GLuint((count + 63) / 64), 1, 1);
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  std::vector<Out> out(outCount);
  glGetNamedBufferSubData(buffers[1], 0, GLsizeiptr(out.size() * sizeof(Out)), out.data());
  bvhlab::checkGl(what);
  glDeleteBuffers(2, buffers);
  return out;
}

}  // namespace bvhlab::test
