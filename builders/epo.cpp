// End-Point Overlap (builders/epo.hpp): exact triangle/box clipping, and a BVH query per node that
// finds the triangles of other subtrees overlapping the node's box.
#include "builders/epo.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <exception>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace bvhlab {

namespace {

// A clipped polygon. One half-space clip emits at most two vertices per input vertex (the vertex
// and the crossing on its outgoing edge), so three vertices clipped by six planes never exceed
// 3 * 2^6. In exact arithmetic a convex polygon gains at most one vertex per plane (9 in all); the
// bound that does not rely on convexity also holds when rounding bends an edge by an ulp.
struct Polygon {
  std::array<glm::dvec3, 3 * 64> v;
  int n = 0;
};

// Keeps the part of `in` on the inner side of the plane p[axis] = plane: p[axis] >= plane when
// `lower`, p[axis] <= plane otherwise. Points on the plane are kept (closed boxes). A crossing gets
// the plane's value in `axis` exactly, so later clips against the opposite face of a flat box see it
// on that face instead of an interpolation's rounding off it.
void clipHalfSpace(const Polygon& in, Polygon& out, int axis, double plane, bool lower) {
  out.n = 0;
  for (int i = 0; i < in.n; ++i) {
    const glm::dvec3& p = in.v[i];
    const glm::dvec3& q = in.v[(i + 1) % in.n];
    const double dp = lower ? p[axis] - plane : plane - p[axis];
    const double dq = lower ? q[axis] - plane : plane - q[axis];
    if (dp >= 0.0) out.v[out.n++] = p;
    if ((dp >= 0.0) != (dq >= 0.0)) {  // one side each: dp - dq is not 0, t lies in [0, 1]
      glm::dvec3 x = p + (dp / (dp - dq)) * (q - p);
      x[axis] = plane;
      out.v[out.n++] = x;
    }
  }
}

// Area of a planar polygon: half the length of the sum of its fan's cross products.
double polygonArea(const Polygon& poly) {
  glm::dvec3 sum(0.0);
  for (int i = 1; i + 1 < poly.n; ++i) sum += glm::cross(poly.v[i] - poly.v[0], poly.v[i + 1] - poly.v[0]);
  return 0.5 * glm::length(sum);
}

// The clip with caller-owned buffers (two polygons are 9 KiB; the EPO reuses one pair per thread).
double clippedArea(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, const Aabb& box, Polygon& p,
                   Polygon& q) {
  if (box.empty()) return 0.0;
  p.v[0] = a, p.v[1] = b, p.v[2] = c;
  p.n = 3;
  // Only the planes the triangle crosses: a plane with all three vertices inside has the whole
  // triangle inside (the clipped polygon is a part of the triangle), so clipping against it would
  // return the polygon unchanged. Skipping it cut the clipping's share of the bunny's EPO profile
  // from 32% to 18%: a triangle that sticks out of a box rarely crosses more than one or two faces.
  const glm::dvec3 lo = glm::min(a, glm::min(b, c)), hi = glm::max(a, glm::max(b, c));
  Polygon *in = &p, *out = &q;
  for (int axis = 0; axis < 3; ++axis) {
    if (lo[axis] < box.min[axis]) {
      clipHalfSpace(*in, *out, axis, box.min[axis], true);
      std::swap(in, out);
    }
    if (hi[axis] > box.max[axis]) {
      clipHalfSpace(*in, *out, axis, box.max[axis], false);
      std::swap(in, out);
    }
    if (in->n < 3) return 0.0;
  }
  return polygonArea(*in);
}

bool finite(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// Closed-box overlap; false when either box is empty. Written out per component: it is the query's
// innermost test.
inline bool overlaps(const Aabb& a, const Aabb& b) {
  return a.min.x <= b.max.x && b.min.x <= a.max.x && a.min.y <= b.max.y && b.min.y <= a.max.y &&
         a.min.z <= b.max.z && b.min.z <= a.max.z;
}

// `inner` lies in the closed box `outer`.
inline bool inside(const Aabb& inner, const Aabb& outer) {
  return outer.min.x <= inner.min.x && inner.max.x <= outer.max.x && outer.min.y <= inner.min.y &&
         inner.max.y <= outer.max.y && outer.min.z <= inner.min.z && inner.max.z <= outer.max.z;
}

// The reachable tree in depth-first pre-order (left child first), so that the subtree of node i is
// the id range [i, end) and "is an ancestor of" is a range test.
struct FlatNode {
  Aabb geometry;         // tight box of the subtree's triangles, from their vertices (the query prunes
                         // with it, so a builder's box that is too small or too large cannot hide area)
  double area = 0.0;     // total area of the subtree's triangles referenced once in the whole tree
  bool shared = false;   // the subtree references a triangle that is referenced more than once
  uint32_t left = 0, right = 0;   // inner: children's ids
  uint32_t end = 0;               // one past the subtree's last id
  uint32_t first = 0, count = 0;  // leaf: range in Bvh::primIndices
};

struct Prepared {
  std::vector<FlatNode> nodes;  // what the query walks
  std::vector<Aabb> boxes;      // per node id, the builder's box: the region whose overlap is measured
  std::vector<Aabb> triBox;     // per triangle, exact (min/max of float vertices)
  std::vector<double> triArea;  // per triangle
  double totalArea = 0.0;
  // Triangles referenced by more than one leaf entry (builders that split primitives, e.g. sbvh):
  // shared[t], and the pre-order ids of the leaves that reference t in
  // leafIds[leafBegin[t], leafBegin[t + 1]), ascending. Empty when every triangle is referenced once.
  std::vector<uint8_t> shared;
  std::vector<uint32_t> leafBegin, leafIds;
  bool anyShared = false;
};

Prepared prepare(const Bvh& bvh, std::span<const glm::vec3> v0, std::span<const glm::vec3> v1,
                 std::span<const glm::vec3> v2) {
  const size_t triangles = v0.size();
  if (v1.size() != triangles || v2.size() != triangles)
    throw std::invalid_argument("endPointOverlap: the vertex spans differ in length (" + std::to_string(v0.size()) +
                                ", " + std::to_string(v1.size()) + ", " + std::to_string(v2.size()) + ")");
  if (bvh.nodes.empty()) throw std::invalid_argument("endPointOverlap: the tree has no nodes");

  Prepared p;
  p.triBox.resize(triangles);
  p.triArea.resize(triangles);
  for (size_t t = 0; t < triangles; ++t) {
    if (!finite(v0[t]) || !finite(v1[t]) || !finite(v2[t]))
      throw std::invalid_argument("endPointOverlap: triangle " + std::to_string(t) + " has a non-finite vertex");
    p.triBox[t].grow(v0[t]);
    p.triBox[t].grow(v1[t]);
    p.triBox[t].grow(v2[t]);
    // The same operations polygonArea does on an unclipped triangle (clipping keeps the vertex order),
    // so a triangle inside a box counts the same area whether the query takes the shortcut (box
    // contained) or clips it.
    p.triArea[t] = triangleArea(v0[t], v1[t], v2[t]);
    p.totalArea += p.triArea[t];
  }

  // Pre-order ids, with the walk's cycle / range checks (as in builders/stats.cpp).
  std::vector<uint32_t> order;                                    // id -> original index
  std::vector<uint32_t> idOf(bvh.nodes.size(), UINT32_MAX);       // original index -> id
  std::vector<uint32_t> stack{0u};
  while (!stack.empty()) {
    const uint32_t index = stack.back();
    stack.pop_back();
    if (index >= bvh.nodes.size() || idOf[index] != UINT32_MAX)
      throw std::invalid_argument("endPointOverlap: malformed BVH: child index out of range or node reached twice");
    if (order.size() >= 0x7FFFFFFFu)
      throw std::invalid_argument("endPointOverlap: more than 2^31 - 1 nodes");
    idOf[index] = uint32_t(order.size());
    order.push_back(index);
    const BvhNode& node = bvh.nodes[index];
    if (!node.isLeaf()) {
      stack.push_back(node.right);
      stack.push_back(node.left);
    }
  }

  p.nodes.resize(order.size());
  p.boxes.resize(order.size());
  std::vector<uint32_t> referenced(triangles, 0);
  for (size_t id = 0; id < order.size(); ++id) {
    const BvhNode& node = bvh.nodes[order[id]];
    FlatNode& f = p.nodes[id];
    if (!finite(node.bounds.min) || !finite(node.bounds.max))
      throw std::invalid_argument("endPointOverlap: node " + std::to_string(order[id]) + " has a non-finite box");
    p.boxes[id] = node.bounds;
    if (node.isLeaf()) {
      if (size_t(node.first) + node.count > bvh.primIndices.size())
        throw std::invalid_argument("endPointOverlap: leaf " + std::to_string(order[id]) +
                                    " range is outside primIndices");
      f.first = node.first, f.count = node.count;
      for (uint32_t k = node.first; k < node.first + node.count; ++k) {
        const uint32_t t = bvh.primIndices[k];
        if (t >= triangles)
          throw std::invalid_argument("endPointOverlap: primitive " + std::to_string(t) + " is out of range (" +
                                      std::to_string(triangles) + " triangles)");
        ++referenced[t];
      }
    } else {
      f.left = idOf[node.left], f.right = idOf[node.right];
    }
  }
  for (size_t t = 0; t < triangles; ++t)
    if (!referenced[t])
      throw std::invalid_argument("endPointOverlap: triangle " + std::to_string(t) + " is in no leaf of the tree");
  p.shared.assign(triangles, 0);
  for (size_t t = 0; t < triangles; ++t)
    if (referenced[t] > 1) p.shared[t] = 1, p.anyShared = true;
  if (p.anyShared) {
    p.leafBegin.assign(triangles + 1, 0);
    for (size_t t = 0; t < triangles; ++t) p.leafBegin[t + 1] = p.leafBegin[t] + (p.shared[t] ? referenced[t] : 0);
    p.leafIds.resize(p.leafBegin[triangles]);
    std::vector<uint32_t> fill(p.leafBegin.begin(), p.leafBegin.end() - 1);
    for (size_t id = 0; id < p.nodes.size(); ++id) {  // ascending ids: each list comes out sorted
      const FlatNode& f = p.nodes[id];
      for (uint32_t k = f.first; k < f.first + f.count; ++k)
        if (p.shared[bvh.primIndices[k]]) p.leafIds[fill[bvh.primIndices[k]]++] = uint32_t(id);
    }
  }

  // Bottom-up in reverse pre-order: children have larger ids than their parent. The right child is
  // walked after the left one, so its subtree ends where the parent's does.
  for (size_t id = p.nodes.size(); id-- > 0;) {
    FlatNode& f = p.nodes[id];
    if (f.count > 0) {
      f.end = uint32_t(id + 1);
      for (uint32_t k = f.first; k < f.first + f.count; ++k) {
        const uint32_t t = bvh.primIndices[k];
        f.geometry.grow(p.triBox[t]);
        if (p.shared[t])
          f.shared = true;
        else
          f.area += p.triArea[t];
      }
    } else {
      const FlatNode &l = p.nodes[f.left], &r = p.nodes[f.right];
      f.end = r.end;
      f.geometry = l.geometry;
      f.geometry.grow(r.geometry);
      f.area = l.area + r.area;
      f.shared = l.shared || r.shared;
    }
  }
  return p;
}

// A((S \ Q(n)) ∩ box(n)): walks the tree from the root, skipping n's subtree and everything whose
// triangles cannot reach n's box. The walk order is fixed, so the sum is the same on every thread.
class OverlapQuery {
 public:
  OverlapQuery(const Prepared& p, std::span<const uint32_t> primIndices, std::span<const glm::vec3> v0,
               std::span<const glm::vec3> v1, std::span<const glm::vec3> v2)
      : p_(p), prims_(primIndices), v0_(v0), v1_(v1), v2_(v2) {}

  // Q(n) is the SET of triangles referenced in n's subtree. A triangle referenced once is outside
  // Q(n) exactly when its leaf is outside n's subtree, which the walk's skip of n gives for free. A
  // triangle referenced by several leaves (a builder that splits primitives) is counted at most
  // once per node, and only when none of its leaves lies in n's subtree.
  double operator()(uint32_t n) {
    const Aabb& box = p_.boxes[n];
    const uint32_t end = p_.nodes[n].end;
    double sum = 0.0;
    stack_.assign(1, 0u);
    while (!stack_.empty()) {
      const uint32_t entry = stack_.back();
      stack_.pop_back();
      const uint32_t m = entry & ~kInsideBit;
      if (m == n) continue;  // Q(n): the surfaces a visit to n is for
      const FlatNode& f = p_.nodes[m];
      if (entry & kInsideBit) {
        // Below a subtree that lies wholly inside the box (not an ancestor of n) whose once-referenced
        // area is already summed: what is left are its shared triangles, each whole inside the box.
        if (!f.shared) continue;
        if (f.count == 0) {
          stack_.push_back(f.right | kInsideBit);
          stack_.push_back(f.left | kInsideBit);
          continue;
        }
        for (uint32_t k = f.first; k < f.first + f.count; ++k) {
          const uint32_t t = prims_[k];
          if (p_.shared[t] && firstOutsideQ(t, n, end)) sum += p_.triArea[t];
        }
        continue;
      }
      if (!overlaps(f.geometry, box)) continue;
      // A subtree wholly inside the box contributes all its area, unless it holds n (an ancestor).
      const bool ancestor = m < n && n < f.end;
      if (!ancestor && inside(f.geometry, box)) {
        sum += f.area;
        if (f.shared) stack_.push_back(m | kInsideBit);
        continue;
      }
      if (f.count == 0) {
        stack_.push_back(f.right);
        stack_.push_back(f.left);
        continue;
      }
      for (uint32_t k = f.first; k < f.first + f.count; ++k) {
        const uint32_t t = prims_[k];
        if (!overlaps(p_.triBox[t], box)) continue;
        if (p_.anyShared && p_.shared[t] && !firstOutsideQ(t, n, end)) continue;
        sum += inside(p_.triBox[t], box) ? p_.triArea[t] : clippedArea(v0_[t], v1_[t], v2_[t], box, a_, b_);
      }
    }
    return sum;
  }

 private:
  static constexpr uint32_t kInsideBit = 0x80000000u;  // prepare() keeps node ids below it

  // For a shared triangle t: true the first time this query for node n (subtree ids [n, end)) meets
  // it, if no leaf of n's subtree references it.
  bool firstOutsideQ(uint32_t t, uint32_t n, uint32_t end) {
    if (stamp_.empty()) stamp_.assign(p_.triArea.size(), 0u);
    if (stamp_[t] == n + 1) return false;
    stamp_[t] = n + 1;
    const auto first = p_.leafIds.begin() + p_.leafBegin[t], last = p_.leafIds.begin() + p_.leafBegin[t + 1];
    const auto it = std::lower_bound(first, last, n);
    return !(it != last && *it < end);
  }

  const Prepared& p_;
  std::span<const uint32_t> prims_;
  std::span<const glm::vec3> v0_, v1_, v2_;
  std::vector<uint32_t> stack_;
  std::vector<uint32_t> stamp_;  // per triangle: n + 1 once the query for node n has met it
  Polygon a_, b_;
};

}  // namespace

double triangleArea(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
  return 0.5 * glm::length(glm::cross(b - a, c - a));
}

double clippedTriangleArea(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, const Aabb& box) {
  Polygon p, q;
  return clippedArea(a, b, c, box, p, q);
}

double endPointOverlap(const Bvh& bvh, std::span<const glm::vec3> v0, std::span<const glm::vec3> v1,
                       std::span<const glm::vec3> v2, const CostModel& cost, unsigned threads) {
  const Prepared p = prepare(bvh, v0, v1, v2);
  if (!(p.totalArea > 0.0)) return 0.0;  // no surface, no end points (see the header)

  const size_t count = p.nodes.size();
  std::vector<double> overlap(count, 0.0);
  // Nodes are handed out in chunks from a shared counter: the cost per node varies by orders of
  // magnitude (a node near the root overlaps much of the scene), so a static split would idle threads.
  constexpr size_t kChunk = 64;
  std::atomic<size_t> next{0};
  std::exception_ptr failure;
  std::mutex failureMutex;
  auto work = [&] {
    try {
      OverlapQuery query(p, bvh.primIndices, v0, v1, v2);
      for (size_t begin; (begin = next.fetch_add(kChunk)) < count;)
        for (size_t n = begin; n < std::min(count, begin + kChunk); ++n) overlap[n] = query(uint32_t(n));
    } catch (...) {
      std::lock_guard<std::mutex> lock(failureMutex);
      if (!failure) failure = std::current_exception();
      next = count;  // the others stop at their next chunk
    }
  };
  if (threads == 0) threads = std::max(1u, std::thread::hardware_concurrency());
  threads = unsigned(std::min<size_t>(threads, (count + kChunk - 1) / kChunk));
  std::vector<std::thread> pool;
  for (unsigned i = 1; i < threads; ++i) pool.emplace_back(work);
  work();
  for (std::thread& t : pool) t.join();
  if (failure) std::rethrow_exception(failure);

  // Reduced in pre-order, whatever thread computed each term.
  double sum = 0.0;
  for (size_t n = 0; n < count; ++n) {
    const FlatNode& f = p.nodes[n];
    const double c = f.count > 0 ? double(cost.intersectionCost) * f.count : double(cost.traversalCost);
    sum += c * overlap[n];
  }
  return sum / p.totalArea;
}

}  // namespace bvhlab
