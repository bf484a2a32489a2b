// H-PLOC's definition, shared by the CPU builder (builders/hploc.cpp) and the GPU one
// (builders/gpu/gpu_hploc.hpp, gpubuild_hploc.glsl), which build the same tree.
//
// Benthin, Meister, Barczak, Mehalwal, Tsakok & Kensler 2024, "H-PLOC: Hierarchical Parallel
// Locally-Ordered Clustering for Bounding Volume Hierarchy Construction" (HPG 2024, Proc. ACM CGIT
// 7(3)). PLOC's clustering (Meister & Bittner 2018) runs inside the subtrees of the LBVH radix tree
// over the sorted Morton codes instead of over the whole array:
//  - The radix tree is found bottom-up (Apetrei 2014, "Fast and Simple Agglomerative LBVH
//    Construction"): the subtree of sorted positions [L, R] is its parent's left child when
//    delta(R) < delta(L - 1) (or L = 0), its right child otherwise (or R = n - 1), delta(i) being
//    the XOR of the keys at i and i + 1: (code, position), compared code first. The smaller XOR
//    is the more similar pair, the boundary the parent spans. Keys are distinct (positions are), so
//    the tree is the radix tree of the keys.
//  - Each subtree holds a list of clusters (nodes of the final tree) in Morton order; a leaf's is
//    itself. A parent's list is the left child's followed by the right's, at most 2 kKeep = kGroup
//    clusters; when the parent spans more than kKeep primitives (or is the root), PLOC passes run
//    over that list until at most kKeep clusters are left (the root: one). A pass is ploc's
//    (builders/ploc.cpp): every cluster's nearest neighbour within +-radius positions of the list by
//    builders/ploc_keys.hpp's keys, mutual pairs merged at the lower position (left child the lower
//    one), the list compacted in order.
//  - A subtree whose keys all have one Morton code (primitives the codes cannot tell apart) is the
//    radix tree's own node over its two children, each then one cluster: a tree balanced by the
//    positions, as ploc makes a balanced tree of each run of equal codes. Clustering such boxes
//    (one centre, nested sizes) would chain them: depth 51 for 3000 nested boxes, where the radix
//    tree gives 12.
// What one node's list becomes depends only on its children's lists, so the tree does not depend on
// the order in which subtrees finish: the GPU's order (the second thread to reach a node goes on)
// and the CPU's (jobs of leaves on any number of threads) give the same tree.
#pragma once
#include <cstdint>

namespace bvhlab::detail::hploc {

// The clusters a group holds at once: the GPU's workgroup, one cluster per invocation (a warp on
// NVIDIA, as the paper's). A radius of kGroup - 1 or more searches the whole list.
constexpr uint32_t kGroup = 32;
// A subtree of more primitives is clustered down to this many clusters (the paper's threshold: half
// the group, so that two children's lists fill one group).
constexpr uint32_t kKeep = kGroup / 2;

}  // namespace bvhlab::detail::hploc
