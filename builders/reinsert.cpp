// EXPERIMENTAL DRAFT (knobs read from the environment while tuning).
#include "builders/reinsert.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

#include "builders/build_util.hpp"

namespace bvhlab {

namespace {

constexpr uint32_t kNone = 0xffffffffu;

double envD(const char* name, double fallback) {
  const char* v = std::getenv(name);
  return v ? std::atof(v) : fallback;
}

double area(const Aabb& b) { return double(b.halfArea()); }

Aabb merged(const Aabb& a, const Aabb& b) {
  Aabb u = a;
  u.grow(b);
  return u;
}

bool sameBox(const Aabb& a, const Aabb& b) { return a.min == b.min && a.max == b.max; }

class Optimizer {
 public:
  Optimizer(Bvh& bvh, uint32_t depthLimit) : nodes_(bvh.nodes), depthLimit_(depthLimit) {}

  std::vector<BvhNode>& nodes_;
  std::vector<uint32_t> parent_, height_;
  uint32_t depthLimit_;
  double delta_ = 0.0;  // change of the sum of inner-node areas since the last commit

  struct Saved {
    uint32_t index;
    BvhNode node;
    uint32_t parent, height;
  };
  std::vector<Saved> log_;

  struct Entry {
    double cost;
    uint32_t node, depth;
    bool operator>(const Entry& o) const { return cost > o.cost || (cost == o.cost && node > o.node); }
  };
  std::vector<Entry> heap_;

  void save(uint32_t i) { log_.push_back({i, nodes_[i], parent_[i], height_[i]}); }
  void commit() {
    log_.clear();
    delta_ = 0.0;
  }
  void rollback() {
    for (size_t k = log_.size(); k-- > 0;) {
      const Saved& s = log_[k];
      nodes_[s.index] = s.node;
      parent_[s.index] = s.parent;
      height_[s.index] = s.height;
    }
    log_.clear();
    delta_ = 0.0;
  }

  void replaceChild(uint32_t p, uint32_t oldChild, uint32_t newChild) {
    save(p);
    if (nodes_[p].left == oldChild)
      nodes_[p].left = newChild;
    else
      nodes_[p].right = newChild;
  }

  // Refits boxes and heights from `a` up to the root, stopping where nothing changes.
  void refitUp(uint32_t a) {
    for (; a != kNone; a = parent_[a]) {
      const BvhNode& n = nodes_[a];
      const Aabb box = merged(nodes_[n.left].bounds, nodes_[n.right].bounds);
      const uint32_t h = 1 + std::max(height_[n.left], height_[n.right]);
      if (sameBox(box, n.bounds) && h == height_[a]) return;
      save(a);
      delta_ += area(box) - area(n.bounds);
      nodes_[a].bounds = box;
      height_[a] = h;
    }
  }

  // Detaches x (whose parent is not the root) with its subtree; x's sibling takes its parent's place.
  // Returns the freed parent slot.
  uint32_t detach(uint32_t x) {
    const uint32_t p = parent_[x];
    const uint32_t s = nodes_[p].left == x ? nodes_[p].right : nodes_[p].left;
    const uint32_t g = parent_[p];
    replaceChild(g, p, s);
    save(s);
    parent_[s] = g;
    save(x);
    parent_[x] = kNone;
    save(p);
    parent_[p] = kNone;
    delta_ -= area(nodes_[p].bounds);
    refitUp(g);
    return p;
  }

  // Inserts the detached x as the sibling of t, with `slot` as their new parent.
  void attach(uint32_t x, uint32_t t, uint32_t slot) {
    save(slot);
    save(x);
    if (t == 0) {
      // A new root: the old root moves to `slot`; nodes[0] stays the root.
      nodes_[slot] = nodes_[0];
      parent_[slot] = 0;
      height_[slot] = height_[0];
      for (uint32_t c : {nodes_[slot].left, nodes_[slot].right}) {
        save(c);
        parent_[c] = slot;
      }
      save(0);
      BvhNode root;
      root.bounds = merged(nodes_[slot].bounds, nodes_[x].bounds);
      root.left = slot;
      root.right = x;
      nodes_[0] = root;
      height_[0] = 1 + std::max(height_[slot], height_[x]);
      parent_[x] = 0;
      delta_ += area(root.bounds);
      return;
    }
    const uint32_t g = parent_[t];
    replaceChild(g, t, slot);
    BvhNode n;
    n.bounds = merged(nodes_[t].bounds, nodes_[x].bounds);
    n.left = t;
    n.right = x;
    nodes_[slot] = n;
    parent_[slot] = g;
    height_[slot] = 1 + std::max(height_[t], height_[x]);
    save(t);
    parent_[t] = slot;
    parent_[x] = slot;
    delta_ += area(n.bounds);
    refitUp(g);
  }

