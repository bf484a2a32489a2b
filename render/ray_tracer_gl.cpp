#include "render/ray_tracer_gl.hpp"

#include <algorithm>
#include <bit>
#include <chrono>
#include <stdexcept>
#include <string>

#include <glad/gl.h>

#include "render/gl_context.hpp"
#include "render/gpu_renderer.hpp"
#include "traversal/kernels.hpp"

namespace bvhlab {

namespace {

constexpr GLuint kLocalSize = kComputeLanes;  // trace_rays.glsl's local_size_x (shaders/assemble.hpp)
// Work groups of a persistent-threads dispatch: 4096 x 64 = 262,144 invocations, about the resident
// thread count of the largest GPUs in use (an H100 or H200: 132 SMs x 2,048 threads = 270,336), so
// every resident slot gets an invocation and a group launched late finds the rays taken and exits.
constexpr GLuint kPersistentGroups = 4096;

std::vector<BatchHit> decode(const std::vector<glm::uvec4>& raw, bool anyHit, const std::vector<float>& tMax) {
  std::vector<BatchHit> hits(raw.size());
  for (size_t i = 0; i < raw.size(); ++i) {
    hits[i].hit = raw[i].x != 0u;
    if (anyHit) {
      hits[i].t = tMax[i];
    } else {
      hits[i].prim = hits[i].hit ? raw[i].y : BatchHit::kNoPrim;
      hits[i].t = std::bit_cast<float>(raw[i].z);
    }
  }
  return hits;
}

}  // namespace

GlRayTracer::GlRayTracer(const PackedBvh& packed, const RayTracerOptions& options)
    : options_(options), layout_(packed.layout), triangleFormat_(packed.triangleFormat), stack_(stackSizeFor(packed)),
      persistent_(persistentThreadsOn(findKernel(packed.layout, options.kernel),
                                      reinterpret_cast<const char*>(glGetString(GL_RENDERER)))) {
  const int stack = stack_;
  const std::string& layout = packed.layout;
  timed_ = compileComputeProgram(
      assembleRayTracer(options.kernel, options.storage, options.robust, stack, options.anyHit, false, layout,
                        packed.triangleFormat, options.twoLevel, persistent_));
  counted_ = compileComputeProgram(
      assembleRayTracer(options.kernel, options.storage, options.robust, stack, options.anyHit, true, layout,
                        packed.triangleFormat, options.twoLevel, persistent_));
  upload(packed);
  const char* names[4] = {"u_nodes", "u_triangles", "u_attributes", "u_vertices"};
  for (GLuint program : {timed_, counted_}) {
    glUseProgram(program);
    for (int unit = 0; unit < 4; ++unit) glUniform1i(glGetUniformLocation(program, names[unit]), unit);
  }
  glCreateBuffers(1, &rayBuffer_);
  glCreateBuffers(1, &resultBuffer_);
  glCreateBuffers(1, &countBuffer_);
  glCreateBuffers(1, &rayCounter_);
  const GLuint zero = 0;
  glNamedBufferData(rayCounter_, sizeof(GLuint), &zero, GL_DYNAMIC_DRAW);
  checkGl("GlRayTracer setup");
}

void GlRayTracer::upload(const PackedBvh& packed) {
  streams_[0] = uploadBvhStream(packed.nodes, options_.storage, "node", &streamBuffers_[0]);
  streams_[1] = uploadBvhStream(packed.triangles, options_.storage, "triangle", &streamBuffers_[1]);
  streams_[2] = uploadBvhStream(packed.attributes, options_.storage, "attribute", &streamBuffers_[2]);
  streams_[3] = uploadBvhStream(packed.vertices, options_.storage, "vertex", &streamBuffers_[3]);  // indexed only
}

void GlRayTracer::checkSameProgram(const PackedBvh& packed, const char* what) const {
  if (packed.layout != layout_ || packed.triangleFormat != triangleFormat_ || stackSizeFor(packed) > stack_)
    throw std::invalid_argument(std::string("GlRayTracer::") + what + ": the tree needs another program (layout " +
                                packed.layout + ", triangles " + packed.triangleFormat + ", stack " +
                                std::to_string(stackSizeFor(packed)) + " > " + std::to_string(stack_) + ")");
}

void GlRayTracer::releaseStreams() {
  glDeleteTextures(4, streams_);
  glDeleteBuffers(borrowed_ ? 0 : 3, streamBuffers_);
  glDeleteBuffers(1, &streamBuffers_[3]);
  for (int k = 0; k < 4; ++k) streams_[k] = streamBuffers_[k] = 0;
  borrowed_ = false;
}

void GlRayTracer::setTree(const PackedBvh& packed) {
  checkSameProgram(packed, "setTree");
  releaseStreams();
  upload(packed);
  checkGl("re-uploading the tree");
}

void GlRayTracer::setTreeBuffers(const PackedBvh& shape, const unsigned buffers[3]) {
  checkSameProgram(shape, "setTreeBuffers");
  if (options_.storage == Storage::Tex2D)  // before anything is released (viewBvhStream would refuse it too)
    throw std::invalid_argument("GlRayTracer::setTreeBuffers: --storage tex2d would copy the streams into textures; "
                                "streams on the GPU are bound with --storage tbo or ssbo");
  releaseStreams();
  borrowed_ = true;
  const std::vector<glm::uvec4>* sized[3] = {&shape.nodes, &shape.triangles, &shape.attributes};
  const char* names[3] = {"node", "triangle", "attribute"};
  for (int k = 0; k < 3; ++k) {
    streamBuffers_[k] = buffers[k];
    streams_[k] = viewBvhStream(buffers[k], sized[k]->size(), options_.storage, names[k]);
  }
  streams_[3] = uploadBvhStream(shape.vertices, options_.storage, "vertex", &streamBuffers_[3]);  // indexed only
  glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
  checkGl("binding the tree's streams on the GPU");
}

GlRayTracer::~GlRayTracer() {
  glDeleteProgram(timed_);
  glDeleteProgram(counted_);
  releaseStreams();
  GLuint buffers[] = {rayBuffer_, resultBuffer_, countBuffer_, rayCounter_};
  glDeleteBuffers(4, buffers);
}

void GlRayTracer::setRays(const std::vector<BatchRay>& rays) {
  count_ = rays.size();
  const GLsizeiptr n = GLsizeiptr(std::max<size_t>(1, count_));
  glNamedBufferData(rayBuffer_, n * GLsizeiptr(sizeof(BatchRay)), rays.empty() ? nullptr : rays.data(), GL_STATIC_DRAW);
  glNamedBufferData(resultBuffer_, n * GLsizeiptr(sizeof(glm::uvec4)), nullptr, GL_STREAM_READ);
  const GLsizeiptr perRay = options_.twoLevel ? 2 : 1;  // two-level: BLAS and TLAS counters
  glNamedBufferData(countBuffer_, perRay * n * GLsizeiptr(sizeof(glm::uvec4)), nullptr, GL_STREAM_READ);
  tMax_.resize(rays.size());
  for (size_t i = 0; i < rays.size(); ++i) tMax_[i] = rays[i].tMax;
  checkGl("uploading the rays");
}

void GlRayTracer::issue(unsigned program) {
  glUseProgram(program);
  glUniform1i(glGetUniformLocation(program, "u_count"), GLint(count_));
  if (options_.storage == Storage::Ssbo)
    bindBvhStorageBuffers(streamBuffers_);
  else
    for (GLuint unit = 0; unit < 4; ++unit) glBindTextureUnit(unit, streams_[unit]);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, rayBuffer_);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, resultBuffer_);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, countBuffer_);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, rayCounter_);
  dispatchOnce();
}

