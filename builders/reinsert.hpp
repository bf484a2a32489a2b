// `--optimize reinsert`: a post-pass over any builder's tree (Bittner, Hapala & Havran 2013,
// "Fast insertion-based optimization of bounding volume hierarchies"): repeatedly remove the nodes
// whose removal and best reinsertion lowers the SAH most, and reinsert them where the SAH grows
// least, until no move gains or the time budget (BuildOptions::optimizeBudgetMs) is spent.
// The tree keeps its primitives and leaves; only inner structure changes. The SAH never rises.
#pragma once
#include "builders/bvh.hpp"

namespace bvhlab {

// Optimises `bvh` in place with `options.cost` (and its budget). Deterministic: the same tree for
// any thread count.
void optimizeReinsert(Bvh& bvh, const BuildOptions& options);

}  // namespace bvhlab
