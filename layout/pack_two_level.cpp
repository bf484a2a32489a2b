// packTwoLevel / repackTopLevel: BLASes and instances -> the streams of layout/pack_two_level.hpp.
#include "layout/pack_two_level.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "builders/builder.hpp"
#include "layout/layout_bvh2cb.hpp"
#include "layout/layouts.hpp"

namespace bvhlab {

namespace {

uint32_t bits(float f) { return std::bit_cast<uint32_t>(f); }

// Texels of one node (v1) or record (bvh2-cb): the unit of the layout's node links.
uint32_t nodeTexels(const std::string& layout) { return layout == kLayoutBvh2cb ? kBvh2cbRecordTexels : kNodeTexels; }

void checkIndex(uint64_t index, const char* what) {
  if (index >= kEscapeEnd)
    throw std::runtime_error(std::string("packTwoLevel: ") + what + " " + std::to_string(index) +
                             " exceeds the layout's limit of " + std::to_string(kEscapeEnd - 1));
}

// Appends `nodes` (one tree's node stream in `layout`) to `out`, links rebased: node links by
// nodeOffset, leaf triangle links by firstPrimitive.
void appendRebased(std::vector<glm::uvec4>& out, const std::vector<glm::uvec4>& nodes, const std::string& layout,
                   uint64_t nodeOffset, uint64_t firstPrimitive) {
  const size_t begin = out.size();
  out.insert(out.end(), nodes.begin(), nodes.end());
  if (layout == kLayoutBvh2cb) {
    for (size_t slot = begin; slot < out.size(); slot += 2) {  // a slot = (bmin, link), (bmax, count)
      const uint64_t link = uint64_t(out[slot].w) + (out[slot + 1].w == kBvh2cbInner ? nodeOffset : firstPrimitive);
      checkIndex(link, "link");
      out[slot].w = uint32_t(link);
    }
    return;
  }
  for (size_t texel = begin; texel < out.size(); texel += kNodeTexels) {
    glm::uvec4& lo = out[texel];
    glm::uvec4& hi = out[texel + 1];
    const uint32_t count = (lo.w >> 28) | ((hi.w >> 28) << 4);
    const uint64_t a = uint64_t(lo.w & kIndexMask) + (count == 0 ? nodeOffset : firstPrimitive);
    checkIndex(a, count == 0 ? "child node" : "first triangle");
    lo.w = uint32_t(a) | (lo.w & ~kIndexMask);
    const uint32_t escape = hi.w & kIndexMask;
    if (escape != kEscapeEnd) {
      checkIndex(uint64_t(escape) + nodeOffset, "escape node");
      hi.w = uint32_t(escape + nodeOffset) | (hi.w & ~kIndexMask);
    }
  }
}

Aabb rootBox(const PackedBvh& blas) {
  if (blas.layout == kLayoutBvh2cb) {
    const Bvh2cbRecord r = unpackBvh2cbRecord(blas, 0);
    Aabb box{r.child[0].bmin, r.child[0].bmax};
    box.grow(Aabb{r.child[1].bmin, r.child[1].bmax});
    return box;
  }
  const NodeRecord r = unpackNode(blas, 0);
  return Aabb{r.bmin, r.bmax};
}

glm::uvec4 row(const glm::mat4x3& m, int i) {
  return {bits(m[0][i]), bits(m[1][i]), bits(m[2][i]), bits(m[3][i])};
}

// The INSTANCES and TLAS regions (and the header's TLAS root), appended from dynamicTexelBegin.
void appendTopLevel(PackedTwoLevel& p, const std::vector<Instance>& instances, const TopLevelBuild& top) {
  if (instances.empty()) throw std::invalid_argument("packTwoLevel: no instances");
  const std::string& layout = p.streams.layout;
  std::vector<Aabb> boxes;
  std::vector<glm::vec3> centroids;
  std::vector<glm::mat4x3> inverses;
  for (size_t i = 0; i < instances.size(); ++i) {
    const Instance& inst = instances[i];
    if (inst.blas >= p.blasRoot.size())
      throw std::invalid_argument("packTwoLevel: instance " + std::to_string(i) + " names BLAS " +
                                  std::to_string(inst.blas) + " of " + std::to_string(p.blasRoot.size()));
    try {
      inverses.push_back(inverseAffine(inst.objectToWorld));
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("packTwoLevel: instance " + std::to_string(i) + ": " + e.what());
    }
    boxes.push_back(transformBox(p.blasBox[inst.blas], inst.objectToWorld));
    centroids.push_back(boxes.back().center());
  }
  p.tlas = buildBvh(top.builder, BuildInput{boxes, centroids}, top.options);
  const Bvh& tlas = p.tlas;
  // The layout's packer wants triangles: one placeholder per instance. Its TRIANGLE stream is dropped;
  // texel 3j.w of it names the instance at leaf-order position j.
  TriangleSoup placeholders;
  const size_t n = instances.size();
  placeholders.v0.assign(n, glm::vec3(0.0f));
  placeholders.v1 = placeholders.v2 = placeholders.n0 = placeholders.n1 = placeholders.n2 = placeholders.v0;
  placeholders.uv0.assign(n, glm::vec2(0.0f));
  placeholders.uv1 = placeholders.uv2 = placeholders.uv0;
  placeholders.material.assign(n, 0u);
  placeholders.mesh.assign(n, 0u);
  const PackedBvh packedTlas = findLayout(layout).pack(tlas, placeholders);

  std::vector<glm::uvec4>& nodes = p.streams.nodes;
  nodes.resize(p.dynamicTexelBegin);
  const size_t references = packedTlas.triangles.size() / kTriangleTexels;
  p.recordInstance.clear();
  for (size_t j = 0; j < references; ++j) {
    const uint32_t id = packedTlas.triangles[kTriangleTexels * j].w;
    const Instance& inst = instances[id];
    const glm::mat4x3& toWorld = inst.objectToWorld;
    const glm::mat4x3& toObject = inverses[id];
    for (int i = 0; i < 3; ++i) nodes.push_back(row(toObject, i));
    for (int i = 0; i < 3; ++i) nodes.push_back(row(toWorld, i));
    nodes.push_back({bits(toWorld[3].x), bits(toWorld[3].y), bits(toWorld[3].z), p.blasRoot[inst.blas]});
    nodes.push_back({id, inst.blas, p.blasFirstTriangle[inst.blas], inst.material});
    p.recordInstance.push_back(id);
  }
  const uint32_t units = nodeTexels(layout);
  const uint64_t tlasRoot = nodes.size() / units;
  appendRebased(nodes, packedTlas.nodes, layout, tlasRoot, p.firstRecord());
  checkIndex(nodes.size() / units, "node count");
  p.tlasRoot = uint32_t(tlasRoot);
  p.tlasDepth = packedTlas.depth;
  p.streams.depth = std::max(p.tlasDepth, p.blasDepth);
  nodes[0] = {p.tlasRoot, uint32_t(n), uint32_t(p.blasRoot.size()), kTwoLevelVersion};
}

}  // namespace

bool twoLevelLayoutSupported(const std::string& layout) { return layout == "v1" || layout == kLayoutBvh2cb; }

glm::mat4x3 inverseAffine(const glm::mat4x3& m) {
  const glm::dmat3 linear{glm::dvec3(m[0]), glm::dvec3(m[1]), glm::dvec3(m[2])};
  const double det = glm::determinant(linear);
  // A zero or non-finite determinant: no inverse (NaN compares false, so it is refused here too).
  if (!(std::isfinite(det) && det != 0.0)) throw std::invalid_argument("the transform's linear part is singular");
  const glm::dmat3 inv = glm::inverse(linear);
  const glm::dvec3 t = -(inv * glm::dvec3(m[3]));
  glm::mat4x3 out;
  for (int c = 0; c < 3; ++c) out[c] = glm::vec3(inv[c]);
  out[3] = glm::vec3(t);
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 3; ++r)
      if (!std::isfinite(out[c][r])) throw std::invalid_argument("the transform's inverse is not finite in float");
  return out;
}

