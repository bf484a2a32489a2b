// Update strategy `rebuild`: a new tree every frame with the configured builder (builders/update.hpp).
#include "builders/update_base.hpp"

namespace bvhlab {

namespace {

class Rebuild final : public detail::UpdateStrategyBase {
 public:
  using UpdateStrategyBase::UpdateStrategyBase;
  bool update(const FrameTriangles& frame) override {
    checkCount(frame);
    rebuild(frame);
    return true;
  }
};

}  // namespace

std::unique_ptr<UpdateStrategy> makeRebuildStrategy(const UpdateSpec& spec, const UpdateOptions& options) {
  return std::make_unique<Rebuild>(spec, options);
}

}  // namespace bvhlab
