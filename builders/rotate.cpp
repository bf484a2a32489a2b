// Tree rotations (builders/rotate.hpp).
#include "builders/rotate.hpp"

#include <stdexcept>
#include <string>
#include <vector>

namespace bvhlab {

const char* rotationName(Rotation rotation) {
  switch (rotation) {
    case Rotation::None: return "none";
    case Rotation::LeftWithRightLeft: return "L<->RL";
    case Rotation::LeftWithRightRight: return "L<->RR";
    case Rotation::RightWithLeftLeft: return "R<->LL";
    case Rotation::RightWithLeftRight: return "R<->LR";
    case Rotation::LeftLeftWithRightLeft: return "LL<->RL";
    case Rotation::LeftLeftWithRightRight: return "LL<->RR";
  }
  return "?";
}

namespace {

// a + b as an unevaluated pair (sum, error) with sum + error == a + b exactly (Knuth's TwoSum; a and
// b are floats, exact in double). Two such pairs order exactly as their real sums do, except that two
// sums straddling a rounding tie may compare "less" while equal: never "less" when greater.
struct ExactSum {
  double sum, error;
};
ExactSum exactSum(float a, float b) {
  const double x = a, y = b;
  const double s = x + y;
  const double bb = s - x;
  return {s, (x - (s - bb)) + (y - bb)};
}
bool less(const ExactSum& p, const ExactSum& q) { return p.sum < q.sum || (p.sum == q.sum && p.error < q.error); }

float unionArea(const Aabb& a, const Aabb& b) {
  Aabb u = a;
  u.grow(b);
  return u.halfArea();
}

}  // namespace

Rotation bestRotation(const Bvh& bvh, uint32_t index) {
  const BvhNode& n = bvh.nodes[index];
  if (n.isLeaf()) return Rotation::None;
  const BvhNode& l = bvh.nodes[n.left];
  const BvhNode& r = bvh.nodes[n.right];
  const float areaL = l.bounds.halfArea(), areaR = r.bounds.halfArea();
  // Every candidate as the exact sum of the half areas of N's two children after the swap: the only
  // boxes a swap changes are among them (a leaf child's term is the same on both sides).
  ExactSum best = exactSum(areaL, areaR);
  Rotation choice = Rotation::None;
  auto consider = [&](Rotation rotation, float a, float b) {
    const ExactSum s = exactSum(a, b);
    if (less(s, best)) best = s, choice = rotation;
  };
  if (!r.isLeaf()) {
    const Aabb &rl = bvh.nodes[r.left].bounds, &rr = bvh.nodes[r.right].bounds;
    consider(Rotation::LeftWithRightLeft, areaL, unionArea(l.bounds, rr));
    consider(Rotation::LeftWithRightRight, areaL, unionArea(rl, l.bounds));
  }
  if (!l.isLeaf()) {
    const Aabb &ll = bvh.nodes[l.left].bounds, &lr = bvh.nodes[l.right].bounds;
    consider(Rotation::RightWithLeftLeft, unionArea(r.bounds, lr), areaR);
    consider(Rotation::RightWithLeftRight, unionArea(ll, r.bounds), areaR);
  }
  if (!l.isLeaf() && !r.isLeaf()) {
    const Aabb &ll = bvh.nodes[l.left].bounds, &lr = bvh.nodes[l.right].bounds;
    const Aabb &rl = bvh.nodes[r.left].bounds, &rr = bvh.nodes[r.right].bounds;
    consider(Rotation::LeftLeftWithRightLeft, unionArea(rl, lr), unionArea(ll, rr));
    consider(Rotation::LeftLeftWithRightRight, unionArea(rr, lr), unionArea(rl, ll));
  }
  return choice;
}

void applyRotation(Bvh& bvh, uint32_t index, Rotation rotation) {
  if (rotation == Rotation::None) return;
  BvhNode& n = bvh.nodes.at(index);
  if (n.isLeaf()) throw std::invalid_argument("applyRotation: node " + std::to_string(index) + " is a leaf");
  BvhNode& l = bvh.nodes.at(n.left);
  BvhNode& r = bvh.nodes.at(n.right);
  const bool needL = rotation == Rotation::RightWithLeftLeft || rotation == Rotation::RightWithLeftRight ||
                     rotation == Rotation::LeftLeftWithRightLeft || rotation == Rotation::LeftLeftWithRightRight;
  const bool needR = rotation != Rotation::RightWithLeftLeft && rotation != Rotation::RightWithLeftRight;
  if ((needL && l.isLeaf()) || (needR && r.isLeaf()))
    throw std::invalid_argument(std::string("applyRotation: ") + rotationName(rotation) + " at node " +
                                std::to_string(index) + " names a grandchild under a leaf");
  auto refitNode = [&](BvhNode& node) {
    Aabb box = bvh.nodes[node.left].bounds;
    box.grow(bvh.nodes[node.right].bounds);
    node.bounds = box;
  };
  switch (rotation) {
    case Rotation::LeftWithRightLeft: std::swap(n.left, r.left); refitNode(r); break;
    case Rotation::LeftWithRightRight: std::swap(n.left, r.right); refitNode(r); break;
    case Rotation::RightWithLeftLeft: std::swap(n.right, l.left); refitNode(l); break;
    case Rotation::RightWithLeftRight: std::swap(n.right, l.right); refitNode(l); break;
    case Rotation::LeftLeftWithRightLeft: std::swap(l.left, r.left); refitNode(l), refitNode(r); break;
    case Rotation::LeftLeftWithRightRight: std::swap(l.left, r.right); refitNode(l), refitNode(r); break;
    case Rotation::None: break;
  }
}

uint32_t refitRotateBvh(Bvh& bvh, const FrameTriangles& frame, const CostModel& cost) {
  // The whole refit first, then the swaps, children before parents: the same tree as swapping at each
  // node as soon as it is refit, because a swap at N changes the boxes of N's children only (to the
  // union of their new children, whose boxes are final by then) and never N's box or an ancestor's
  // (each holds the same leaves). The post-order is taken before any swap: a swap at N relinks only
  // N's children and grandchildren, which come before N in the order and are not visited again, so the
  // rest of the order holds for the whole pass (the next frame takes a new order from the new topology).
  const std::vector<uint32_t> order = refitOrder(bvh);
  refitBvh(bvh, order, frame);
  if (!(cost.traversalCost > 0.0f)) return 0;
  uint32_t rotations = 0;
  for (const uint32_t node : order) {
    if (bvh.nodes[node].isLeaf()) continue;
    const Rotation rotation = bestRotation(bvh, node);
    if (rotation != Rotation::None) {
      applyRotation(bvh, node, rotation);
      ++rotations;
    }
  }
  return rotations;
}

}  // namespace bvhlab