Aabb transformBox(const Aabb& objectBox, const glm::mat4x3& m) {
  glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
  for (int corner = 0; corner < 8; ++corner) {
    const glm::dvec3 c((corner & 1) ? objectBox.max.x : objectBox.min.x, (corner & 2) ? objectBox.max.y : objectBox.min.y,
                       (corner & 4) ? objectBox.max.z : objectBox.min.z);
    const glm::dvec3 w = glm::dmat3(glm::dvec3(m[0]), glm::dvec3(m[1]), glm::dvec3(m[2])) * c + glm::dvec3(m[3]);
    lo = glm::min(lo, w);
    hi = glm::max(hi, w);
  }
  Aabb box;
  for (int k = 0; k < 3; ++k) {
    float a = float(lo[k]), b = float(hi[k]);
    if (double(a) > lo[k]) a = std::nextafter(a, -std::numeric_limits<float>::infinity());
    if (double(b) < hi[k]) b = std::nextafter(b, std::numeric_limits<float>::infinity());
    box.min[k] = a;
    box.max[k] = b;
  }
  return box;
}

PackedTwoLevel packTwoLevel(const std::vector<PackedBvh>& blases, const std::vector<Instance>& instances,
                            const TopLevelBuild& top) {
  PackedTwoLevel p = packBottomLevel(blases);
  appendTopLevel(p, instances, top);
  return p;
}

