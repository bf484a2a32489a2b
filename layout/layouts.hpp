// The layout registry: every texture layout a tree can be packed into, as an experimental axis
// (`--layout` on render, trace, build; `bvhlab layouts`). Each layout is described in its own header
// (v1: layout/layout.hpp; bvh2-cb: layout/layout_bvh2cb.hpp); this table names it, packs it and
// says which GLSL modules decode it. Which kernels run on it: traversal/kernels.hpp (kernelsFor),
// whose KernelInfo::layout names the layout each kernel walks.
#pragma once
#include <string>
#include <vector>

#include "layout/layout.hpp"

namespace bvhlab {

using PackFn = PackedBvh (*)(const Bvh& bvh, const TriangleSoup& soup);

struct LayoutInfo {
  std::string name;         // "v1", "bvh2-cb"
  std::string description;  // one line for `bvhlab layouts`
  PackFn pack;              // sets PackedBvh::layout to `name`
  // The GLSL accessor modules, in assembly order after the storage module (they need its fetchNode):
  // the node decoder(s) this layout's kernels call. The triangle accessors (testTriangle,
  // loadTriangle, loadTriangleIds, loadAttributes) come from the triangle format's module
  // (layout/triangle_formats.hpp), whatever the layout.
  std::vector<std::string> glslModules;
  std::string defaultKernel;  // what `--kernel` means when not given
};

constexpr const char* kDefaultLayout = "v1";

const std::vector<LayoutInfo>& layouts();
// Throws std::invalid_argument naming the valid layouts when `name` is unknown.
const LayoutInfo& findLayout(const std::string& name);

}  // namespace bvhlab
