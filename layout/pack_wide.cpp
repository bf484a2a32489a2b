// packWide: any builder's Bvh -> layout bvh4 / bvh8 (layout/layout_wide.hpp). It goes through v1's
// packer and the collapse (layout/collapse_v1.hpp), keeps v1's TRIANGLE and ATTRIBUTE streams as they
// are, and writes the wide tree as slots and records.
#include <algorithm>
#include <bit>
#include <stdexcept>
#include <string>
#include <utility>

#include "layout/collapse_v1.hpp"
#include "layout/layout_wide.hpp"

namespace bvhlab {

namespace {

uint32_t bits(float f) { return std::bit_cast<uint32_t>(f); }
glm::vec3 floats(const glm::uvec4& t) {
  return {std::bit_cast<float>(t.x), std::bit_cast<float>(t.y), std::bit_cast<float>(t.z)};
}

void writeSlot(std::vector<glm::uvec4>& out, size_t texel, const Aabb& box, uint32_t link, uint32_t count) {
  out[texel] = {bits(box.min.x), bits(box.min.y), bits(box.min.z), link};
  out[texel + 1] = {bits(box.max.x), bits(box.max.y), bits(box.max.z), count};
}

}  // namespace

uint32_t wideWidth(const std::string& layout) {
  if (layout == kLayoutBvh4) return 4;
  if (layout == kLayoutBvh8) return 8;
  return 0;
}

PackedBvh packWide(const Bvh& bvh, const TriangleSoup& soup, uint32_t width) {
  if (width != 4 && width != 8) throw std::invalid_argument("packWide: width must be 4 or 8, got " + std::to_string(width));
  CollapsedV1 collapsed = collapseThroughV1(bvh, soup, width);
  const Bvh& binary = collapsed.binary;
  const std::vector<uint32_t>& refs = collapsed.refs;
  const std::vector<uint32_t>& first = collapsed.first;
  const WideTree& wide = collapsed.wide;

  PackedBvh out;
  out.layout = width == 4 ? kLayoutBvh4 : kLayoutBvh8;
  const Aabb rootBox = binary.nodes[0].bounds;
  if (wide.nodes.empty()) {  // the binary root is a leaf: the root slot is that leaf, no record
    out.nodes.resize(kWideSlotTexels);
    writeSlot(out.nodes, 0, rootBox, first[0], refs[0]);
    out.depth = 1;
  } else {
    // Record offsets in pre-order: the root slot, then each wide node's 2k texels.
    std::vector<uint32_t> offset(wide.nodes.size()), depth(wide.nodes.size(), 1);
    size_t texels = kWideSlotTexels;
    for (size_t i = 0; i < wide.nodes.size(); ++i) {
      if (texels > 0xFFFFFFFFu) throw std::runtime_error("packWide: more than 2^32 NODE texels");
      offset[i] = uint32_t(texels);
      texels += kWideSlotTexels * wide.nodes[i].children.size();
    }
    out.nodes.resize(texels);
    writeSlot(out.nodes, 0, rootBox, offset[0], kWideInner + uint32_t(wide.nodes[0].children.size()));
    uint32_t maxDepth = 2;
    for (size_t i = 0; i < wide.nodes.size(); ++i) {  // pre-order: a node's depth is set before its children's
      const WideNode& n = wide.nodes[i];
      for (size_t c = 0; c < n.children.size(); ++c) {
        const WideChild& ch = n.children[c];
        const size_t texel = offset[i] + kWideSlotTexels * c;
        const Aabb& box = binary.nodes[ch.binaryNode].bounds;
        if (ch.leaf) {
          writeSlot(out.nodes, texel, box, first[ch.binaryNode], refs[ch.binaryNode]);
        } else {
          writeSlot(out.nodes, texel, box, offset[ch.wideNode],
                    kWideInner + uint32_t(wide.nodes[ch.wideNode].children.size()));
          depth[ch.wideNode] = depth[i] + 1;
        }
        maxDepth = std::max(maxDepth, depth[i] + 1);
      }
    }
    out.depth = maxDepth;
  }
  out.triangles = std::move(collapsed.v1.triangles);
  out.attributes = std::move(collapsed.v1.attributes);
  return out;
}

PackedBvh packBvh4(const Bvh& bvh, const TriangleSoup& soup) { return packWide(bvh, soup, 4); }
PackedBvh packBvh8(const Bvh& bvh, const TriangleSoup& soup) { return packWide(bvh, soup, 8); }

WideSlot unpackWideSlot(const PackedBvh& packed, uint32_t texel) {
  if (wideWidth(packed.layout) == 0)
    throw std::invalid_argument("unpackWideSlot decodes layouts bvh4 and bvh8; this tree is packed in layout '" +
                                packed.layout + "'");
  if (size_t(texel) + 1 >= packed.nodes.size())
    throw std::out_of_range("unpackWideSlot: texel " + std::to_string(texel) + " of " +
                            std::to_string(packed.nodes.size()));
  const glm::uvec4 lo = packed.nodes[texel], hi = packed.nodes[size_t(texel) + 1];
  return WideSlot{floats(lo), floats(hi), lo.w, hi.w};
}

}  // namespace bvhlab
