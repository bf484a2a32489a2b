// collapseWide: the dynamic program of layout/collapse_wide.hpp, then the wide tree it chose.
#include "layout/collapse_wide.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace bvhlab {

namespace {

constexpr double kInfinite = std::numeric_limits<double>::infinity();

// What C(n, i) chose: n as one leaf, n as one inner wide node, or n's slots distributed over its
// children (`split` of the i slots to the left child, the rest to the right).
enum class Choice : uint8_t { Leaf, Internal, Distribute };

// The binary nodes in depth-first pre-order (a parent before its children), checking the tree.
std::vector<uint32_t> preOrder(const Bvh& bvh) {
  std::vector<uint32_t> order, stack{0u};
  order.reserve(bvh.nodes.size());
  while (!stack.empty()) {
    const uint32_t n = stack.back();
    stack.pop_back();
    if (n >= bvh.nodes.size() || order.size() >= bvh.nodes.size())
      throw std::runtime_error("collapseWide: malformed BVH (child index out of range or node reached twice)");
    order.push_back(n);
    if (!bvh.nodes[n].isLeaf()) {
      stack.push_back(bvh.nodes[n].right);
      stack.push_back(bvh.nodes[n].left);
    }
  }
  return order;
}

// Half areas relative to the root's. A root of zero area (every primitive in one point) makes every
// ratio meaningless; the areas are then all 0 and the program only breaks ties.
std::vector<double> relativeAreas(const Bvh& bvh) {
  const double root = bvh.nodes[0].bounds.halfArea();
  if (!std::isfinite(root)) throw std::runtime_error("collapseWide: the root box is not finite");
  std::vector<double> a(bvh.nodes.size());
  for (size_t n = 0; n < a.size(); ++n) a[n] = root > 0.0 ? bvh.nodes[n].bounds.halfArea() / root : 0.0;
  return a;
}

class Collapse {
 public:
  Collapse(const Bvh& bvh, uint32_t width, const CostModel& cost, uint32_t maxLeafSize)
      : bvh_(bvh), w_(width), area_(relativeAreas(bvh)), refs_(subtreeReferences(bvh)) {
    const size_t cells = bvh.nodes.size() * w_;
    c_.assign(cells, kInfinite);
    choice_.assign(cells, Choice::Leaf);
    split_.assign(cells, 0);
    internalCost_.assign(bvh.nodes.size(), kInfinite);
    internalSplit_.assign(bvh.nodes.size(), 1);
    const std::vector<uint32_t> order = preOrder(bvh);
    for (auto it = order.rbegin(); it != order.rend(); ++it) solve(*it, cost, maxLeafSize);  // children first
  }

  WideTree emit() {
    WideTree out;
    out.width = w_;
    if (bvh_.nodes[0].isLeaf()) {
      out.cost = c(0, 1);
      return out;
    }
    out.cost = internalCost_[0];
    emitInternal(0, out);
    return out;
  }

 private:
  // C(n, i), i = 1..W.
  double& c(uint32_t n, uint32_t i) { return c_[size_t(n) * w_ + (i - 1)]; }
  Choice& choice(uint32_t n, uint32_t i) { return choice_[size_t(n) * w_ + (i - 1)]; }
  uint8_t& split(uint32_t n, uint32_t i) { return split_[size_t(n) * w_ + (i - 1)]; }

