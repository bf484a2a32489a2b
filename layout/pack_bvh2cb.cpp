// packBvh2cb: any builder's Bvh -> layout bvh2-cb (layout/layout_bvh2cb.hpp). It goes through v1's
// packer: that checks the tree, orders it depth-first and writes the TRIANGLE and ATTRIBUTE streams,
// which bvh2-cb keeps as they are; each v1 inner node then becomes one record holding its children.
#include <bit>
#include <stdexcept>
#include <string>
#include <utility>

#include "layout/layout_bvh2cb.hpp"

namespace bvhlab {

namespace {

uint32_t bits(float f) { return std::bit_cast<uint32_t>(f); }
glm::vec3 floats(const glm::uvec4& t) {
  return {std::bit_cast<float>(t.x), std::bit_cast<float>(t.y), std::bit_cast<float>(t.z)};
}

void pushSlot(std::vector<glm::uvec4>& out, const Bvh2cbSlot& s) {
  out.push_back({bits(s.bmin.x), bits(s.bmin.y), bits(s.bmin.z), s.link});
  out.push_back({bits(s.bmax.x), bits(s.bmax.y), bits(s.bmax.z), s.count});
}

}  // namespace

PackedBvh packBvh2cb(const Bvh& bvh, const TriangleSoup& soup) {
  PackedBvh v1 = packBvh(bvh, soup);
  const uint32_t nodeCount = uint32_t(v1.nodes.size() / kNodeTexels);
  // Record index of each v1 inner node: v1 is in pre-order, so counting inner nodes in stream order
  // gives the inner nodes' pre-order (and a child A that is inner gets its parent's record + 1).
  std::vector<uint32_t> record(nodeCount, kBvh2cbInner);
  uint32_t records = 0;
  for (uint32_t i = 0; i < nodeCount; ++i)
    if (!unpackNode(v1, i).isLeaf()) record[i] = records++;
  const auto slot = [&](uint32_t node) {
    const NodeRecord r = unpackNode(v1, node);
    return r.isLeaf() ? Bvh2cbSlot{r.bmin, r.bmax, r.a, r.count} : Bvh2cbSlot{r.bmin, r.bmax, record[node], kBvh2cbInner};
  };

  PackedBvh out;
  out.layout = kLayoutBvh2cb;
  out.depth = v1.depth;
  if (records == 0) {  // the root is a leaf: A = that leaf, B = an empty slot over the same box
    const Bvh2cbSlot a = slot(0);
    out.nodes.reserve(kBvh2cbRecordTexels);
    pushSlot(out.nodes, a);
    pushSlot(out.nodes, Bvh2cbSlot{a.bmin, a.bmax, a.link, 0u});
  } else {
    out.nodes.reserve(size_t(kBvh2cbRecordTexels) * records);
    for (uint32_t i = 0; i < nodeCount; ++i) {
      const NodeRecord r = unpackNode(v1, i);
      if (r.isLeaf()) continue;
      pushSlot(out.nodes, slot(i + 1));  // child A is adjacent in v1's order
      pushSlot(out.nodes, slot(r.a));
    }
  }
  out.triangles = std::move(v1.triangles);
  out.attributes = std::move(v1.attributes);
  return out;
}

uint32_t bvh2cbRecordCount(const PackedBvh& packed) { return uint32_t(packed.nodes.size() / kBvh2cbRecordTexels); }

Bvh2cbRecord unpackBvh2cbRecord(const PackedBvh& packed, uint32_t index) {
  if (packed.layout != kLayoutBvh2cb)
    throw std::invalid_argument("unpackBvh2cbRecord decodes layout bvh2-cb; this tree is packed in layout '" +
                                packed.layout + "'");
  if (index >= bvh2cbRecordCount(packed))
    throw std::out_of_range("unpackBvh2cbRecord: record " + std::to_string(index) + " of " +
                            std::to_string(bvh2cbRecordCount(packed)));
  Bvh2cbRecord r;
  for (int c = 0; c < 2; ++c) {
    const glm::uvec4 lo = packed.nodes[size_t(kBvh2cbRecordTexels) * index + 2 * c + 0];
    const glm::uvec4 hi = packed.nodes[size_t(kBvh2cbRecordTexels) * index + 2 * c + 1];
    r.child[c] = Bvh2cbSlot{floats(lo), floats(hi), lo.w, hi.w};
  }
  return r;
}

}  // namespace bvhlab
