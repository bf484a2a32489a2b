// Update strategy `refit+rotate`: the first frame's tree, refit every later frame with tree rotations
// (builders/rotate.hpp; Kopta et al. 2012), so its topology follows the motion.
#include "builders/rotate.hpp"
#include "builders/update_base.hpp"

namespace bvhlab {

namespace {

class RefitRotate final : public detail::UpdateStrategyBase {
 public:
  using UpdateStrategyBase::UpdateStrategyBase;
  bool update(const FrameTriangles& frame) override {
    checkCount(frame);
    rotations_ = 0;
    if (first()) {
      rebuild(frame);
      return true;
    }
    rotations_ = refitRotateBvh(tree_, frame, options().build.cost);
    return false;
  }
  uint32_t rotations() const override { return rotations_; }

 private:
  uint32_t rotations_ = 0;
};

}  // namespace

std::unique_ptr<UpdateStrategy> makeRefitRotateStrategy(const UpdateSpec& spec, const UpdateOptions& options) {
  return std::make_unique<RefitRotate>(spec, options);
}

}  // namespace bvhlab
