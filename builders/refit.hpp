// Refitting a tree to moved triangles: the topology stays, every box is recomputed bottom-up.
//
// A leaf's box becomes the union of the boxes of the triangles it references, an inner node's the
// union of its two children's boxes: exact (min/max of floats, no epsilon), so a refit of a tree over
// triangles that did not move gives back the builder's boxes (bit for bit up to the sign of a zero
// coordinate: min(-0, +0) keeps whichever came first, and the builder and the refit may meet the two
// in different orders). One thread: the work is a single pass over the nodes, and its result cannot
// depend on a thread count. (A refit on several threads, refitSchedule below, splits the nodes
// into subtrees refit side by side: min and max are exact, so the boxes are the same bit for bit.)
//
// A tree whose builder splits primitives (sbvh) references a triangle from several leaves, each box
// holding a clipped part of it; a refit cannot know the clip regions of moved triangles and gives each
// such leaf the box of its whole triangles (still a valid, conservative tree, no longer the builder's).
#pragma once
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "builders/bvh.hpp"

namespace bvhlab {

// The triangles of one frame: triangle i is (v0[i], v1[i], v2[i]); the three spans have one length.
struct FrameTriangles {
  std::span<const glm::vec3> v0, v1, v2;
  size_t size() const { return v0.size(); }
};

// Every node reachable from the root, children before their parent (a post-order), for refitBvh. It
// depends on the topology only: compute it once and reuse it while the topology does not change.
// Throws std::invalid_argument for a tree that is not one (child out of range, node reached twice).
std::vector<uint32_t> refitOrder(const Bvh& bvh);

// Recomputes the boxes of the nodes in `order` (refitOrder(bvh)) from `frame`. Throws
// std::invalid_argument when the spans differ in length or a leaf references a triangle past their
// end, and InputError (datasets/scene.hpp) naming the triangle when a vertex is not finite (the tree
// is left partly refit then). With `sums`, also adds every refit node to it (builders/bvh.hpp
// SahSums, zeroed by the caller): over refitOrder(bvh), sahCost(*sums, root half area, cost) is then
// sahCost(bvh, cost) bit for bit, without a second pass over the tree.
void refitBvh(Bvh& bvh, std::span<const uint32_t> order, const FrameTriangles& frame, SahSums* sums = nullptr);
// The same with the order computed here.
void refitBvh(Bvh& bvh, const FrameTriangles& frame);

// refitOrder cut for `threads` threads: the post-order puts every subtree in a contiguous range ending
// at its root, so subtrees of at most max(kRefitTaskNodes, nodes / (8 x threads)) nodes are tasks
// that threads refit side by side, and the few nodes above them (`top`) follow, in order, on one.
// Depends on the topology only, as refitOrder. One task (the whole order) for one thread or a tree
// too small to split.
constexpr uint32_t kRefitTaskNodes = 256;  // below this a task costs less than handing it to a thread
struct RefitSchedule {
  std::vector<uint32_t> order;                       // refitOrder(bvh)
  std::vector<std::pair<uint32_t, uint32_t>> tasks;  // [begin, end) ranges of `order`, ascending
  std::vector<uint32_t> top;                         // positions in `order` outside every task, ascending
};
RefitSchedule refitSchedule(const Bvh& bvh, unsigned threads);
// refitBvh over a schedule on up to `threads` threads. The same boxes, errors and sums (added in
// `order`, after the refit) as refitBvh(bvh, schedule.order, frame, sums) for any thread count: of
// several bad leaves the one first in `order` is reported.
void refitBvh(Bvh& bvh, const RefitSchedule& schedule, const FrameTriangles& frame, unsigned threads,
              SahSums* sums = nullptr);

// The box of triangle i of the frame (the one builders get: layout/layout.hpp triangleBoxes).
inline Aabb triangleBox(const FrameTriangles& frame, size_t i) {
  Aabb box;
  box.grow(frame.v0[i]);
  box.grow(frame.v1[i]);
  box.grow(frame.v2[i]);
  return box;
}

// Throws InputError ("update: triangle i has a non-finite vertex") for the frame's first triangle with
// a NaN or infinite vertex coordinate. Checked on the vertices: min/max drop a NaN silently, so a box
// alone (which validateBuildInput checks) may hide one.
void checkFiniteVertices(const FrameTriangles& frame);

}  // namespace bvhlab
