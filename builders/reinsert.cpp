// `--optimize reinsert`: insertion-based BVH optimisation (Bittner, Hapala & Havran 2013, "Fast
// Insertion-Based Optimization of Bounding Volume Hierarchies").
//
// The pass changes the inner structure only: leaves keep their slots, boxes and primitive ranges and
// primIndices is never touched, so any builder's tree can be optimised (SBVH's duplicate references
// included), and the node count stays the same. With the leaves and the root box fixed, the SAH
// changes only through Ct * sum(inner areas), so every decision compares changes of that sum, in
// double, from the same float boxes (min/max unions are exact) the final tree stores. (buildBvh runs
// builders/reinsert_leaves.cpp, which expands the leaves to single primitives before this pass and
// collapses them by SAH after it.)
//
// Operations; each is kept only if it lowers the sum by more than eps, otherwise undone exactly:
//  - a leaf L is removed with its parent (L's sibling takes the parent's place, the ancestors are
//    refitted) and reinserted where the induced cost is lowest: the new parent's area plus the growth
//    of every ancestor, found by branch and bound from the root (Sec. 4 of the paper). L's old place
//    is among the positions, so a found one is never worse than staying.
//  - an inner node N: the paper's operation: N and its parent are removed and N's subtrees `level`
//    levels below N (its 2 children at level 1, as in the paper; up to 2^level subtrees) are
//    reinserted one by one, largest first, into the freed slots. Levels above 1 escape local minima
//    of level 1 (bunny, sah-binned tree: -2.55% at level 1 alone, -2.9% with levels up to 4).
// A sweep tries every node that is neither the root nor a child of it, inner nodes in the order of
// the paper's combined inefficiency measure (area x area/mean child area x area/min child area),
// leaves by their parent's area. Sweeps repeat while one lowers the SAH by at least kMinSweepGain;
// then the level grows, up to kMaxLevel. A node whose last attempt failed is skipped while nothing
// near it changed (`stale`).
//
// Parallelism, with a tree that does not depend on the thread count: the candidates go in fixed
// batches. Every candidate of a batch is first tried as a dry run (applied and undone) against the
// tree as it was when the batch began, by all threads, each on its own copy of the tree (the calling
// thread on the live tree, which an undone operation leaves bit-identical). Then, in batch order,
// the calling thread applies for real the candidates whose dry run gained, each re-evaluated on the
// current tree, so the SAH still only falls. Verdicts depend only on the batch's start tree and the
// real operations are sequential: the same tree for 1 or N threads. (Meister & Bittner 2018 search
// all nodes in parallel too, but resolve conflicting moves by timing-dependent locks.)
//
// Depth: reinsertion may deepen a tree (moving it towards the SAH optimum). The pass never makes it
// deeper than max(input depth, kReinsertMinDepthLimit): a position that would is not taken. The GLSL stack
// kernels size their stacks from the tree's depth (stackSizeFor), so they get at most 64 entries
// unless the builder's own tree needed more. Measured depths after the pass: 20-27 on the scanned
// meshes, 44-46 on a 1M-triangle generated mesh.
#include "builders/reinsert.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "builders/build_util.hpp"

namespace bvhlab {

namespace {

constexpr uint32_t kNone = 0xffffffffu;
using detail::kReinsertMinDepthLimit;
// Highest dissolve level (2^4 = 16 subtrees reinserted per operation).
constexpr int kMaxLevel = 4;
// A sweep that lowers the SAH by less than this fraction ends the current level. Measured gains per
// sweep fall roughly geometrically (e.g. 2.4%, 0.21%, 0.04%, 0.006% on the bunny's sah-binned tree):
// below 0.1% the rest of a level adds about a fifth of the last sweep's gain at the cost of one full
// sweep each (measured: running level 1 to 1000 sweeps instead took 100x the time for another 0.015%
// on the bunny's lbvh tree), and 0.1% of SAH is far below the frame-time differences the experiment
// runner can resolve (its A/A noise band is a few percent).
constexpr double kMinSweepGain = 1e-3;
// Candidates evaluated together (dry runs against the tree as it was at the batch's start). Smaller
// batches see fresher trees, larger ones amortise the threads' synchronisation.
constexpr size_t kBatch = 2048;
constexpr unsigned kMaxThreads = 16;

double area(const Aabb& b) { return double(b.halfArea()); }

Aabb merged(const Aabb& a, const Aabb& b) {
  Aabb u = a;
  u.grow(b);
  return u;
}

bool sameBox(const Aabb& a, const Aabb& b) { return a.min == b.min && a.max == b.max; }

bool finiteBox(const Aabb& b) {
  for (int k = 0; k < 3; ++k)
    if (!std::isfinite(b.min[k]) || !std::isfinite(b.max[k])) return false;
  return true;
}

// One copy of the tree being optimised, with an undo log: every write first saves the node's old
// state, so a tried operation is undone exactly.
class Tree {
 public:
  std::vector<BvhNode> nodes;
  std::vector<uint32_t> parent, height;  // height: leaf = 1
  uint32_t depthLimit = 0;
  double eps = 0.0;        // the least gain (in area units) an operation must bring
  double delta = 0.0;      // change of the inner-area sum since the last commit/rollback
  double lastGain = 0.0;   // gain of the last committed operation
  bool recordRedo = false;

