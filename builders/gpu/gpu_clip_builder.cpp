// GPU clip builders (builders/gpu/gpu_clip_builder.hpp).
#include "builders/gpu/gpu_clip_builder.hpp"

#include <algorithm>
#include <chrono>
#include <memory>
#include <vector>

#include "builders/builder.hpp"
#include "builders/gpu/gpu_builders.hpp"  // makeGpuBuilder
#include "builders/gpu/gpu_lbvh.hpp"      // GpuPhaseTimes
#include "builders/gpu/gpu_pack.hpp"
#include "builders/refit.hpp"  // checkFiniteVertices
#include "render/gl_context.hpp"

namespace bvhlab {

namespace {

class ResidentClipBuilder final : public GpuClipBuilder {
 public:
  ResidentClipBuilder(const std::string& builder, const BuildOptions& options, const std::string& layout)
      : builder_(builder), options_(options), layout_(layout) {}
  ~ResidentClipBuilder() override {
    glDeleteBuffers(1, &soup_);
    gpubuild::deleteStreams(streams_);
  }

  GpuClipFrame build(const TriangleSoup& soup) override {
    // Checked on the CPU, untimed, as the CPU strategies check a frame (builders/update_base.cpp): a
    // non-finite vertex is an InputError naming its triangle, and no NaN reaches the GPU's comparisons.
    checkFiniteVertices(FrameTriangles{soup.v0, soup.v1, soup.v2});
    const std::vector<Aabb> boxes = triangleBoxes(soup);
    const std::vector<glm::vec3> centroids = triangleCentroids(soup);
    const BuildInput input{boxes, centroids, soup.v0, soup.v1, soup.v2};
    validateBuildInput(input, options_);
    if (!gpuBuilder_) gpuBuilder_ = gpubuild::makeGpuBuilder(builder_);  // compiled in the first build's context
    gpuBuilder_->checkLimits(soup.size(), true);
    // The texels are laid out on the CPU untimed (a renderer's animation would write them on the GPU);
    // their upload is timed.
    const std::vector<glm::uvec4> texels = gpubuild::soupTexels(soup);
    const GLsizeiptr bytes = GLsizeiptr(texels.size() * sizeof(glm::uvec4));
    GpuClipFrame frame;
    glFinish();
    const auto start = std::chrono::steady_clock::now();
    if (bytes != soupBytes_) {  // the first frame (every frame of a clip has the same triangles)
      glDeleteBuffers(1, &soup_);
      soup_ = gpubuild::makeStorageBuffer(uint64_t(bytes), texels.data());
      soupBytes_ = bytes;
    } else {
      glNamedBufferSubData(soup_, 0, bytes, texels.data());
    }
    glFinish();
    frame.uploadMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    checkGl("GPU clip build: uploading the frame's triangles");

    const gpubuild::GpuPackRequest request{layout_, &soup, &frame.packed, soup_, /*boxesFromSoup=*/true, &streams_};
    gpubuild::GpuPhaseTimes times;
    auto run = [&] { return gpuBuilder_->build(input, options_, &times, &request); };
    if (!warmed_) {  // the driver compiles at the first dispatch: untimed, as timeGpuBuild's warm-up
      run();
      warmed_ = true;
    }
    frame.tree = run();
    frame.buildMs = times.wallMs;
    frame.gpuMs = times.totalMs();
    frame.phases = times.phases;
    frame.streams[0] = streams_.node;
    frame.streams[1] = streams_.triangle;
    frame.streams[2] = streams_.attribute;
    return frame;
  }

 private:
  std::string builder_;
  BuildOptions options_;
  std::string layout_;
  std::unique_ptr<gpubuild::AnyGpuBuilder> gpuBuilder_;
  GLuint soup_ = 0;
  GLsizeiptr soupBytes_ = 0;
  gpubuild::GpuStreamBuffers streams_;
  bool warmed_ = false;
};

}  // namespace

std::unique_ptr<GpuClipBuilder> makeResidentClipBuilder(const std::string& builder, const BuildOptions& options,
                                                        const std::string& layout) {
  const std::vector<BuilderInfo>& all = builders();
  const bool gpu = std::any_of(all.begin(), all.end(), [&](const BuilderInfo& b) { return b.gpu && b.name == builder; });
  if (!gpu || !gpubuild::gpuPackable(layout))
    return nullptr;
  return std::make_unique<ResidentClipBuilder>(builder, options, layout);
}

}  // namespace bvhlab
