// packWide: any builder's Bvh -> layout bvh4 / bvh8 (layout/layout_wide.hpp). It goes through v1's
// packer, which checks the tree, orders it depth-first and writes the TRIANGLE and ATTRIBUTE streams
// (kept as they are); v1's nodes are read back as a binary tree whose every subtree covers one
// contiguous triangle range, collapsed (layout/collapse_wide.hpp) and written as slots and records.
#include <algorithm>
#include <bit>
#include <stdexcept>
#include <string>
#include <utility>

#include "layout/collapse_wide.hpp"
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

// v1's NODE stream as a Bvh in the same (depth-first) order: node i's children are i + 1 and a, a
// leaf's range indexes the TRIANGLE stream.
Bvh binaryFromV1(const PackedBvh& v1) {
  Bvh b;
  const uint32_t count = uint32_t(v1.nodes.size() / kNodeTexels);
  b.nodes.resize(count);
  for (uint32_t i = 0; i < count; ++i) {
    const NodeRecord r = unpackNode(v1, i);
    BvhNode& n = b.nodes[i];
    n.bounds = Aabb{r.bmin, r.bmax};
    if (r.isLeaf()) n.first = r.a, n.count = r.count;
    else n.left = i + 1, n.right = r.a;
  }
  return b;
}

}  // namespace

uint32_t wideWidth(const std::string& layout) {
  if (layout == kLayoutBvh4) return 4;
  if (layout == kLayoutBvh8) return 8;
  return 0;
}

PackedBvh packWide(const Bvh& bvh, const TriangleSoup& soup, uint32_t width) {
  if (width != 4 && width != 8) throw std::invalid_argument("packWide: width must be 4 or 8, got " + std::to_string(width));
  PackedBvh v1 = packBvh(bvh, soup);
  const Bvh binary = binaryFromV1(v1);
  const std::vector<uint32_t> refs = subtreeReferences(binary);
  // First triangle of every subtree; v1's depth-first order makes a subtree's triangles contiguous.
  std::vector<uint32_t> first(binary.nodes.size());
  uint32_t maxLeaf = 1;
  for (uint32_t i = uint32_t(binary.nodes.size()); i-- > 0;) {
    const BvhNode& n = binary.nodes[i];
    if (n.isLeaf()) {
      first[i] = n.first;
      maxLeaf = std::max(maxLeaf, n.count);
      continue;
    }
    first[i] = first[n.left];
    if (first[n.right] != first[n.left] + refs[n.left])
      throw std::runtime_error("packWide: v1's triangle stream is not in depth-first leaf order");
  }
  // Merged leaves are capped at the largest leaf the builder made (its --leaf-size, in effect): the
  // collapse trades nodes for references only within the leaf size the tree was asked for.
  const WideTree wide = collapseWide(binary, width, CostModel{}, std::min(maxLeaf, kMaxLeafSize));

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
  out.triangles = std::move(v1.triangles);
  out.attributes = std::move(v1.attributes);
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