  struct Saved {
    uint32_t index;
    BvhNode node;
    uint32_t parent, height;
  };
  std::vector<Saved> log, redo;  // redo: final states of committed writes (for the other copies)

  bool eligible(uint32_t x) const { return x != 0 && parent[x] != kNone && parent[x] != 0; }

  // Tries the operation for candidate x; keeps it (commit = true) only if it gains, otherwise or
  // when commit = false undoes it. Returns whether it gained.
  bool tryCandidate(uint32_t x, int level, bool commit) {
    if (!eligible(x)) return false;
    const bool gained = nodes[x].isLeaf() ? moveSubtree(x) : dissolve(x, level);
    if (gained && commit) {
      keep();
      return true;
    }
    undo();
    return gained;
  }

  void applyRedo(const std::vector<Saved>& entries) {
    for (const Saved& s : entries) {
      nodes[s.index] = s.node;
      parent[s.index] = s.parent;
      height[s.index] = s.height;
    }
  }

 private:
  struct Entry {
    double cost;
    uint32_t node, depth;
    bool operator>(const Entry& o) const { return cost > o.cost || (cost == o.cost && node > o.node); }
  };
  std::vector<Entry> heap_;
  std::vector<uint32_t> subs_, slots_;

  void save(uint32_t i) { log.push_back({i, nodes[i], parent[i], height[i]}); }

  void keep() {
    if (recordRedo)
      for (const Saved& s : log) redo.push_back({s.index, nodes[s.index], parent[s.index], height[s.index]});
    log.clear();
    lastGain = -delta;
    delta = 0.0;
  }

  void undo() {
    for (size_t k = log.size(); k-- > 0;) {
      const Saved& s = log[k];
      nodes[s.index] = s.node;
      parent[s.index] = s.parent;
      height[s.index] = s.height;
    }
    log.clear();
    delta = 0.0;
  }

  void replaceChild(uint32_t p, uint32_t oldChild, uint32_t newChild) {
    save(p);
    (nodes[p].left == oldChild ? nodes[p].left : nodes[p].right) = newChild;
  }

  // Refits boxes and heights from `a` up to the root, stopping where nothing changes.
  void refitUp(uint32_t a) {
    for (; a != kNone; a = parent[a]) {
      const BvhNode& n = nodes[a];
      const Aabb box = merged(nodes[n.left].bounds, nodes[n.right].bounds);
      const uint32_t h = 1 + std::max(height[n.left], height[n.right]);
      if (sameBox(box, n.bounds) && h == height[a]) return;
      save(a);
      delta += area(box) - area(n.bounds);
      nodes[a].bounds = box;
      height[a] = h;
    }
  }

  // Detaches x (neither the root nor a child of it) with its subtree: x's sibling takes the parent's
  // place. Returns the parent's slot, now free.
  uint32_t detach(uint32_t x) {
    const uint32_t p = parent[x];
    const uint32_t s = nodes[p].left == x ? nodes[p].right : nodes[p].left;
    const uint32_t g = parent[p];
    replaceChild(g, p, s);
    save(s);
    parent[s] = g;
    save(x);
    parent[x] = kNone;
    save(p);
    parent[p] = kNone;
    delta -= area(nodes[p].bounds);
    refitUp(g);
    return p;
  }

