// The GPU pack's host side (builders/gpu/gpu_pack.hpp).
#include "builders/gpu/gpu_pack.hpp"

#include <algorithm>
#include <bit>
#include <stdexcept>
#include <vector>

#include "builders/gpu/gpu_build_steps.hpp"
#include "builders/gpu/gpu_pack_wide.hpp"
#include "layout/layout_bvh2cb.hpp"
#include "layout/layout_cwbvh.hpp"
#include "render/gl_context.hpp"

namespace bvhlab::gpubuild {

namespace {

// gpubuild_pack_*.glsl's PackState as it lies in the buffer (std430: uvec3, then uints).
struct PackState {
  uint32_t groups = 0, one_y = 1, one_z = 1;  // the indirect dispatch of the next jumping round
  uint32_t unfinished = 0, finalHalf = 0, depth = 0;
};
static_assert(sizeof(PackState) == 24);

uint32_t bits(float f) { return std::bit_cast<uint32_t>(f); }

}  // namespace

std::vector<glm::uvec4> soupTexels(const TriangleSoup& soup) {
  std::vector<glm::uvec4> t;
  t.reserve(7 * soup.size());
  for (size_t p = 0; p < soup.size(); ++p) {
    t.push_back({bits(soup.v0[p].x), bits(soup.v0[p].y), bits(soup.v0[p].z), uint32_t(p)});
    t.push_back({bits(soup.v1[p].x), bits(soup.v1[p].y), bits(soup.v1[p].z), soup.material[p]});
    t.push_back({bits(soup.v2[p].x), bits(soup.v2[p].y), bits(soup.v2[p].z), soup.mesh[p]});
    t.push_back({bits(soup.n0[p].x), bits(soup.n0[p].y), bits(soup.n0[p].z), bits(soup.uv0[p].x)});
    t.push_back({bits(soup.n1[p].x), bits(soup.n1[p].y), bits(soup.n1[p].z), bits(soup.uv0[p].y)});
    t.push_back({bits(soup.n2[p].x), bits(soup.n2[p].y), bits(soup.n2[p].z), bits(soup.uv1[p].x)});
    t.push_back({bits(soup.uv1[p].y), bits(soup.uv2[p].x), bits(soup.uv2[p].y), 0u});
  }
  return t;
}

GLuint uploadSoupTexels(const TriangleSoup& soup) {
  const std::vector<glm::uvec4> texels = soupTexels(soup);
  const GLuint buffer = makeStorageBuffer(texels.size() * 16, texels.data());
  checkGl("GPU pack: uploading the soup");
  return buffer;
}

void deleteStreams(GpuStreamBuffers& streams) {
  const GLuint ids[] = {streams.node, streams.triangle, streams.attribute};
  glDeleteBuffers(3, ids);
  streams = GpuStreamBuffers{};
}

bool gpuPackable(const std::string& layout) {
  return layout == "v1" || layout == kLayoutBvh2cb || layout == kLayoutCwbvh;
}

PackedBvh cpuPackFor(const Bvh& bvh, const TriangleSoup& soup, const std::string& layout) {
  if (!gpuPackable(layout)) throw std::invalid_argument("GPU pack: layout '" + layout + "' is packed on the CPU");
  return layout == "v1" ? packBvh(bvh, soup) : layout == kLayoutBvh2cb ? packBvh2cb(bvh, soup) : packCwbvh(bvh, soup);
}

void packOnTheCpu(const Bvh& bvh, const GpuPackRequest& request) {
  *request.out = cpuPackFor(bvh, *request.soup, request.layout);
  if (request.keep) {
    deleteStreams(*request.keep);
    request.keep->node = makeStorageBuffer(request.out->nodes.size() * 16, request.out->nodes.data());
    request.keep->triangle = makeStorageBuffer(request.out->triangles.size() * 16, request.out->triangles.data());
    request.keep->attribute = makeStorageBuffer(request.out->attributes.size() * 16, request.out->attributes.data());
    checkGl("GPU pack: uploading the CPU's pack of one primitive");
  }
}

GpuPacker::GpuPacker()
    : edges_("gpubuild_pack_edges.glsl"),
      jump_("gpubuild_pack_jump.glsl"),
      gate_("gpubuild_pack_gate.glsl"),
      nodesV1_("gpubuild_pack_nodes.glsl", "#define LAYOUT_V1 1\n"),
      nodesBvh2cb_("gpubuild_pack_nodes.glsl", "#define LAYOUT_BVH2CB 1\n"),
      triangles_("gpubuild_pack_triangles.glsl"),
      soupBoxes_("gpubuild_soup_boxes.glsl") {}

GpuPacker::~GpuPacker() = default;

const WidePackPrograms& GpuPacker::widePrograms() const {
  if (!wide_) wide_ = std::make_unique<WidePackPrograms>();
  return *wide_;
}

std::array<std::pair<const char*, uint64_t>, 6> GpuPacker::buffers(uint64_t n) {
  const uint64_t nodes = 2 * n - 1;
  return {{{"soup texels (pack)", n * 7 * 16},
           {"path sums (pack)", 2 * nodes * 16},
           {"ancestors (pack)", 2 * nodes * 4},
           {"node stream (pack)", 2 * nodes * 16},
           {"triangle stream (pack)", n * 3 * 16},
           {"attribute stream (pack)", n * 4 * 16}}};
}

GpuPackJob::GpuPackJob(const GpuPacker& packer, const GpuPackRequest& request, uint32_t primitives)
    : packer_(packer), request_(request), n_(primitives) {
  if (!gpuPackable(request.layout))
    throw std::invalid_argument("GPU pack: layout '" + request.layout + "' is packed on the CPU (the GPU packs v1, " +
                                kLayoutBvh2cb + " and " + kLayoutCwbvh + ")");
  if (!request.soup || !request.out || request.soup->size() != primitives)
    throw std::invalid_argument("GPU pack: the soup has " + std::to_string(request.soup ? request.soup->size() : 0) +
                                " triangles for a build of " + std::to_string(primitives) + " primitives");
  if (2 * uint64_t(primitives) - 1 >= kEscapeEnd)
    throw InputError("GPU pack: " + std::to_string(primitives) + " primitives make more nodes than layout v1's limit of " +
                     std::to_string(kEscapeEnd - 1));
  const uint64_t nodes = 2 * uint64_t(primitives) - 1;
  const bool wide = request.layout == kLayoutCwbvh;
  if (wide) {  // its buffers past the binary pack's (which the builder's checkLimits counts)
    GpuWidePack::checkLimits(primitives, queryGpuLimits());
    wide_ = std::make_unique<GpuWidePack>(primitives);
  }
  if (request.soupTexels == 0) ids_[kSoup] = uploadSoupTexels(*request.soup);
  soup_ = request.soupTexels != 0 ? request.soupTexels : ids_[kSoup];
  ids_[kSteps] = makeStorageBuffer(2 * nodes * 16);
  ids_[kAncestors] = makeStorageBuffer(2 * nodes * 4);
  PackState state;
  state.groups = groupsFor(nodes);
  ids_[kState] = makeStorageBuffer(sizeof state, &state);
  ids_[kNodeStream] = makeStorageBuffer(wide ? 5 * std::max<uint64_t>(1, primitives - 1) * 16 : 2 * nodes * 16);
  ids_[kTriangleStream] = makeStorageBuffer(uint64_t(primitives) * 3 * 16);
  ids_[kAttributeStream] = makeStorageBuffer(uint64_t(primitives) * 4 * 16);
  checkGl("GPU pack: making the buffers");
}

GpuPackJob::~GpuPackJob() {
  glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, 0);
  if (request_.keep) {  // the streams go to the caller
    deleteStreams(*request_.keep);
    *request_.keep = {ids_[kNodeStream], ids_[kTriangleStream], ids_[kAttributeStream]};
    ids_[kNodeStream] = ids_[kTriangleStream] = ids_[kAttributeStream] = 0;
  }
  glDeleteBuffers(GLsizei(ids_.size()), ids_.data());
}