  // Branch and bound (Bittner et al. 2013, Sec. 4.2): the cheapest sibling for the detached x, by the
  // induced cost (the new parent's area plus the growth of every ancestor). Returns kNone when no
  // position respects the depth limit.
  uint32_t search(uint32_t x, double& bestCost) {
    const Aabb& box = nodes_[x].bounds;
    const double ax = area(box);
    const uint32_t hx = height_[x];
    bestCost = std::numeric_limits<double>::infinity();
    uint32_t best = kNone;
    heap_.clear();
    heap_.push_back({0.0, 0, 1});
    const auto greater = std::greater<Entry>();
    while (!heap_.empty()) {
      std::pop_heap(heap_.begin(), heap_.end(), greater);
      const Entry e = heap_.back();
      heap_.pop_back();
      if (!(e.cost + ax < bestCost)) break;
      const BvhNode& n = nodes_[e.node];
      const double direct = area(merged(n.bounds, box));
      const double cost = e.cost + direct;
      if (cost < bestCost && e.depth + std::max(height_[e.node], hx) <= depthLimit_) {
        bestCost = cost;
        best = e.node;
      }
      if (n.isLeaf()) continue;
      const double induced = cost - area(n.bounds);
      if (induced + ax < bestCost && e.depth + 1 + hx <= depthLimit_) {
        heap_.push_back({induced, n.left, e.depth + 1});
        std::push_heap(heap_.begin(), heap_.end(), greater);
        heap_.push_back({induced, n.right, e.depth + 1});
        std::push_heap(heap_.begin(), heap_.end(), greater);
      }
    }
    return best;
  }

  bool eligible(uint32_t x) const { return x != 0 && parent_[x] != kNone && parent_[x] != 0; }

  // Moves x's subtree to its best position if that lowers the SAH by more than eps.
  bool moveSubtree(uint32_t x, double eps) {
    const uint32_t slot = detach(x);
    const double gain = -delta_;
    double cost;
    const uint32_t t = search(x, cost);
    if (t == kNone || !(cost < gain - eps)) {
      rollback();
      return false;
    }
    attach(x, t, slot);
    if (!(delta_ < -eps) || height_[0] > depthLimit_) {
      rollback();
      return false;
    }
    commit();
    return true;
  }