  // Inserts the detached x as the sibling of t, with the free `slot` as their new parent.
  void attach(uint32_t x, uint32_t t, uint32_t slot) {
    save(slot);
    save(x);
    BvhNode n;
    if (t == 0) {  // a new root: the old root moves to `slot`, nodes[0] stays the root
      nodes[slot] = nodes[0];
      parent[slot] = 0;
      height[slot] = height[0];
      for (uint32_t c : {nodes[slot].left, nodes[slot].right}) {
        save(c);
        parent[c] = slot;
      }
      save(0);
      n.bounds = merged(nodes[slot].bounds, nodes[x].bounds);
      n.left = slot;
      n.right = x;
      nodes[0] = n;
      height[0] = 1 + std::max(height[slot], height[x]);
      parent[x] = 0;
      delta += area(n.bounds);
      return;
    }
    const uint32_t g = parent[t];
    replaceChild(g, t, slot);
    n.bounds = merged(nodes[t].bounds, nodes[x].bounds);
    n.left = t;
    n.right = x;
    nodes[slot] = n;
    parent[slot] = g;
    height[slot] = 1 + std::max(height[t], height[x]);
    save(t);
    parent[t] = slot;
    parent[x] = slot;
    delta += area(n.bounds);
    refitUp(g);
  }

  // Branch and bound (Sec. 4.2 of the paper): the sibling t for the detached x that minimises the
  // induced cost A(t u x) + sum over t's ancestors a of (A(a u x) - A(a)), among the positions that
  // cost less than `bound` and keep the tree within depthLimit. Best-first by the cost induced above
  // a node, which only grows downwards; A(x) bounds what any position below still adds. Ties go to
  // the lower node index. Returns kNone when no position beats `bound`.
  uint32_t search(uint32_t x, double bound, double& bestCost) {
    const Aabb& box = nodes[x].bounds;
    const double ax = area(box);
    const uint32_t hx = height[x];
    bestCost = bound;
    uint32_t best = kNone;
    heap_.clear();
    heap_.push_back({0.0, 0, 1});
    const std::greater<Entry> greater;
    while (!heap_.empty()) {
      std::pop_heap(heap_.begin(), heap_.end(), greater);
      const Entry e = heap_.back();
      heap_.pop_back();
      if (!(e.cost + ax < bestCost)) break;
      const BvhNode& n = nodes[e.node];
      const double cost = e.cost + area(merged(n.bounds, box));
      // Inserting at depth d puts t's deepest leaf at d + height(t) and x's at d + height(x).
      if (cost < bestCost && e.depth + std::max(height[e.node], hx) <= depthLimit) {
        bestCost = cost;
        best = e.node;
      }
      if (n.isLeaf()) continue;
      const double induced = cost - area(n.bounds);
      if (induced + ax < bestCost && e.depth + 1 + hx <= depthLimit) {
        heap_.push_back({induced, n.left, e.depth + 1});
        std::push_heap(heap_.begin(), heap_.end(), greater);
        heap_.push_back({induced, n.right, e.depth + 1});
        std::push_heap(heap_.begin(), heap_.end(), greater);
      }
    }
    return best;
  }

  bool moveSubtree(uint32_t x) {
    const uint32_t slot = detach(x);
    double cost;
    const uint32_t t = search(x, -delta - eps, cost);
    if (t == kNone) return false;
    attach(x, t, slot);
    return delta < -eps && height[0] <= depthLimit;
  }

