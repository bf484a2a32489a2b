// Update strategy `refit+rebuild:K`: a rebuild on frames 0, K, 2K, ... (counting the strategy's
// updates from 0), a refit on the others (builders/update.hpp).
#include "builders/update_base.hpp"

namespace bvhlab {

namespace {

class RefitRebuildEvery final : public detail::UpdateStrategyBase {
 public:
  RefitRebuildEvery(const UpdateSpec& spec, const UpdateOptions& options)
      : UpdateStrategyBase(spec, options), every_(spec.every) {}
  bool update(const FrameTriangles& frame) override {
    checkCount(frame);
    const bool due = frame_ % every_ == 0;
    ++frame_;
    if (due) {
      rebuild(frame);
      return true;
    }
    refit(frame);
    return false;
  }

 private:
  uint64_t every_;      // >= 1 (parseUpdateSpec)
  uint64_t frame_ = 0;  // updates so far
};

}  // namespace

std::unique_ptr<UpdateStrategy> makeRefitRebuildEveryStrategy(const UpdateSpec& spec, const UpdateOptions& options) {
  return std::make_unique<RefitRebuildEvery>(spec, options);
}

}  // namespace bvhlab
