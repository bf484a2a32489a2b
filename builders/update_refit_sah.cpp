// Update strategy `refit+rebuild:sah>R`: refit, and rebuild when the refit tree's SAH exceeds R x the
// SAH of the tree the last rebuild made (builders/update.hpp). The SAH is builders/bvh.hpp sahCost
// with UpdateOptions::build.cost, computed on every refit frame as part of the update (it is what
// decides), from the sums the refit gathers as it goes (no second pass over the tree; the same
// value bit for bit): a frame kept without a rebuild has SAH <= R x the last rebuild's, by construction.
#include "builders/update_base.hpp"

namespace bvhlab {

namespace {

class RefitRebuildSah final : public detail::UpdateStrategyBase {
 public:
  RefitRebuildSah(const UpdateSpec& spec, const UpdateOptions& options)
      : UpdateStrategyBase(spec, options), ratio_(spec.sahRatio) {}
  bool update(const FrameTriangles& frame) override {
    checkCount(frame);
    if (!first()) {
      SahSums sums;
      refit(frame, &sums);
      const double sah = sahCost(sums, tree_.nodes[0].bounds.halfArea(), options().build.cost);
      // Not "> ratio x last" negated: a NaN (never produced from finite boxes) would rebuild.
      if (sah <= ratio_ * rebuiltSah_) return false;
    }
    rebuild(frame);
    rebuiltSah_ = sahCost(tree_, options().build.cost);
    return true;
  }

 private:
  double ratio_;  // >= 1, finite (parseUpdateSpec)
  double rebuiltSah_ = 0.0;
};

}  // namespace

std::unique_ptr<UpdateStrategy> makeRefitRebuildSahStrategy(const UpdateSpec& spec, const UpdateOptions& options) {
  return std::make_unique<RefitRebuildSah>(spec, options);
}

}  // namespace bvhlab