PackedTwoLevel packBottomLevel(const std::vector<PackedBvh>& blases) {
  if (blases.empty()) throw std::invalid_argument("packTwoLevel: no BLASes");
  const std::string& layout = blases.front().layout;
  if (!twoLevelLayoutSupported(layout))
    throw std::invalid_argument("packTwoLevel: layout '" + layout + "' has no two-level walk (layouts: v1, bvh2-cb)");
  PackedTwoLevel p;
  p.streams.layout = layout;
  p.streams.nodes.assign(kTwoLevelHeaderTexels, glm::uvec4(0u));
  const uint32_t units = nodeTexels(layout);
  for (size_t b = 0; b < blases.size(); ++b) {
    const PackedBvh& blas = blases[b];
    if (blas.layout != layout)
      throw std::invalid_argument("packTwoLevel: BLAS " + std::to_string(b) + " is in layout '" + blas.layout +
                                  "', BLAS 0 in '" + layout + "'");
    if (blas.triangleFormat != "raw" || !blas.vertices.empty())
      throw std::invalid_argument("packTwoLevel: BLAS " + std::to_string(b) + " is in triangle format '" +
                                  blas.triangleFormat + "'; two-level trees take raw triangles");
    const uint64_t root = p.streams.nodes.size() / units;
    const uint64_t firstTriangle = p.streams.triangles.size() / kTriangleTexels;
    checkIndex(firstTriangle + blas.triangles.size() / kTriangleTexels, "triangle count");
    appendRebased(p.streams.nodes, blas.nodes, layout, root, firstTriangle);
    p.streams.triangles.insert(p.streams.triangles.end(), blas.triangles.begin(), blas.triangles.end());
    p.streams.attributes.insert(p.streams.attributes.end(), blas.attributes.begin(), blas.attributes.end());
    p.blasRoot.push_back(uint32_t(root));
    p.blasFirstTriangle.push_back(uint32_t(firstTriangle));
    p.blasBox.push_back(rootBox(blas));
    p.blasDepth = std::max(p.blasDepth, blas.depth);
  }
  // Records are 8-texel aligned: record r at texels 8r .. 8r + 7.
  const size_t padded = (p.streams.nodes.size() + kInstanceTexels - 1) / kInstanceTexels * kInstanceTexels;
  p.streams.nodes.resize(padded, glm::uvec4(0u));
  p.dynamicTexelBegin = padded;
  return p;
}

void repackTopLevel(PackedTwoLevel& packed, const std::vector<Instance>& instances, const TopLevelBuild& top) {
  appendTopLevel(packed, instances, top);
}

}  // namespace bvhlab
