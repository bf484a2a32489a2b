// Sorting the Morton-coded keys of the bottom-up builders (lbvh, ploc) into code order.
#pragma once
#include "builders/morton.hpp"
#include "builders/scratch.hpp"

namespace bvhlab::detail {

// Sorts keys by code, stably: equal codes keep their input order, so the result is unique and the
// same for any thread count (threads only split the work).
void sortMortonKeys(ScratchVector<Keyed>& keys, unsigned threads);

}  // namespace bvhlab::detail
