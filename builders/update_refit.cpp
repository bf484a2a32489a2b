// Update strategy `refit`: the first frame's tree, its boxes refit every later frame
// (builders/update.hpp, builders/refit.hpp).
#include "builders/update_base.hpp"

namespace bvhlab {

namespace {

class Refit final : public detail::UpdateStrategyBase {
 public:
  using UpdateStrategyBase::UpdateStrategyBase;
  bool update(const FrameTriangles& frame) override {
    checkCount(frame);
    if (first()) {
      rebuild(frame);
      return true;
    }
    refit(frame);
    return false;
  }
};

}  // namespace

std::unique_ptr<UpdateStrategy> makeRefitStrategy(const UpdateSpec& spec, const UpdateOptions& options) {
  return std::make_unique<Refit>(spec, options);
}

}  // namespace bvhlab
