// Tree rotations during a refit (Kopta, Ize, Spjut, Brunvand, Davis & Kensler, "Fast, Effective BVH
// Updates for Animated Scenes", I3D 2012): while the boxes are recomputed bottom-up, each inner node
// tries to swap subtrees among its children and grandchildren and keeps the swap that lowers the SAH
// most, so a refit tree whose primitives drift apart regains part of what a rebuild would give, at a
// refit's cost.
//
// At an inner node N with children L, R and grandchildren LL, LR (of L) and RL, RR (of R), six swaps
// are tried (each needs the grandchildren it names):
//   child with grandchild:       L <-> RL, L <-> RR, R <-> LL, R <-> LR
//   grandchild with grandchild:  LL <-> RL, LL <-> RR (LR <-> RR and LR <-> RL give the same trees)
// A swap keeps every node and every leaf (and the leaves' primitive ranges) and only changes which
// node is whose child: N's box stays the same (its subtree holds the same leaves), the boxes below
// the swapped subtrees stay the same, and only the box of the child (or the two children) that
// received a new subtree changes; it is recomputed as the exact union of its new children. The SAH
// (builders/bvh.hpp sahCost) therefore changes by Ct x (the change of those one or two inner nodes'
// half areas) / the root's half area, and that change is all a swap is judged by.
//
// A swap is taken only when it lowers the summed half area of the changed nodes, compared exactly
// (the sums of two floats are compared through their exact double-double values, not rounded): a
// rotation never raises the SAH. With Ct = 0 no swap can lower the SAH and none is made.
#pragma once
#include <cstdint>

#include "builders/bvh.hpp"
#include "builders/refit.hpp"

namespace bvhlab {

enum class Rotation : uint8_t {
  None,
  LeftWithRightLeft,
  LeftWithRightRight,
  RightWithLeftLeft,
  RightWithLeftRight,
  LeftLeftWithRightLeft,
  LeftLeftWithRightRight,
};
const char* rotationName(Rotation rotation);

// The swap at inner node `node` that lowers the summed half area of the nodes it changes most
// (the first of the list above on a tie), or None when no swap lowers it. Reads the boxes of the
// node's children and grandchildren as they are (refit them first). A leaf gives None.
Rotation bestRotation(const Bvh& bvh, uint32_t node);

// Applies `rotation` at `node`: relinks the nodes and recomputes the changed child boxes as the
// union of their new children. Throws std::invalid_argument when the node lacks the grandchildren the
// rotation names.
void applyRotation(Bvh& bvh, uint32_t node, Rotation rotation);

// Refits the tree to `frame` (builders/refit.hpp) and, at each inner node once its subtree is refit,
// applies bestRotation when cost.traversalCost > 0. Returns the number of rotations made. One thread
// (the result is the same on every machine). Throws as refitBvh does.
uint32_t refitRotateBvh(Bvh& bvh, const FrameTriangles& frame, const CostModel& cost);

}  // namespace bvhlab
