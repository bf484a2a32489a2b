// Full-sweep SAH builder (MacDonald and Booth 1990; the "sweep" of Wald et al. 2007): the primitive
// indices are kept sorted by centroid on all three axes at once, so every node evaluates the exact SAH
// of every object split along every axis in O(n), then partitions the two other axes' orders stably
// by a left/right mark. O(n log n) overall after the initial three sorts. Axes with zero centroid
// extent are skipped (their order is the index order, not a spatial one); when no split beats a leaf
// but the node exceeds maxLeafSize it splits at the object median of its longest centroid axis.
#include <algorithm>
#include <array>
#include <numeric>
#include <span>
#include <vector>

#include "builders/build_util.hpp"

namespace bvhlab {

namespace {

struct Task {
  uint32_t node, begin, end;
};

class SweepStepper {
 public:
  // orders[a]: primitive indices sorted by centroid on axis a (ties by index). The scratch arrays have
  // one slot per primitive and are touched only inside a task's own range (isLeft: at the task's
  // primitives), so steppers of disjoint ranges may run concurrently.
  SweepStepper(const BuildInput& input, const BuildOptions& options, std::array<std::vector<uint32_t>, 3>& orders,
               std::vector<double>& rightCost, std::vector<uint8_t>& isLeft, std::vector<uint32_t>& temp)
      : input_(input), options_(options), orders_(orders), rightCost_(rightCost), isLeft_(isLeft), temp_(temp) {}

  detail::NodeStep<Task> step(const Task& task, const Aabb& box) {
    detail::NodeStep<Task> step;
    const uint32_t n = task.end - task.begin;
    if (n == 1) return step;

    // Best object split over the three sorted orders.
    int bestAxis = -1;
    uint32_t bestCount = 0;  // primitives on the left
    double bestCost = 0.0;
    glm::vec3 centroidExtent(0.0f);
    for (int a = 0; a < 3; ++a) {
      const uint32_t* order = orders_[a].data();
      centroidExtent[a] = centroid(order[task.end - 1])[a] - centroid(order[task.begin])[a];
      if (!(centroidExtent[a] > 0.0f)) continue;
      Aabb right;
      for (uint32_t k = task.end - 1; k > task.begin; --k) {
        right.grow(input_.boxes[order[k]]);
        rightCost_[k] = double(right.halfArea()) * (task.end - k);
      }
      Aabb left;
      for (uint32_t k = task.begin; k + 1 < task.end; ++k) {
        left.grow(input_.boxes[order[k]]);
        const uint32_t leftCount = k + 1 - task.begin;
        const double cost = double(left.halfArea()) * leftCount + rightCost_[k + 1];
        if (bestAxis < 0 || cost < bestCost) bestAxis = a, bestCount = leftCount, bestCost = cost;
      }
    }

    const CostModel& c = options_.cost;
    const double area = box.halfArea();
    const bool splitWins =
        bestAxis >= 0 && c.traversalCost * area + c.intersectionCost * bestCost < c.intersectionCost * area * n;
    if (!splitWins && n <= options_.maxLeafSize) return step;
    if (!splitWins) {
      // Median fallback on the longest centroid axis (its order is already sorted); with all
      // centroids equal, that is a split of the index order in half.
      bestAxis = detail::longestAxis(centroidExtent);
      bestCount = n / 2;
    }

    const uint32_t mid = task.begin + bestCount;
    const uint32_t* chosen = orders_[bestAxis].data();
    for (uint32_t k = task.begin; k < mid; ++k) {
      isLeft_[chosen[k]] = 1;
      step.childBox[0].grow(input_.boxes[chosen[k]]);
    }
    for (uint32_t k = mid; k < task.end; ++k) {
      isLeft_[chosen[k]] = 0;
      step.childBox[1].grow(input_.boxes[chosen[k]]);
    }
    for (int a = 0; a < 3; ++a)
      if (a != bestAxis) stablePartition(orders_[a], task, mid);
    step.leaf = false;
    step.child[0] = {0, task.begin, mid};
    step.child[1] = {0, mid, task.end};
    return step;
  }

 private:
  const glm::vec3& centroid(uint32_t prim) const { return input_.centroids[prim]; }

  // Left-marked indices first, both groups keeping their sorted order.
  void stablePartition(std::vector<uint32_t>& order, const Task& task, uint32_t mid) {
    uint32_t l = task.begin, r = mid;
    for (uint32_t k = task.begin; k < task.end; ++k) {
      const uint32_t prim = order[k];
      temp_[isLeft_[prim] ? l++ : r++] = prim;
    }
    std::copy(temp_.begin() + task.begin, temp_.begin() + task.end, order.begin() + task.begin);
  }

  const BuildInput& input_;
  const BuildOptions& options_;
  std::array<std::vector<uint32_t>, 3>& orders_;
  std::vector<double>& rightCost_;
  std::vector<uint8_t>& isLeft_;
  std::vector<uint32_t>& temp_;
};

}  // namespace

Bvh buildSahSweepBvh(const BuildInput& input, const BuildOptions& options) {
  const uint32_t n = uint32_t(input.boxes.size());
  const unsigned threads = detail::resolveThreads(options.threads);
  std::array<std::vector<uint32_t>, 3> orders;
  detail::runJobs(3, threads, [&](size_t a) {
    orders[a].resize(n);
    std::iota(orders[a].begin(), orders[a].end(), 0u);
    std::sort(orders[a].begin(), orders[a].end(), [&](uint32_t i, uint32_t j) {
      const float ci = input.centroids[i][int(a)], cj = input.centroids[j][int(a)];
      return ci < cj || (ci == cj && i < j);
    });
  });
  std::vector<double> rightCost(n);
  std::vector<uint8_t> isLeft(n);
  std::vector<uint32_t> temp(n);

  Aabb all;
  for (const Aabb& b : input.boxes) all.grow(b);
  Bvh bvh;
  bvh.nodes = detail::buildTopDown(all, Task{0, 0, n}, threads, [&] {
    return SweepStepper(input, options, orders, rightCost, isLeft, temp);
  });

  // Every node's range holds the same primitives in all three orders; leaves read them from any one.
  bvh.primIndices = std::move(orders[0]);
  return bvh;
}

}  // namespace bvhlab
