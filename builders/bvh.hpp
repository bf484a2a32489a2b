// The one binary-BVH type every builder emits, and the cost model they share.
// Builders are primitive-agnostic: they see boxes and centroids, never triangles.
#pragma once
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace bvhlab {

struct Aabb {
  glm::vec3 min{std::numeric_limits<float>::infinity()};
  glm::vec3 max{-std::numeric_limits<float>::infinity()};

  void grow(const glm::vec3& p) { min = glm::min(min, p); max = glm::max(max, p); }
  void grow(const Aabb& b) { min = glm::min(min, b.min); max = glm::max(max, b.max); }
  bool empty() const { return !(min.x <= max.x && min.y <= max.y && min.z <= max.z); }
  glm::vec3 extent() const { return max - min; }
  glm::vec3 center() const { return 0.5f * (min + max); }
  // Half the surface area: the SAH only needs ratios, and Embree/tinybvh use the half area too.
  float halfArea() const {
    if (empty()) return 0.0f;
    glm::vec3 e = extent();
    return e.x * e.y + e.y * e.z + e.z * e.x;
  }
  bool contains(const Aabb& b) const {
    return glm::all(glm::lessThanEqual(min, b.min)) && glm::all(glm::greaterThanEqual(max, b.max));
  }
};

// A node of the binary BVH. Inner nodes: count == 0, children at `first` and `first + 1` are NOT
// implied: `left`/`right` are explicit so builders may emit in any order; the packer re-orders
// depth-first (see layout/layout.hpp).
struct BvhNode {
  Aabb bounds;
  uint32_t left = 0, right = 0;   // inner: child node indices
  uint32_t first = 0, count = 0;  // leaf: range in Bvh::primIndices; count > 0 marks a leaf
  bool isLeaf() const { return count > 0; }
};

struct Bvh {
  std::vector<BvhNode> nodes;         // nodes[0] is the root
  std::vector<uint32_t> primIndices;  // leaf ranges index this; entries are input primitive ids
};

// SAH cost model shared by every builder (Ct = Ci = 1 by default, half areas, normalised by the
// root's area: the convention of Embree and tinybvh, so our figures compare with theirs).
struct CostModel {
  float traversalCost = 1.0f;     // Ct
  float intersectionCost = 1.0f;  // Ci
};

enum class MortonGrid : uint8_t { Cube, Axes };

struct BuildOptions {
  uint32_t maxLeafSize = 4;  // 1..kMaxLeafSize primitives per leaf
  CostModel cost;
  uint32_t bins = 0;         // sah-binned, sbvh: bin count (0 = the builder's measured default)
  // sbvh (Stich, Friedrich & Dietrich 2009): a spatial split is tried at a node only when the overlap
  // of its best object split's children, as a fraction of the root's area, exceeds alpha; at most
  // referenceBudget x primitives leaf references in all.
  float sbvhAlpha = 1e-5f;
  float sbvhReferenceBudget = 2.0f;
  uint32_t plocRadius = 16;  // ploc (Meister & Bittner 2018): nearest-neighbour search radius in Morton order
  // ploc: 0 (default) clusters to the end, as the paper does. F > 0: once the clusters are down to
  // n / F, those are split top-down by binned SAH (sah-binned over the cluster boxes, one cluster per
  // leaf) instead: PLOC for the bottom of the tree, SAH for its top, where PLOC loses most of its SAH
  // (docs/builders.md, "The knobs"). 0..kMaxPlocTopDown.
  uint32_t plocTopDown = 0;
  // ploc, lbvh: bits of each primitive's size (the square root of its box diagonal over the scene's)
  // among the upper bits of its Morton code (Vinkler, Bittner & Havran 2017; builders/morton.hpp),
  // 0..kMaxMortonSizeBits. 0 = plain position codes (measured: no setting helps on scanned meshes).
  uint32_t mortonSizeBits = 0;
  // ploc, lbvh: the grid the Morton codes quantise centroids on (builders/morton.hpp). Cube (default):
  // one cell size on every axis, the longest centroid extent over 2^21; Axes: each axis over its own
  // extent (the codes before December 2026), which stretches the cells of a flat or long scene along
  // its short axes (measured in docs/builders.md: lbvh's SAH up to 20-24% lower with the cube on the
  // interior and terrain bench scenes, within +-1.6% on the scans).
  MortonGrid mortonGrid = MortonGrid::Cube;
  // A post-pass after any builder: "" (none) or "reinsert" (Bittner et al. 2013).
  std::string optimize;
  double optimizeBudgetMs = 0.0;  // reinsert: stop after this long (0 = run to convergence)
  // Worker threads for builders that split their top levels into tasks (0 = hardware concurrency).
  // The tree never depends on it: the task split is fixed and results are spliced in a fixed order.
  uint32_t threads = 0;
};

// Input: one box and one centroid per primitive (same length). When the primitives are triangles,
// v0/v1/v2 may give their vertices (same length again): builders that split primitives (sbvh) clip
// the triangles themselves then, and clip the boxes when they are empty.
struct BuildInput {
  std::span<const Aabb> boxes;
  std::span<const glm::vec3> centroids;
  std::span<const glm::vec3> v0 = {}, v1 = {}, v2 = {};
  bool hasTriangles() const { return !v0.empty(); }
};

struct BuildStats {
  std::string builder;
  uint32_t leafSize = 0;
  size_t primitives = 0, nodes = 0, leaves = 0;
  size_t references = 0;   // leaf entries: == primitives unless a builder splits primitives (sbvh)
  double sahBeforeOptimize = 0.0;  // the builder's own tree's SAH when a post-pass ran (else == sahCost)
  double optimizeMs = 0.0;         // the post-pass's time (included in buildMs)
  uint32_t depth = 0;      // root alone = depth 1
  double sahCost = 0.0;    // normalised by root half-area
  double buildMs = 0.0;
  size_t bytes = 0;        // packed layout bytes (nodes + triangles + attributes), filled by the packer
  double primsPerLeafMean = 0.0;
  uint32_t primsPerLeafMax = 0;
};

constexpr uint32_t kMaxLeafSize = 255;  // the packed node stores a leaf count in 8 bits
// One size bit per 7 code bits (6 of position, builders/morton.hpp) in a 63-bit code: at most 9.
constexpr uint32_t kMaxMortonSizeBits = 9;
// BuildOptions::plocTopDown: a divisor of the primitive count (the measured range is 2..64).
constexpr uint32_t kMaxPlocTopDown = 1024;
// BuildOptions::plocRadius: 1..kMaxPlocRadius (the search costs O(radius) per cluster and pass).
constexpr uint32_t kMaxPlocRadius = 1024;

// SAH cost of a built tree with the given model (recomputed from the tree, not trusted from a builder).
// The sums run over the nodes in builders/refit.hpp refitOrder (children before their parent), the
// order refitBvh visits them in, so a refit that gathers them (SahSums) gives this cost bit for bit.
double sahCost(const Bvh& bvh, const CostModel& cost);
// What sahCost sums over the nodes reachable from the root, node by node in refitOrder.
struct SahSums {
  double innerArea = 0.0;   // inner nodes' half areas
  double leafArea = 0.0;    // leaves' half areas x their primitive counts
  double innerNodes = 0.0;  // counts, for a root of zero area
  double references = 0.0;
  void add(const BvhNode& node) {
    const double area = node.bounds.halfArea();
    if (node.isLeaf()) {
      leafArea += area * node.count;
      references += node.count;
    } else {
      innerArea += area;
      innerNodes += 1.0;
    }
  }
};
// The cost from the sums and the root's half area. Throws std::runtime_error when that is not finite.
double sahCost(const SahSums& sums, double rootHalfArea, const CostModel& cost);
// Node/leaf/depth/leaf-size statistics of a built tree (sahCost included; buildMs/bytes left 0).
BuildStats computeStats(const Bvh& bvh, const CostModel& cost);

}  // namespace bvhlab
