// `--optimize reinsert`: a post-pass over any builder's tree (Bittner, Hapala & Havran 2013,
// "Fast insertion-based optimization of bounding volume hierarchies"): repeatedly remove the nodes
// whose removal and best reinsertion lowers the SAH most, and reinsert them where the SAH grows
// least, until no move gains or the time budget (BuildOptions::optimizeBudgetMs) is spent.
// The SAH never rises; the tree never gets deeper than max(its depth, 64).
#pragma once
#include <cstdint>

#include "builders/bvh.hpp"

namespace bvhlab {

// Optimises `bvh` in place with `options.cost` (and its budget), inner structure only: the tree keeps
// its node count, primIndices and every leaf (slot, range, box). Deterministic: the same tree for any
// thread count. (builders/reinsert.cpp)
void optimizeReinsert(Bvh& bvh, const BuildOptions& options);

// The same with the builder's input: leaves are re-formed too (expanded to single primitives,
// optimised, collapsed by SAH into leaves of at most options.maxLeafSize), so node count, leaves and
// the order of primIndices change; the references (primIndices as a multiset) stay. Trees whose
// leaves cannot be expanded (a leaf box that is not the union of its primitives' boxes: SBVH's
// clipped references) get the pass above. What buildBvh runs. (builders/reinsert_leaves.cpp)
void optimizeReinsert(Bvh& bvh, const BuildInput& input, const BuildOptions& options);

namespace detail {
// The depth bound when the input tree is shallower (see reinsert.cpp).
constexpr uint32_t kReinsertMinDepthLimit = 64;
// The inner-structure pass with a depth bound of max(input depth, depthLimit) (0: kReinsertMinDepthLimit).
void optimizeInnerStructure(Bvh& bvh, const BuildOptions& options, uint32_t depthLimit);
}  // namespace detail

}  // namespace bvhlab
