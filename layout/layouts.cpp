#include "layout/layouts.hpp"

#include <stdexcept>

#include "layout/layout_bvh2cb.hpp"
#include "layout/layout_cwbvh.hpp"
#include "layout/layout_wide.hpp"

namespace bvhlab {

const std::vector<LayoutInfo>& layouts() {
  static const std::vector<LayoutInfo> table = {
      {"v1", "binary, 32-byte node (own box + child/escape links), depth-first (the reference)",
       packBvh, {"layout.glsl"}, "stack-ordered"},
      // Every layout leaves the triangle streams to the triangle format (layout/triangle_formats.hpp),
      // whose module the assembler adds; the others take layout.glsl's constants (whose v1 loadNode
      // their kernels never call) and add their node decoder.
      {"bvh2-cb", "binary, 64-byte node holding both child boxes (Aila-Laine 2009), leaves in the parent",
       packBvh2cb, {"layout.glsl", "layout_bvh2cb.glsl"}, "bvh2cb-stack-ordered"},
      {"bvh4", "4-wide, SAH-optimal collapse (Ylitie et al. 2017), 32-byte child slots, leaves in the parent",
       packBvh4, {"layout.glsl", "layout_wide.glsl"}, "bvh4-stack-ordered"},
      {"bvh8", "8-wide, SAH-optimal collapse (Ylitie et al. 2017), 32-byte child slots, leaves in the parent",
       packBvh8, {"layout.glsl", "layout_wide.glsl"}, "bvh8-stack-ordered"},
      {"cwbvh", "8-wide compressed node (Ylitie et al. 2017): 80 bytes, child boxes quantised to 8 bits on the node's grid",
       packCwbvh, {"layout.glsl", "layout_cwbvh.glsl"}, "cwbvh-stack-ordered"},
  };
  return table;
}

const LayoutInfo& findLayout(const std::string& name) {
  for (const LayoutInfo& l : layouts())
    if (l.name == name) return l;
  std::string msg = "unknown layout '" + name + "'; valid layouts:";
  for (const LayoutInfo& l : layouts()) msg += " " + l.name;
  throw std::invalid_argument(msg);
}

}  // namespace bvhlab