void GpuPackJob::soupBoxes(GLuint boxes, GLuint centroids, PhaseStamps& stamps) const {
  const GLuint buffers[] = {soup_, boxes, centroids};
  for (GLuint slot = 0; slot < 3; ++slot) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, slot, buffers[slot]);
  packer_.soupBoxes_.set("u_count", n_);
  packer_.soupBoxes_.dispatch(groupsFor(n_), "GPU boxes: triangle boxes from the soup (gpubuild_soup_boxes.glsl)");
  stamps.mark("boxes");
}

void GpuPackJob::run(const GpuTreeBuffers& tree, PhaseStamps& stamps) {
  tree_ = tree;
  const uint32_t nodes = 2 * n_ - 1;
  auto bind = [](std::initializer_list<GLuint> buffers) {
    GLuint slot = 0;
    for (GLuint b : buffers) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, slot++, b);
  };
  bind({tree.children, tree.parents, tree.info, ids_[kSteps], ids_[kAncestors]});
  packer_.edges_.set("u_nodes", nodes);
  packer_.edges_.dispatch(groupsFor(nodes), "GPU pack edges: steps from the parents (gpubuild_pack_edges.glsl)");
  bind({ids_[kSteps], ids_[kAncestors], ids_[kState]});
  glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, ids_[kState]);
  packer_.jump_.set("u_nodes", nodes);
  for (uint32_t round = 0; round < kMaxJumpRounds; ++round) {
    packer_.jump_.set("u_from", round % 2);
    packer_.jump_.dispatchIndirect(0, "GPU pack jump: a pointer-jumping round (gpubuild_pack_jump.glsl)");
    packer_.gate_.set("u_wrote", 1 - round % 2);
    packer_.gate_.dispatch(1, "GPU pack jump: the gate (gpubuild_pack_gate.glsl)");
  }
  glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, 0);
  if (!wide_) {  // cwbvh writes its node stream in the wide passes below
    const ComputeProgram& nodesPass = request_.layout == "v1" ? packer_.nodesV1_ : packer_.nodesBvh2cb_;
    bind({tree.children, tree.nodeBoxes, tree.info, ids_[kState], ids_[kSteps], ids_[kNodeStream]});
    nodesPass.set("u_count", n_);
    nodesPass.dispatch(groupsFor(nodes), "GPU pack nodes: the node stream (gpubuild_pack_nodes.glsl)");
  }
  // The triangles in v1's leaf order: the streams themselves, or, for cwbvh, what its node pass reorders.
  bind({tree.keys, ids_[kSteps], ids_[kState], soup_, wide_ ? wide_->v1Triangles() : ids_[kTriangleStream],
        wide_ ? wide_->v1Attributes() : ids_[kAttributeStream]});
  packer_.triangles_.set("u_count", n_);
  packer_.triangles_.dispatch(groupsFor(n_), "GPU pack triangles: the triangle and attribute streams (gpubuild_pack_triangles.glsl)");
  stamps.mark("pack");
  if (wide_)
    wide_->run(packer_.widePrograms(), packer_.jump_, packer_.gate_, tree, ids_[kSteps], ids_[kState],
               ids_[kNodeStream], ids_[kTriangleStream], ids_[kAttributeStream], stamps);
}

