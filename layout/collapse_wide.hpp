// The SAH-optimal collapse of a binary BVH into a wide one (Ylitie, Karras & Laine 2017, "Efficient
// Incoherent Ray Traversal on GPUs Through Compressed Wide BVHs", section 4.1), generic in the width W.
//
// A dynamic program over (binary node n, number of slots i = 1..W): C(n, i) is the least SAH cost of
// representing n's subtree by at most i wide-tree nodes (the "slots" it may occupy in its parent):
//   C(n, 1) = min(Cleaf(n), Cinternal(n))
//   C(n, i) = min(Cdistribute(n, i), C(n, i - 1))                         for i > 1
//   Cleaf(n)        = Ci * A(n) * P(n)   (P(n): n's leaf references; infinite when P(n) exceeds the
//                                         leaf cap and n is not already a binary leaf)
//   Cinternal(n)    = Ct * A(n) + Cdistribute(n, W)          (n becomes a wide node)
//   Cdistribute(n,j)= min over 0 < k < j of C(left, k) + C(right, j - k)
// A binary leaf is always a leaf (C(n, i) = Cleaf(n), whatever its size: the collapse never splits a
// leaf the builder made). A(n) is n's half area over the root's (the project's SAH convention,
// builders/bvh.hpp), Ct and Ci the CostModel's. The root is always an inner wide node (a kernel
// starts at a record) unless the binary root is itself a leaf.
#pragma once
#include <cstdint>
#include <vector>

#include "builders/bvh.hpp"

namespace bvhlab {

struct WideChild {
  uint32_t binaryNode;  // the binary node this child stands for; its box is the child's box
  bool leaf;            // a leaf: all references of binaryNode's subtree; else an inner wide node
  uint32_t wideNode;    // inner: index into WideTree::nodes (unused for a leaf)
};

struct WideNode {
  uint32_t binaryNode;              // the binary node the wide node replaces (same box)
  std::vector<WideChild> children;  // 2..W, in the binary tree's left-to-right order
};

struct WideTree {
  uint32_t width = 0;
  // nodes[0] is the root, in depth-first pre-order (a node's inner children come after it). Empty when
  // the binary root is a leaf: the whole tree is then that one leaf.
  std::vector<WideNode> nodes;
  double cost = 0.0;  // the program's C at the root, normalised like sahCost (builders/bvh.hpp)
};

// Throws std::invalid_argument for a width outside 2..32, a leaf cap of 0, or an empty tree.
WideTree collapseWide(const Bvh& bvh, uint32_t width, const CostModel& cost, uint32_t maxLeafSize);

// The SAH cost of a wide tree, recomputed from its nodes (same normalisation): Ct * sum of inner wide
// node areas + Ci * sum over leaves of area * references, over the root's area.
double wideSahCost(const Bvh& bvh, const WideTree& wide, const CostModel& cost);

// Leaf references of every binary node's subtree (sbvh's duplicates counted as often as they occur).
std::vector<uint32_t> subtreeReferences(const Bvh& bvh);

}  // namespace bvhlab
