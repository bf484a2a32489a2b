// What the top-down builders share: primitive references, range bounds, the object-median split, and
// the driver (buildTopDown) that runs a builder's per-node step over the whole tree: the top levels on one
// thread while the subtrees below them are built on the others, a tree identical for any thread count.
#pragma once
#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <cstdlib>
#include <deque>
#include <exception>
#include <mutex>
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
// nodes bigger than n / kSubtreeFraction are made level by level on one thread, and every smaller
// node becomes an independent subtree job, started as soon as it appears (SubtreeTeam). Both
// thresholds depend on the input size only, never on the thread count, so the tree and its node order
// are the same for any thread count. 4,096: with one thread start per build, two threads build
// sah-binned trees of 5,800-6,400 triangles in 0.83x one thread's time (measured when this was chosen; its run is
// in the git history of docs/builders.md); below that a start (~60 us here) is a tenth of the build.
constexpr uint32_t kParallelMinInput = 4096;
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

// The subtrees of a parallel build, handed out while the top levels are still being made: the main
// thread makes the levels (in the order the one-thread build makes them), publishing each subtree as
// it appears, and the other threads of the team build the biggest waiting one into its own array.
// Once the levels are done, the main thread takes subtrees too; once every subtree is built, the team
// copies them into the tree in creation order (a subtree's root replaces its placeholder, its other
// nodes follow those of the subtrees before it: the one-thread layout), each thread a subtree at a
// time. One start per thread per build. The first exception thrown by a stepper is rethrown by run().
template <class Task>
class SubtreeTeam {
 public:
  explicit SubtreeTeam(std::vector<BvhNode>& nodes) : nodes_(nodes) {}

  // Starts `helpers` threads, calls levels(publish) on this one, then takes part in the rest.
  template <class MakeStepper, class Levels>
  void run(unsigned helpers, MakeStepper& makeStepper, Levels&& levels) {
    std::vector<std::thread> team;
    for (unsigned t = 0; t < helpers; ++t) team.emplace_back([&] { work(makeStepper); });
    try {
      levels([&](const Task& task) { publish(task); });
    } catch (...) {
      fail(std::current_exception());
    }
    {
      std::lock_guard lock(mutex_);
      closed_ = true;
      if (built_ == entries_.size()) startCopies();  // else the last subtree's builder does it
    }
    wake_.notify_all();
    work(makeStepper);
    for (std::thread& t : team) t.join();
    if (error_) std::rethrow_exception(error_);
  }

 private:
  struct Entry {
    Task task;
    BvhNode placeholder;
    std::vector<BvhNode> nodes;
    bool claimed = false;
  };

  void publish(const Task& task) {
    {
      std::lock_guard lock(mutex_);
      entries_.push_back({task, nodes_[task.node], {}, false});
    }
    wake_.notify_one();
  }

  void fail(std::exception_ptr e) {
    std::lock_guard lock(mutex_);
    if (!error_) error_ = e;
    failed_ = true;
  }

  // Builds subtrees until none is waiting and the levels are done, then copies subtrees into the tree
  // once all are built (the last builder sets out the offsets).
  template <class MakeStepper>
  void work(MakeStepper& makeStepper) {
    std::unique_lock lock(mutex_);
    for (;;) {
      Entry* next = nullptr;
      for (Entry& e : entries_)  // the biggest waiting subtree (few: tens)
        if (!e.claimed && (!next || e.task.end - e.task.begin > next->task.end - next->task.begin)) next = &e;
      if (next) {
        next->claimed = true;
        Task task = next->task;
        const BvhNode placeholder = next->placeholder;
        lock.unlock();
        std::vector<BvhNode> local;
        try {
          if (!failed_) {
            local.reserve(2 * size_t(task.end - task.begin) - 1);
            local.push_back(placeholder);
            task.node = 0;
            auto stepper = makeStepper();
            buildSubtree(local, task, stepper);
          }
        } catch (...) {
          fail(std::current_exception());
        }
        lock.lock();
        next->nodes = std::move(local);  // a std::deque: publishing keeps entries where they are
        if (++built_ == entries_.size() && closed_) startCopies();
        continue;
      }
      if (closed_ && built_ == entries_.size()) break;
      wake_.wait(lock);
    }
    // Copies, each thread a subtree at a time.
    while (copied_ < entries_.size()) {
      const size_t k = copied_++;
      lock.unlock();
      copy(k);
      lock.lock();
    }
  }

  // All subtrees built: the offsets, then every thread may copy.
  void startCopies() {
    size_t at = nodes_.size();
    offsets_.resize(entries_.size());
    for (size_t k = 0; k < entries_.size(); ++k) {
      offsets_[k] = at;
      if (!entries_[k].nodes.empty()) at += entries_[k].nodes.size() - 1;
    }
    nodes_.resize(at);  // capacity reserved by buildTopDown: no reallocation
    wake_.notify_all();
  }

  // Local index j >= 1 lands at offsets_[k] + j - 1; the local root replaces its placeholder.
  void copy(size_t k) {
    const std::vector<BvhNode>& local = entries_[k].nodes;
    if (local.empty()) return;  // a stepper failed: run() rethrows
    const uint32_t shift = uint32_t(offsets_[k]) - 1;
    auto moved = [shift](BvhNode node) {
      if (!node.isLeaf()) node.left += shift, node.right += shift;
      return node;
    };
    nodes_[entries_[k].task.node] = moved(local[0]);
    BvhNode* out = nodes_.data() + offsets_[k];
    for (size_t j = 1; j < local.size(); ++j) out[j - 1] = moved(local[j]);
  }

  std::vector<BvhNode>& nodes_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<Entry> entries_;
  std::vector<size_t> offsets_;
  size_t built_ = 0, copied_ = 0;
  bool closed_ = false;
  std::exception_ptr error_;
  std::atomic<bool> failed_{false};  // error_ is set: the rest is skipped
};

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

  // The nodes bigger than the cut, level by level (each level's in order), on this thread; every
  // smaller node becomes a subtree, handed to `subtree` as it appears.
  const uint32_t cut = n / kSubtreeFraction;
  auto levels = [&](auto&& subtree) {
    auto stepper = makeStepper();
    std::vector<Task> level{root}, next;
    while (!level.empty()) {
      next.clear();
      for (Task& task : level) {
        NodeStep<Task> step = stepper.step(task, nodes[task.node].bounds);
        applyStep(nodes, task, step);
        if (step.leaf) continue;
        for (const Task& child : step.child) {
          if (child.end - child.begin <= cut)
            subtree(child);
          else
            next.push_back(child);
        }
      }
      level.swap(next);
    }
  };

  // One thread: each subtree straight into `nodes`, in creation order. That is the layout the
  // team's copies make, without the copies.
  if (threads <= 1) {
    std::vector<Task> subtrees;
    levels([&](const Task& task) { subtrees.push_back(task); });
    for (const Task& task : subtrees) {
      auto stepper = makeStepper();
      buildSubtree(nodes, task, stepper);
    }
    return nodes;
  }
  SubtreeTeam<Task> team(nodes);
  team.run(threads - 1, makeStepper, levels);
  return nodes;
}

}  // namespace bvhlab::detail
