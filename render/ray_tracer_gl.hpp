// A GLSL traversal kernel tracing a buffer of rays (`bvhlab trace`): the packed BVH uploaded in the
// chosen storage kind, the rays in a shader storage buffer, one compute invocation per ray
// (shaders/trace_rays.glsl), results read back. Needs a current GL context for its whole life.
#pragma once
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "layout/layout.hpp"
#include "shaders/assemble.hpp"
#include "traversal/ray_batch.hpp"

namespace bvhlab {

struct RayTracerOptions {
  std::string kernel = "stack-ordered";  // must walk the packed tree's layout ("" = that layout's default)
  Storage storage = Storage::Tbo;
  Robustness robust = Robustness::Watertight;
  bool anyHit = false;  // traceAny instead of traceClosest
  // The tree is a two-level one (layout/pack_two_level.hpp): the kernel's two-level walk
  // (traversal/two_level.glsl); answers carry instance ids and the counters split TLAS and BLAS.
  bool twoLevel = false;
};

class GlRayTracer {
 public:
  // Compiles the timed program (no counters) and the counting one over the accessors of the tree's
  // layout (PackedBvh::layout); uploads the tree. A kernel of another layout is refused
  // (std::invalid_argument naming the layout's kernels).
  GlRayTracer(const PackedBvh& packed, const RayTracerOptions& options);
  ~GlRayTracer();
  GlRayTracer(const GlRayTracer&) = delete;
  GlRayTracer& operator=(const GlRayTracer&) = delete;

  void setRays(const std::vector<BatchRay>& rays);
  // Replaces the tree's streams with `packed`'s (an animated clip's next frame): the old buffers and
  // textures are deleted and the new ones uploaded as the constructor does. The programs stay: the
  // tree must have the constructor's layout and triangle format and need no deeper stack than
  // stackSize() (std::invalid_argument otherwise; build a new tracer then). Not waited for.
  void setTree(const PackedBvh& packed);
  // Binds streams already on the GPU instead (an animated clip's tree built and packed there,
  // render/gpu_clip_build.hpp): `buffers` are the node, triangle and attribute storage buffers of uvec4
  // texels, holding at least `shape`'s streams (its layout, triangle format, depth and texel counts
  // are the buffers' tree's; its vertex stream, empty for raw triangles, is uploaded). The buffers stay
  // the caller's, and must live while this tracer uses them. With Storage::Tbo they are viewed as
  // texture buffers (shape's sizes), with Ssbo bound as they are; Tex2d would need a copy and is
  // refused (std::invalid_argument), as is a tree needing another program (as setTree). A memory
  // barrier makes the passes' writes visible to the traces.
  void setTreeBuffers(const PackedBvh& shape, const unsigned buffers[3]);
  int stackSize() const { return stack_; }
  // Whether the programs run trace_rays.glsl's persistent-threads loop (persistentThreadsOn).
  bool persistentThreads() const { return persistent_; }
  // One dispatch over every ray, waited for (glFinish); returns wall-clock ms. With dispatches > 1
  // (a GPU, where one dispatch is shorter than its clock's ramp-up and glFinish's round trip): one
  // untimed dispatch waited for, then `dispatches` back to back (a barrier between, so they do not
  // overlap) waited for once; returns the wall-clock ms per dispatch.
  double trace(int dispatches = 1);
  // The last trace()'s answers (prim = original triangle id).
  std::vector<BatchHit> results() const;
  // Traces once more with the counters compiled in: per ray (node visits, triangle tests, stack
  // overflow, box tests); `hits` gets that run's answers.
  // Over a two-level tree the per-ray counters are the BLAS walks' (summed over the instances a ray
  // enters) and `tlas` gets the TLAS walk's: (node visits, instance tests, 0, box tests).
  std::vector<glm::uvec4> traceCounted(std::vector<BatchHit>* hits = nullptr, std::vector<glm::uvec4>* tlas = nullptr);
  // Over a two-level tree: the instance id of each ray's last answer (0 for a miss or any hit);
  // BatchHit::prim is then the instance's own triangle id.
  std::vector<uint32_t> instances() const;

 private:
  void issue(unsigned program);  // binds the program and buffers, dispatches (not waited for)
  void dispatchOnce();           // one dispatch of the bound program (the ray counter zeroed first)
  unsigned groups() const;       // work groups of one dispatch
  double dispatch(unsigned program);
  void upload(const PackedBvh& packed);
  void checkSameProgram(const PackedBvh& packed, const char* what) const;
  void releaseStreams();  // the textures, the vertex buffer, and the others unless borrowed
  RayTracerOptions options_;
  std::string layout_, triangleFormat_;
  int stack_ = 0;
  unsigned timed_ = 0, counted_ = 0;
  unsigned streams_[4] = {0, 0, 0, 0}, streamBuffers_[4] = {0, 0, 0, 0};  // node, triangle, attribute, vertex
  bool borrowed_ = false;  // streamBuffers_[0..2] are the caller's (setTreeBuffers)
  unsigned rayBuffer_ = 0, resultBuffer_ = 0, countBuffer_ = 0;
  bool persistent_ = false;      // persistentThreadsOn(the kernel) (traversal/kernels.hpp)
  unsigned rayCounter_ = 0;      // trace_rays.glsl's nextRay (persistent threads)
  size_t count_ = 0;
  std::vector<float> tMax_;  // per ray, for any-hit answers
};

}  // namespace bvhlab