  void solve(uint32_t n, const CostModel& cost, uint32_t maxLeafSize) {
    const BvhNode& node = bvh_.nodes[n];
    const double leafCost = (node.isLeaf() || refs_[n] <= maxLeafSize)
                                ? cost.intersectionCost * area_[n] * double(refs_[n])
                                : kInfinite;
    if (node.isLeaf()) {
      for (uint32_t i = 1; i <= w_; ++i) c(n, i) = leafCost, choice(n, i) = Choice::Leaf;
      return;
    }
    // Cdistribute(n, j) for j = 2..W, with the best split of the j slots.
    std::vector<double> dist(w_ + 1, kInfinite);
    std::vector<uint8_t> best(w_ + 1, 1);
    for (uint32_t j = 2; j <= w_; ++j)
      for (uint32_t k = 1; k < j; ++k) {
        const double d = c(node.left, k) + c(node.right, j - k);
        if (d < dist[j]) dist[j] = d, best[j] = uint8_t(k);
      }
    internalCost_[n] = cost.traversalCost * area_[n] + dist[w_];
    internalSplit_[n] = best[w_];
    // Ties go to the leaf (fewer nodes for the same cost). Costs are sums of finite non-negative terms
    // or +inf, never NaN, so these comparisons decide on numbers.
    const bool asLeaf = leafCost <= internalCost_[n];
    c(n, 1) = asLeaf ? leafCost : internalCost_[n];
    choice(n, 1) = asLeaf ? Choice::Leaf : Choice::Internal;
    for (uint32_t i = 2; i <= w_; ++i) {
      if (dist[i] < c(n, i - 1)) {
        c(n, i) = dist[i], choice(n, i) = Choice::Distribute, split(n, i) = best[i];
      } else {
        c(n, i) = c(n, i - 1), choice(n, i) = choice(n, i - 1), split(n, i) = split(n, i - 1);
      }
    }
  }

  // The children that C(n, i) puts in at most i slots, appended to `node`'s list.
  void collect(uint32_t n, uint32_t i, uint32_t parent, WideTree& out) {
    const Choice ch = choice(n, i);
    if (ch == Choice::Distribute) {
      const uint32_t k = split(n, i);
      collect(bvh_.nodes[n].left, k, parent, out);
      collect(bvh_.nodes[n].right, i - k, parent, out);
      return;
    }
    if (ch == Choice::Leaf) {
      out.nodes[parent].children.push_back({n, true, 0u});
      return;
    }
    const uint32_t child = emitInternal(n, out);
    out.nodes[parent].children.push_back({n, false, child});
  }

  uint32_t emitInternal(uint32_t n, WideTree& out) {
    const uint32_t index = uint32_t(out.nodes.size());
    out.nodes.push_back({n, {}});
    const uint32_t k = internalSplit_[n];
    collect(bvh_.nodes[n].left, k, index, out);
    collect(bvh_.nodes[n].right, w_ - k, index, out);
    return index;
  }

  const Bvh& bvh_;
  uint32_t w_;
  std::vector<double> area_;
  std::vector<uint32_t> refs_;
  std::vector<double> c_;
  std::vector<Choice> choice_;
  std::vector<uint8_t> split_;
  std::vector<double> internalCost_;     // Cinternal(n)
  std::vector<uint8_t> internalSplit_;   // its split of the W slots
};

}  // namespace

std::vector<uint32_t> subtreeReferences(const Bvh& bvh) {
  std::vector<uint32_t> refs(bvh.nodes.size(), 0);
  if (bvh.nodes.empty()) return refs;
  const std::vector<uint32_t> order = preOrder(bvh);
  for (auto it = order.rbegin(); it != order.rend(); ++it) {
    const BvhNode& n = bvh.nodes[*it];
    refs[*it] = n.isLeaf() ? n.count : refs[n.left] + refs[n.right];
  }
  return refs;
}

WideTree collapseWide(const Bvh& bvh, uint32_t width, const CostModel& cost, uint32_t maxLeafSize) {
  // 32: the split is stored in 8 bits and a record of more children than that has no use here.
  if (width < 2 || width > 32)
    throw std::invalid_argument("collapseWide: width must be in 2..32, got " + std::to_string(width));
  if (maxLeafSize == 0) throw std::invalid_argument("collapseWide: the leaf cap must be at least 1");
  if (bvh.nodes.empty()) throw std::invalid_argument("collapseWide: empty tree");
  return Collapse(bvh, width, cost, maxLeafSize).emit();
}

double wideSahCost(const Bvh& bvh, const WideTree& wide, const CostModel& cost) {
  const std::vector<double> area = relativeAreas(bvh);
  const std::vector<uint32_t> refs = subtreeReferences(bvh);
  if (wide.nodes.empty()) return cost.intersectionCost * area[0] * double(refs[0]);
  double inner = 0.0, leaf = 0.0;
  for (const WideNode& n : wide.nodes) {
    inner += area[n.binaryNode];
    for (const WideChild& c : n.children)
      if (c.leaf) leaf += area[c.binaryNode] * double(refs[c.binaryNode]);
  }
  return cost.traversalCost * inner + cost.intersectionCost * leaf;
}

}  // namespace bvhlab