void GpuPackJob::download() const {
  PackState state;
  glGetNamedBufferSubData(ids_[kState], 0, sizeof state, &state);
  uint32_t rootInfo[2] = {0, 0};  // the root's primitives and emitted inner nodes
  glGetNamedBufferSubData(tree_.info, 0, sizeof rootInfo, rootInfo);
  checkGl("GPU pack: reading the pack state");
  if (state.groups != 0)
    throw std::runtime_error("GPU pack: the tree is deeper than " + std::to_string(1u << kMaxJumpRounds) +
                             " levels (kMaxJumpRounds pointer-jumping rounds)");
  PackedBvh& out = *request_.out;
  out = PackedBvh{};
  out.layout = request_.layout;
  out.depth = state.depth;
  if (wide_) {
    const auto [wideNodes, depth] = wide_->nodesAndDepth();
    out.depth = depth;
    out.nodes = gpubuild::download<glm::uvec4>(ids_[kNodeStream], kCwbvhNodeTexels * size_t(wideNodes));
    out.triangles = gpubuild::download<glm::uvec4>(ids_[kTriangleStream], 3 * size_t(n_));
    out.attributes = gpubuild::download<glm::uvec4>(ids_[kAttributeStream], 4 * size_t(n_));
    checkGl("GPU pack (cwbvh): download");
    return;
  }
  const size_t texels = request_.layout == "v1" ? 2 * (1 + 2 * size_t(rootInfo[1]))
                                                 : kBvh2cbRecordTexels * std::max<size_t>(1, rootInfo[1]);
  out.nodes = gpubuild::download<glm::uvec4>(ids_[kNodeStream], texels);
  out.triangles = gpubuild::download<glm::uvec4>(ids_[kTriangleStream], 3 * size_t(n_));
  out.attributes = gpubuild::download<glm::uvec4>(ids_[kAttributeStream], 4 * size_t(n_));
  checkGl("GPU pack: download");
}

}  // namespace bvhlab::gpubuild