void GlRayTracer::dispatchOnce() {
  if (persistent_) {
    // The counter the previous dispatch advanced goes back to 0 once that dispatch is done with it.
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
    const GLuint zero = 0;
    glClearNamedBufferData(rayCounter_, GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
  }
  glDispatchCompute(groups(), 1, 1);
}

unsigned GlRayTracer::groups() const {
  const unsigned all = unsigned((count_ + kLocalSize - 1) / kLocalSize);
  return persistent_ ? std::min(all, kPersistentGroups) : all;
}

double GlRayTracer::dispatch(unsigned program) {
  const auto start = std::chrono::steady_clock::now();
  issue(program);
  glFinish();
  checkGl("ray dispatch");
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

double GlRayTracer::trace(int dispatches) {
  if (dispatches <= 1) return dispatch(timed_);
  dispatch(timed_);  // untimed: the GPU busy (clocks up) when the timed ones start
  const auto start = std::chrono::steady_clock::now();
  issue(timed_);  // binds the program and buffers once; the others only dispatch again
  for (int k = 1; k < dispatches; ++k) {
    // Each dispatch writes the same result buffer: the barrier orders them, so the time is the sum
    // of whole dispatches, not of overlapping ones.
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    dispatchOnce();
  }
  glFinish();
  checkGl("ray dispatches");
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count() / dispatches;
}

std::vector<BatchHit> GlRayTracer::results() const {
  std::vector<glm::uvec4> raw(count_);
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  if (count_) glGetNamedBufferSubData(resultBuffer_, 0, GLsizeiptr(count_ * sizeof(glm::uvec4)), raw.data());
  checkGl("reading the ray results");
  return decode(raw, options_.anyHit, tMax_);
}

std::vector<glm::uvec4> GlRayTracer::traceCounted(std::vector<BatchHit>* hits, std::vector<glm::uvec4>* tlas) {
  dispatch(counted_);
  const size_t perRay = options_.twoLevel ? 2 : 1;
  std::vector<glm::uvec4> raw(perRay * count_);
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  if (count_) glGetNamedBufferSubData(countBuffer_, 0, GLsizeiptr(raw.size() * sizeof(glm::uvec4)), raw.data());
  checkGl("reading the ray counters");
  if (hits) *hits = results();
  if (perRay == 1) return raw;
  std::vector<glm::uvec4> counts(count_);
  if (tlas) tlas->resize(count_);
  for (size_t i = 0; i < count_; ++i) {
    counts[i] = raw[2 * i];
    if (tlas) (*tlas)[i] = raw[2 * i + 1];
  }
  return counts;
}

std::vector<uint32_t> GlRayTracer::instances() const {
  std::vector<glm::uvec4> raw(count_);
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  if (count_) glGetNamedBufferSubData(resultBuffer_, 0, GLsizeiptr(count_ * sizeof(glm::uvec4)), raw.data());
  checkGl("reading the ray results");
  std::vector<uint32_t> ids(count_);
  for (size_t i = 0; i < count_; ++i) ids[i] = raw[i].w;
  return ids;
}

}  // namespace bvhlab