  bool dissolve(uint32_t n, int level) {
    subs_.assign(1, n);
    slots_.assign(1, detach(n));
    for (int l = 0; l < level; ++l) {
      const size_t m = subs_.size();
      for (size_t k = 0; k < m; ++k) {
        const uint32_t s = subs_[k];
        if (nodes[s].isLeaf()) continue;
        const uint32_t a = nodes[s].left, b = nodes[s].right;
        delta -= area(nodes[s].bounds);
        save(a);
        save(b);
        parent[a] = parent[b] = kNone;
        slots_.push_back(s);
        subs_[k] = a;
        subs_.push_back(b);
      }
    }
    std::sort(subs_.begin(), subs_.end(), [&](uint32_t a, uint32_t b) {
      const double aa = area(nodes[a].bounds), ab = area(nodes[b].bounds);
      return aa > ab || (aa == ab && a < b);
    });
    // Each reinsertion must leave room for the ones still to come (each costs at least its area).
    double rest = 0.0;
    for (uint32_t s : subs_) rest += area(nodes[s].bounds);
    for (size_t k = 0; k < subs_.size(); ++k) {
      rest -= area(nodes[subs_[k]].bounds);
      double cost;
      const uint32_t t = search(subs_[k], -delta - rest - eps, cost);
      if (t == kNone) return false;
      attach(subs_[k], t, slots_[k]);
    }
    return delta < -eps && height[0] <= depthLimit;
  }
};

// Bittner et al.'s combined inefficiency of an inner node (M_area * M_sum * M_min), a leaf's parent's
// area for a leaf; never NaN.
double score(const Tree& tree, uint32_t i, double tiny) {
  const BvhNode& n = tree.nodes[i];
  if (n.isLeaf()) return area(tree.nodes[tree.parent[i]].bounds);
  const double an = area(n.bounds), al = area(tree.nodes[n.left].bounds), ar = area(tree.nodes[n.right].bounds);
  return an * (an / std::max(0.5 * (al + ar), tiny)) * (an / std::max(std::min(al, ar), tiny));
}

}  // namespace

void optimizeReinsert(Bvh& bvh, const BuildOptions& options) { detail::optimizeInnerStructure(bvh, options, 0); }

void detail::optimizeInnerStructure(Bvh& bvh, const BuildOptions& options, uint32_t depthLimit) {
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  const double budgetMs = options.optimizeBudgetMs;
  auto outOfTime = [&] {
    return budgetMs > 0.0 && std::chrono::duration<double, std::milli>(Clock::now() - start).count() > budgetMs;
  };

  const uint32_t count = uint32_t(bvh.nodes.size());
  if (bvh.nodes.size() >= kNone) throw std::invalid_argument("optimizeReinsert: too many nodes");
  if (count < 5) return;  // nothing movable below the root's children

  // Check the shape (a tree over valid leaves with finite boxes), find parents, refit the inner boxes
  // (so that every box is the union of its children, which the cost arithmetic relies on).
  Tree tree;
  tree.parent.assign(count, kNone);
  tree.height.assign(count, 0);
  std::vector<uint32_t> preorder;
  preorder.reserve(count);
  {
    std::vector<char> reached(count, 0);
    std::vector<uint32_t> stack{0};
    while (!stack.empty()) {
      const uint32_t i = stack.back();
      stack.pop_back();
      if (i >= count || reached[i])
        throw std::invalid_argument("optimizeReinsert: the nodes do not form a tree (child index " +
                                    std::to_string(i) + " out of range or reached twice)");
      reached[i] = 1;
      preorder.push_back(i);
      const BvhNode& n = bvh.nodes[i];
      if (n.isLeaf()) {
        if (uint64_t(n.first) + n.count > bvh.primIndices.size())
          throw std::invalid_argument("optimizeReinsert: leaf " + std::to_string(i) + " exceeds primIndices");
        if (!finiteBox(n.bounds))
          throw std::invalid_argument("optimizeReinsert: leaf " + std::to_string(i) + " has a non-finite box");
        continue;
      }
      for (uint32_t c : {n.left, n.right}) {
        if (c < count) tree.parent[c] = i;
        stack.push_back(c);
      }
    }
  }
  const Bvh original = bvh;  // the result must never be worse than this (see the end)
  for (size_t k = preorder.size(); k-- > 0;) {
    const uint32_t i = preorder[k];
    BvhNode& n = bvh.nodes[i];
    if (n.isLeaf()) {
      tree.height[i] = 1;
    } else {
      n.bounds = merged(bvh.nodes[n.left].bounds, bvh.nodes[n.right].bounds);
      tree.height[i] = 1 + std::max(tree.height[n.left], tree.height[n.right]);
    }
  }
  const double rootArea = area(bvh.nodes[0].bounds);
  // Every box lies in the root's, so a finite root area keeps every area, and every sum of them below,
  // finite: no NaN can decide a comparison.
  if (!std::isfinite(rootArea)) {
    bvh = original;
    throw std::invalid_argument("optimizeReinsert: the root box's area overflows a float");
  }
  // Nothing to gain: a zero-area root (all ratios 1, the cost counts nodes, which never change) or
  // free traversal steps (the inner areas do not count).
  if (!(rootArea > 0.0) || !(options.cost.traversalCost > 0.0f) || preorder.size() < 5) {
    bvh = original;
    return;
  }
  const double sahBefore = sahCost(original, options.cost);
  const double ct = options.cost.traversalCost, ci = options.cost.intersectionCost;
  double innerSum = 0.0, leafSum = 0.0;
  for (uint32_t i : preorder) {
    const BvhNode& n = bvh.nodes[i];
    (n.isLeaf() ? leafSum : innerSum) += area(n.bounds) * (n.isLeaf() ? n.count : 1);
  }

  tree.nodes = std::move(bvh.nodes);
  tree.depthLimit = depthLimit ? std::max(tree.height[0], depthLimit) : std::max(tree.height[0], kReinsertMinDepthLimit);
  // Gains below this are rounding, not structure (areas are floats, sums doubles).
  tree.eps = 1e-10 * rootArea;

  // Each extra thread holds a copy of the tree (about 48 bytes a node).
  const unsigned threads = unsigned(std::min<size_t>(detail::resolveThreads(options.threads), kMaxThreads));
  std::vector<Tree> copies(threads - 1);  // dry-run trees of the threads other than this one
  for (Tree& c : copies) c = tree;
  tree.recordRedo = true;  // the copies replay it; the staleness test reads which nodes it names

  // Staleness: a candidate whose last attempt failed is skipped while no node within kNear levels
  // above it (nor the node itself) has been rewritten since.
  constexpr int kNear = 2;
  uint64_t clock = 1;  // advanced by every committed operation
  std::vector<uint64_t> written(count, 0), failedAt(count, 0);
  auto stale = [&](uint32_t x) {
    if (!failedAt[x]) return false;
    uint32_t a = x;
    for (int k = 0; k <= kNear && a != kNone; ++k, a = tree.parent[a])
      if (written[a] > failedAt[x]) return false;
    return true;
  };

  std::vector<std::pair<double, uint32_t>> candidates;
  std::vector<uint32_t> batch;
  std::vector<char> verdict;
  bool stopped = false;
  for (int level = 1; level <= kMaxLevel && !stopped; ++level) {
    // A new level may succeed where the last one failed, but only for inner nodes tall enough that
    // the level changes their operation (a leaf's move is the same at every level).
    for (uint32_t i = 0; i < count; ++i)
      if (!tree.nodes[i].isLeaf() && tree.height[i] > uint32_t(level)) failedAt[i] = 0;
    for (;;) {
      candidates.clear();
      const double tiny = 1e-12 * rootArea;
      for (uint32_t i = 0; i < count; ++i)
        if (tree.eligible(i) && !stale(i)) candidates.push_back({score(tree, i, tiny), i});
      std::sort(candidates.begin(), candidates.end(),
                [](const auto& a, const auto& b) { return a.first > b.first || (a.first == b.first && a.second < b.second); });
      double gained = 0.0;
      for (size_t b0 = 0; b0 < candidates.size() && !stopped; b0 += kBatch) {
        batch.clear();
        for (size_t k = b0; k < std::min(candidates.size(), b0 + kBatch); ++k) batch.push_back(candidates[k].second);
        verdict.assign(batch.size(), 0);
        // Dry runs against the tree as it is now (this thread on the live tree, which an undone
        // operation leaves bit-identical; the others on their copies, first brought up to date).
        std::atomic<size_t> next{0};
        std::atomic<bool> late{false};
        detail::runJobs(threads, threads, [&](size_t w) {
          Tree& t = w == 0 ? tree : copies[w - 1];
          if (w > 0) t.applyRedo(tree.redo);
          for (size_t k; !late.load(std::memory_order_relaxed) && (k = next.fetch_add(1)) < batch.size();) {
            if ((k & 15) == 15 && outOfTime()) late = true;
            verdict[k] = t.tryCandidate(batch[k], level, false);
          }
        });
        tree.redo.clear();
        if (late) stopped = true;
        // The real operations, in batch order, each re-evaluated on the current tree.
        const uint64_t batchClock = clock;
        for (size_t k = 0; k < batch.size() && !stopped; ++k) {
          const uint32_t x = batch[k];
          if (!verdict[k]) {
            failedAt[x] = batchClock;
            continue;
          }
          const size_t firstWrite = tree.redo.size();
          if (tree.tryCandidate(x, level, true)) {
            gained += tree.lastGain;
            ++clock;
            for (size_t r = firstWrite; r < tree.redo.size(); ++r) written[tree.redo[r].index] = clock;
            failedAt[x] = 0;
          } else {
            failedAt[x] = clock;
          }
          if ((k & 15) == 15 && outOfTime()) stopped = true;
        }
      }
      innerSum -= gained;
      const double total = ct * innerSum + ci * leafSum;
      if (stopped || !(ct * gained >= kMinSweepGain * (total + ct * gained))) break;
    }
  }

  bvh.nodes = std::move(tree.nodes);
  // The arithmetic above only takes gains well above rounding; this guards the guarantee against
  // the SAH as computed elsewhere.
  if (!(sahCost(bvh, options.cost) <= sahBefore)) bvh = original;
}

}  // namespace bvhlab
