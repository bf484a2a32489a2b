// What the top-down builders share: primitive references, range bounds, the object-median split, and
// the driver (buildTopDown) that runs a builder's per-node step over the whole tree, on threads at the
// top levels and for the subtrees below them, with a tree that is identical for any thread count.
#pragma once
#include <algorithm>
#include <atomic>
#include <cstdint>
#include <cstdlib>
#include <exception>
#include <new>
#include <span>
#include <thread>
#include <type_traits>
#include <vector>

#include "builders/bvh.hpp"
#include "builders/scratch.hpp"

namespace bvhlab::detail {

// A primitive as the builders move it around: its box, its centroid (the caller's, which need not be
// the box centre) and its input index.
struct PrimRef {
  Aabb box;
  glm::vec3 centroid;
  uint32_t id;
};

inline ScratchVector<PrimRef> makePrimRefs(const BuildInput& input) {
  ScratchVector<PrimRef> refs(input.boxes.size());
  for (size_t i = 0; i < refs.size(); ++i)
    refs[i] = {input.boxes[i], input.centroids[i], uint32_t(i)};
  return refs;
}

struct RangeBounds {
  Aabb box;        // union of the primitives' boxes
  Aabb centroids;  // bounds of their centroids
};

inline RangeBounds rangeBounds(std::span<const PrimRef> refs) {
  RangeBounds b;
  for (const PrimRef& r : refs) {
    b.box.grow(r.box);
    b.centroids.grow(r.centroid);
  }
  return b;
}

// The axis of largest extent; ties go to the lower axis so the choice is deterministic.
inline int longestAxis(const glm::vec3& extent) {
  int axis = 0;
  if (extent.y > extent[axis]) axis = 1;
  if (extent.z > extent[axis]) axis = 2;
  return axis;
}

// Puts the `mid` smallest references (by centroid on `axis`, then by id, a total order so the result
// does not depend on the input order of equal centroids) in refs[0, mid).
inline void objectMedianSplit(std::span<PrimRef> refs, size_t mid, int axis) {
  std::nth_element(refs.begin(), refs.begin() + mid, refs.end(), [axis](const PrimRef& a, const PrimRef& b) {
    return a.centroid[axis] < b.centroid[axis] || (a.centroid[axis] == b.centroid[axis] && a.id < b.id);
  });
}

inline unsigned resolveThreads(uint32_t requested) {
  if (requested) return requested;
  return std::max(1u, std::thread::hardware_concurrency());
}

// Runs job(i) for i in [0, count) on up to `threads` threads (the caller's included), claiming jobs
// in the order `order` gives (all indices when empty). Which thread runs which job never affects the
// results: each job writes only its own slot. The first exception thrown by a job is rethrown here.
template <class Job>
void runJobs(size_t count, unsigned threads, Job&& job, const std::vector<uint32_t>& order = {}) {
  auto jobAt = [&](size_t i) { job(order.empty() ? i : order[i]); };
  threads = unsigned(std::min<size_t>(threads, count));
  if (threads <= 1) {
    for (size_t i = 0; i < count; ++i) jobAt(i);
    return;
  }
  std::atomic<size_t> next{0};
  std::exception_ptr error;
  std::atomic<bool> failed{false};
  auto worker = [&] {
    for (size_t i; !failed.load() && (i = next.fetch_add(1)) < count;) {
      try {
        jobAt(i);
      } catch (...) {
        if (!failed.exchange(true)) error = std::current_exception();
      }
    }
  };
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

// ---- the top-down driver the builders share ------------------------------------------------------
//
// A builder supplies a Task type (with uint32_t members node, begin, end: the node's index and its
// primitive range in the builder's own reference order, plus whatever the builder carries down, e.g.
// centroid bounds) and a stepper: `NodeStep<Task> step(const Task& task, const Aabb& box)` decides
// leaf or split for a node whose box is `box`, partitions the task's range in place, and returns the
// children's boxes and tasks (their `node` is filled in by the driver). Steppers of different tasks
// may run concurrently (their ranges are disjoint); each thread gets its own stepper.

template <class Task>
struct NodeStep {
  bool leaf = true;
  Aabb childBox[2];
  Task child[2];  // child[0] takes [task.begin, mid), child[1] [mid, task.end)
};

// Inputs below this size are built sequentially (threads cost more than they save). Above it, the
// nodes bigger than n / kSubtreeFraction are processed level by level (each level's nodes as parallel
// jobs), and every smaller node becomes an independent subtree job. Both thresholds depend on the
// input size only, never on the thread count, so the tree and its node order are the same for any
// thread count.
constexpr uint32_t kParallelMinInput = 16384;
constexpr uint32_t kSubtreeFraction = 16;

// Appends the two children of nodes[at] (an inner node from here on) and returns the first's index.
// The children's fields are stored one by one, not as a temporary BvhNode copied in: a copy reads
// back, 16 bytes at a time, what was just stored 4 and 8 bytes at a time, and each such read waits
// for the stores to retire (a failed store-to-load forward, ~12 cycles: 5% of a bunny build, perf).
inline uint32_t appendChildren(std::vector<BvhNode>& nodes, uint32_t at, const Aabb (&boxes)[2]) {
  const uint32_t left = uint32_t(nodes.size());
  nodes.resize(left + 2);  // capacity reserved by buildTopDown: no reallocation
  nodes[left].bounds = boxes[0];
  nodes[left + 1].bounds = boxes[1];
  BvhNode& node = nodes[at];
  node.left = left;
  node.right = left + 1;
  node.count = 0;
  return left;
}

template <class Task>
void applyStep(std::vector<BvhNode>& nodes, Task& task, NodeStep<Task>& step) {
  if (step.leaf) {
    BvhNode& node = nodes[task.node];
    node.first = task.begin;
    node.count = task.end - task.begin;
    return;
  }
  const uint32_t left = appendChildren(nodes, task.node, step.childBox);
  step.child[0].node = left;
  step.child[1].node = left + 1;
}

// Depth-first, with an explicit stack (degenerate trees can be as deep as they have primitives).
// The stack keeps each task's node index beside it (the stepper never reads Task::node), so that a
// child task goes onto the stack exactly as the stepper wrote it: setting its node field first
// and copying the task would be the narrow-store, wide-load stall appendChildren avoids.
template <class Task, class Stepper>
void buildSubtree(std::vector<BvhNode>& nodes, const Task& root, Stepper& stepper) {
  std::vector<Task> stack{root};
  std::vector<uint32_t> at{root.node};
  while (!stack.empty()) {
    const Task task = stack.back();
    const uint32_t node = at.back();
    stack.pop_back();
    at.pop_back();
    const NodeStep<Task> step = stepper.step(task, nodes[node].bounds);
    if (step.leaf) {
      nodes[node].first = task.begin;
      nodes[node].count = task.end - task.begin;
      continue;
    }
    const uint32_t left = appendChildren(nodes, node, step.childBox);
    stack.push_back(step.child[1]);
    at.push_back(left + 1);
    stack.push_back(step.child[0]);
    at.push_back(left);
  }
}

// Builds the whole tree over [root.begin, root.end) (root.begin == 0) and returns its nodes (root
// first). `makeStepper()` makes one stepper per job.
template <class Task, class MakeStepper>
std::vector<BvhNode> buildTopDown(const Aabb& rootBox, Task root, unsigned threads, MakeStepper&& makeStepper) {
  const uint32_t n = root.end - root.begin;
  std::vector<BvhNode> nodes;
  nodes.reserve(2 * size_t(n) - 1);
  adviseHugePages(nodes.data(), nodes.capacity() * sizeof(BvhNode));
  nodes.push_back({rootBox});
  root.node = 0;
  if (n < kParallelMinInput) {
    auto stepper = makeStepper();
    buildSubtree(nodes, root, stepper);
    return nodes;
  }

  const uint32_t cut = n / kSubtreeFraction;
  std::vector<Task> level{root}, subtrees;
  while (!level.empty()) {
    std::vector<NodeStep<Task>> steps(level.size());
    runJobs(level.size(), threads, [&](size_t k) {
      auto stepper = makeStepper();
      steps[k] = stepper.step(level[k], nodes[level[k].node].bounds);
    });
    std::vector<Task> next;
    for (size_t k = 0; k < level.size(); ++k) {
      applyStep(nodes, level[k], steps[k]);
      if (steps[k].leaf) continue;
      for (const Task& child : steps[k].child) (child.end - child.begin <= cut ? subtrees : next).push_back(child);
    }
    level = std::move(next);
  }

  // One thread: each subtree straight into `nodes`, in creation order. That is the layout the
  // splice below makes (a subtree's root stays at its placeholder, its other nodes follow those of
  // the subtrees before it, in the order they were made), without the copies.
  if (threads <= 1) {
    for (const Task& task : subtrees) {
      auto stepper = makeStepper();
      buildSubtree(nodes, task, stepper);
    }
    return nodes;
  }

  // Subtrees into their own arrays, biggest first (load balance), then spliced in creation order.
  std::vector<std::vector<BvhNode>> local(subtrees.size());
  std::vector<uint32_t> order(subtrees.size());
  for (uint32_t k = 0; k < order.size(); ++k) order[k] = k;
  std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    return subtrees[a].end - subtrees[a].begin > subtrees[b].end - subtrees[b].begin;
  });
  runJobs(
      subtrees.size(), threads,
      [&](size_t k) {
        Task task = subtrees[k];
        local[k].reserve(2 * size_t(task.end - task.begin) - 1);
        local[k].push_back(nodes[task.node]);
        task.node = 0;
        auto stepper = makeStepper();
        buildSubtree(local[k], task, stepper);
      },
      order);
  for (size_t k = 0; k < subtrees.size(); ++k) {
    // Local index j >= 1 lands at nodes.size() + j - 1; the local root replaces its placeholder.
    const uint32_t shift = uint32_t(nodes.size()) - 1;
    auto moved = [shift](BvhNode node) {
      if (!node.isLeaf()) node.left += shift, node.right += shift;
      return node;
    };
    nodes[subtrees[k].node] = moved(local[k][0]);
    for (size_t j = 1; j < local[k].size(); ++j) nodes.push_back(moved(local[k][j]));
  }
  return nodes;
}

}  // namespace bvhlab::detail