  // Bittner's operation: removes the inner node n and its parent, reinserts n's two children.
  bool dissolve(uint32_t n, double eps) {
    const uint32_t slot = detach(n);
    const uint32_t l = nodes_[n].left, r = nodes_[n].right;
    delta_ -= area(nodes_[n].bounds);
    save(l);
    save(r);
    parent_[l] = parent_[r] = kNone;
    const bool lFirst = area(nodes_[l].bounds) >= area(nodes_[r].bounds);
    const uint32_t a = lFirst ? l : r, b = lFirst ? r : l;
    double cost;
    uint32_t t = search(a, cost);
    if (t == kNone) {
      rollback();
      return false;
    }
    attach(a, t, slot);
    t = search(b, cost);
    if (t == kNone) {
      rollback();
      return false;
    }
    attach(b, t, n);
    if (!(delta_ < -eps) || height_[0] > depthLimit_) {
      rollback();
      return false;
    }
    commit();
    return true;
  }
};

}  // namespace

void optimizeReinsert(Bvh& bvh, const BuildOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  std::vector<BvhNode>& nodes = bvh.nodes;
  if (nodes.size() < 5) return;
  const uint32_t count = uint32_t(nodes.size());
  // Structure check, parents, heights, refit.
  std::vector<uint32_t> parent(count, kNone), height(count, 0), order;
  order.reserve(count);
  {
    std::vector<uint32_t> stack{0};
    std::vector<char> reached(count, 0);
    while (!stack.empty()) {
      const uint32_t i = stack.back();
      stack.pop_back();
      if (i >= count || reached[i]) throw std::invalid_argument("optimizeReinsert: the nodes do not form a tree");
      reached[i] = 1;
      order.push_back(i);
      const BvhNode& n = nodes[i];
      if (n.isLeaf()) {
        if (uint64_t(n.first) + n.count > bvh.primIndices.size())
          throw std::invalid_argument("optimizeReinsert: leaf range out of primIndices");
        continue;
      }
      for (uint32_t c : {n.left, n.right}) {
        if (c >= count) throw std::invalid_argument("optimizeReinsert: child index out of range");
        parent[c] = i;
        stack.push_back(c);
      }
    }
  }
  for (size_t k = order.size(); k-- > 0;) {
    BvhNode& n = nodes[order[k]];
    if (n.isLeaf()) {
      height[order[k]] = 1;
    } else {
      n.bounds = merged(nodes[n.left].bounds, nodes[n.right].bounds);
      height[order[k]] = 1 + std::max(height[n.left], height[n.right]);
    }
  }
  const double rootArea = area(nodes[0].bounds);
  if (!(rootArea > 0.0) || !std::isfinite(rootArea) || options.cost.traversalCost <= 0.0f) return;

  const Bvh original = bvh;
  const double sahBefore = sahCost(bvh, options.cost);

  const uint32_t depthLimit = std::max<uint32_t>(height[0], uint32_t(envD("RI_DEPTH", 64)));
  Optimizer opt(bvh, depthLimit);
  opt.parent_ = std::move(parent);
  opt.height_ = std::move(height);

  double innerSum = 0.0, leafSum = 0.0;
  for (uint32_t i : order)
    (nodes[i].isLeaf() ? leafSum : innerSum) += area(nodes[i].bounds) * (nodes[i].isLeaf() ? nodes[i].count : 1);
  const double ct = options.cost.traversalCost, ci = options.cost.intersectionCost;
  if (envD("RI_VERBOSE", 0) != 0) std::fprintf(stderr, "inner %.4f leaf %.4f depth %u\n", ct * innerSum / rootArea, ci * leafSum / rootArea, opt.height_[0]);

  const double eps = 1e-10 * rootArea;
  const int mode = int(envD("RI_MODE", 0));
  const double fraction = envD("RI_FRACTION", 1.0);
  const double threshold = envD("RI_THRESHOLD", 1e-3);
  const int maxIter = int(envD("RI_ITERS", 1000));
  const bool verbose = envD("RI_VERBOSE", 0) != 0;
  auto elapsedMs = [&] {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  };
  bool outOfTime = false;
  std::vector<std::pair<double, uint32_t>> cand;
  for (int iter = 0; iter < maxIter && !outOfTime; ++iter) {
    cand.clear();
    for (uint32_t i = 0; i < count; ++i) {
      if (!opt.eligible(i)) continue;
      const BvhNode& n = nodes[i];
      double score;
      if (mode == 0 || n.isLeaf()) {
        score = area(nodes[opt.parent_[i]].bounds);  // area of the parent
        if (mode == 3) score = area(nodes[opt.parent_[i]].bounds) - area(n.bounds);
      } else {
        const double al = area(nodes[n.left].bounds), ar = area(nodes[n.right].bounds), an = area(n.bounds);
        const double msum = an / std::max(0.5 * (al + ar), 1e-30 * rootArea);
        const double mmin = an / std::max(std::min(al, ar), 1e-30 * rootArea);
        score = msum * mmin * an;
      }
      cand.push_back({score, i});
    }
    std::sort(cand.begin(), cand.end(), [](const auto& a, const auto& b) {
      return a.first > b.first || (a.first == b.first && a.second < b.second);
    });
    const size_t take = std::max<size_t>(1, size_t(std::ceil(fraction * double(cand.size()))));
    if (cand.size() > take) cand.resize(take);
    double gained = 0.0;
    size_t moves = 0;
    for (size_t k = 0; k < cand.size(); ++k) {
      if ((k & 15) == 0 && options.optimizeBudgetMs > 0.0 && elapsedMs() > options.optimizeBudgetMs) {
        outOfTime = true;
        break;
      }
      const uint32_t x = cand[k].second;
      if (!opt.eligible(x)) continue;
      double before = opt.delta_;
      (void)before;
      bool moved = false;
      // delta_ is reset on commit: capture it via a probe.
      opt.delta_ = 0.0;
      if (mode == 0 || mode == 3 || nodes[x].isLeaf()) {
        const uint32_t p = opt.parent_[x];
        (void)p;
        // record delta before commit
        const uint32_t slot = opt.detach(x);
        const double gain = -opt.delta_;
        double cost;
        const uint32_t t = opt.search(x, cost);
        if (t != kNone && cost < gain - eps) {
          opt.attach(x, t, slot);
          if (opt.delta_ < -eps && opt.height_[0] <= depthLimit) {
            gained -= opt.delta_;
            moved = true;
            opt.commit();
          }
        }
        if (!moved) opt.rollback();
      } else {
        const uint32_t slot = opt.detach(x);
        const uint32_t l = nodes[x].left, r = nodes[x].right;
        opt.delta_ -= area(nodes[x].bounds);
        opt.save(l);
        opt.save(r);
        opt.parent_[l] = opt.parent_[r] = kNone;
        const bool lFirst = area(nodes[l].bounds) >= area(nodes[r].bounds);
        const uint32_t a = lFirst ? l : r, b = lFirst ? r : l;
        double cost;
        uint32_t t = opt.search(a, cost);
        if (t != kNone) {
          opt.attach(a, t, slot);
          t = opt.search(b, cost);
          if (t != kNone) {
            opt.attach(b, t, x);
            if (opt.delta_ < -eps && opt.height_[0] <= depthLimit) {
              gained -= opt.delta_;
              moved = true;
              opt.commit();
            }
          }
        }
        if (!moved) opt.rollback();
      }
      moves += moved;
    }
    innerSum -= gained;
    const double total = ct * innerSum + ci * leafSum;
    const double rel = ct * gained / (total + ct * gained);
    if (verbose)
      std::fprintf(stderr, "iter %d: %zu candidates, %zu moves, SAH %.4f, gain %.5f%%, depth %u, %.1f ms\n", iter,
                   cand.size(), moves, total / rootArea, 100 * rel, opt.height_[0], elapsedMs());
    if (rel < threshold) break;
  }
  if (sahCost(bvh, options.cost) > sahBefore) bvh = original;
}

}  // namespace bvhlab
