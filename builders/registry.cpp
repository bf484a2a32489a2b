// The builder registry and the one entry point that validates, times and measures a build.
// Adding a builder: write builders/NAME.cpp with a `Bvh buildX(const BuildInput&, const BuildOptions&)`
// and add its declaration + one line to the table below.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "builders/builder.hpp"
#include "builders/reinsert.hpp"
#include "datasets/scene.hpp"  // InputError

namespace bvhlab {

// Defined in builders/<name>.cpp.
Bvh buildMedianBvh(const BuildInput&, const BuildOptions&);
Bvh buildSahBinnedBvh(const BuildInput&, const BuildOptions&);
Bvh buildSahSweepBvh(const BuildInput&, const BuildOptions&);
Bvh buildSbvh(const BuildInput&, const BuildOptions&);
Bvh buildLbvh(const BuildInput&, const BuildOptions&);
Bvh buildPloc(const BuildInput&, const BuildOptions&);
Bvh buildHploc(const BuildInput&, const BuildOptions&);
Bvh buildEmbreeBvh(const BuildInput&, const BuildOptions&);
Bvh buildEmbreeLowBvh(const BuildInput&, const BuildOptions&);

namespace {

std::vector<BuilderInfo>& table() {
  static std::vector<BuilderInfo> table = {
      {"median", "complete binary tree, object-median splits on the longest axis, full leaves",
       buildMedianBvh},
      {"sah-binned", "binned SAH (options.bins bins per axis, 64 by default), median fallback", buildSahBinnedBvh,
       /*usesBins=*/true},
      {"sah-sweep", "full-sweep SAH: exact best object split over centroids sorted on all axes", buildSahSweepBvh},
      {"sbvh", "SBVH: binned object + spatial splits (triangles clipped), alpha, reference budget, unsplitting", buildSbvh,
       /*usesBins=*/true, /*usesSbvhAlpha=*/true},
      {"lbvh", "Morton-code radix tree (LBVH), SAH-collapsed leaves", buildLbvh, false, false, false, kMaxLeafSize,
       /*usesMortonSizeBits=*/true},
      {"ploc", "PLOC: bottom-up clustering in Morton order, neighbours within +-plocRadius, SAH-collapsed leaves; "
               "plocTopDown F: the last n/F clusters split top-down by binned SAH",
       buildPloc, false, false, /*usesPlocRadius=*/true, kMaxLeafSize, /*usesMortonSizeBits=*/true},
      {"hploc", "H-PLOC: ploc's clustering inside the subtrees of the LBVH radix tree, bottom-up, a subtree above "
                "16 primitives cut to 16 clusters (neighbours within +-plocRadius); hploc-gpu's tree, built on the CPU",
       buildHploc, false, false, /*usesPlocRadius=*/true, kMaxLeafSize, /*usesMortonSizeBits=*/true},
      // Embree's builder caps leaves at RTC_BUILD_MAX_PRIMITIVES_PER_LEAF (builders/embree.cpp).
      {"embree", "Embree 3 rtcBuildBVH, quality MEDIUM (the reference)", buildEmbreeBvh, false, false, false,
       kEmbreeMaxLeafSize},
      {"embree-low", "Embree 3 rtcBuildBVH, quality LOW (Morton codes)", buildEmbreeLowBvh, false, false, false,
       kEmbreeMaxLeafSize},
  };
  return table;
}

}  // namespace

const std::vector<BuilderInfo>& builders() { return table(); }

void registerBuilder(BuilderInfo info) {
  for (const BuilderInfo& b : table())
    if (b.name == info.name) throw std::invalid_argument("builder '" + info.name + "' is registered already");
  table().push_back(std::move(info));
}

const BuilderInfo& findBuilder(const std::string& name) {
  for (const BuilderInfo& info : builders())
    if (info.name == name) return info;
  std::ostringstream msg;
  msg << "unknown BVH builder '" << name << "'; valid builders:";
  for (const BuilderInfo& info : builders()) msg << ' ' << info.name;
  throw std::invalid_argument(msg.str());
}

namespace {

bool finite(const glm::vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

std::string str(const glm::vec3& v) {
  std::ostringstream s;
  s << '(' << v.x << ", " << v.y << ", " << v.z << ')';
  return s.str();
}

}  // namespace

void validateBuildInput(const BuildInput& input, const BuildOptions& options) {
  if (options.maxLeafSize < 1 || options.maxLeafSize > kMaxLeafSize)
    throw std::invalid_argument("BVH build: maxLeafSize " + std::to_string(options.maxLeafSize) +
                                " is outside 1.." + std::to_string(kMaxLeafSize));
  if (!(options.cost.traversalCost >= 0.0f && options.cost.intersectionCost > 0.0f) ||
      !std::isfinite(options.cost.traversalCost) || !std::isfinite(options.cost.intersectionCost))
    throw std::invalid_argument("BVH build: cost model needs traversalCost >= 0 and intersectionCost > 0");
  if (input.boxes.empty())
    throw InputError("BVH build: the input has no primitives (empty scene?)");
  if (input.boxes.size() != input.centroids.size())
    throw InputError("BVH build: " + std::to_string(input.boxes.size()) + " boxes but " +
                     std::to_string(input.centroids.size()) + " centroids");
  if (input.hasTriangles() && (input.v0.size() != input.boxes.size() || input.v1.size() != input.boxes.size() ||
                               input.v2.size() != input.boxes.size()))
    throw InputError("BVH build: " + std::to_string(input.boxes.size()) + " boxes but " +
                     std::to_string(input.v0.size()) + "/" + std::to_string(input.v1.size()) + "/" +
                     std::to_string(input.v2.size()) + " triangle vertices");
  if (input.boxes.size() > std::numeric_limits<uint32_t>::max())
    throw InputError("BVH build: " + std::to_string(input.boxes.size()) +
                     " primitives; at most 2^32 - 1 are supported");
  Aabb scene, centroids;
  for (size_t i = 0; i < input.boxes.size(); ++i) {
    const Aabb& b = input.boxes[i];
    if (!finite(b.min) || !finite(b.max) || !glm::all(glm::lessThanEqual(b.min, b.max)))
      throw InputError("BVH build: primitive " + std::to_string(i) + " has a non-finite or inverted box: min " +
                       str(b.min) + " max " + str(b.max));
    if (!finite(input.centroids[i]))
      throw InputError("BVH build: primitive " + std::to_string(i) + " has a non-finite centroid " +
                       str(input.centroids[i]));
    scene.grow(b);
    centroids.grow(input.centroids[i]);
  }
  // Builders subtract coordinates and multiply extents; a scene whose extent or half area overflows
  // a float would turn those into Inf and then NaN.
  if (!finite(scene.extent()) || !std::isfinite(scene.halfArea()) || !finite(centroids.extent()))
    throw InputError("BVH build: scene bounds " + str(scene.min) + " .. " + str(scene.max) +
                     " are too large (extent or area overflows float)");
}

OptionReview reviewBuildOptions(const std::string& builder, const BuildOptions& options) {
  const BuilderInfo& info = findBuilder(builder);
  if (!options.optimize.empty() && options.optimize != "reinsert")
    throw std::invalid_argument("unknown --optimize pass '" + options.optimize + "'; valid: reinsert");
  if (options.maxLeafSize < 1 || options.maxLeafSize > kMaxLeafSize)
    throw std::invalid_argument("--leaf-size must be in 1.." + std::to_string(kMaxLeafSize) + " (got " +
                                std::to_string(options.maxLeafSize) + ")");
  if (options.bins == 1 || options.bins > kMaxBuildBins)
    throw std::invalid_argument("--bins must be 0 (the builder's default) or 2.." + std::to_string(kMaxBuildBins) +
                                " (got " + std::to_string(options.bins) + ")");
  if (options.mortonSizeBits > kMaxMortonSizeBits)
    throw std::invalid_argument("--morton-size-bits must be in 0.." + std::to_string(kMaxMortonSizeBits) + " (got " +
                                std::to_string(options.mortonSizeBits) + ")");
  if (options.plocTopDown > kMaxPlocTopDown)
    throw std::invalid_argument("--ploc-top-down must be in 0.." + std::to_string(kMaxPlocTopDown) + " (got " +
                                std::to_string(options.plocTopDown) + ")");
  OptionReview review;
  review.leafSize = std::min(options.maxLeafSize, info.leafSizeCap);
  const BuildOptions defaults;
  if (review.leafSize < options.maxLeafSize)
    review.warnings.push_back(info.name + " builds leaves of at most " + std::to_string(info.leafSizeCap) +
                              " triangles; --leaf-size " + std::to_string(options.maxLeafSize) + " is capped to " +
                              std::to_string(review.leafSize));
  if (options.bins != defaults.bins && !info.usesBins)
    review.warnings.push_back(info.name + " ignores --bins (only sah-binned and sbvh bin)");
  if (options.sbvhAlpha != defaults.sbvhAlpha && !info.usesSbvhAlpha)
    review.warnings.push_back(info.name + " ignores --sbvh-alpha (only sbvh makes spatial splits)");
  if (options.sbvhReferenceBudget != defaults.sbvhReferenceBudget && !info.usesSbvhAlpha)  // usesSbvhAlpha: makes spatial splits
    review.warnings.push_back(info.name + " ignores --sbvh-budget (only sbvh makes spatial splits)");
  if (options.plocRadius != defaults.plocRadius && !info.usesPlocRadius)
    review.warnings.push_back(info.name +
                              " ignores --ploc-radius (only the PLOC builders cluster: ploc, hploc and their GPU versions)");
  if (options.plocTopDown != defaults.plocTopDown && !info.usesPlocRadius)
    review.warnings.push_back(info.name + " ignores --ploc-top-down (only ploc splits its top down)");
  if (options.mortonSizeBits != defaults.mortonSizeBits && !info.usesMortonSizeBits)
    review.warnings.push_back(info.name + " ignores --morton-size-bits (only lbvh, ploc, hploc and their GPU versions build "
                                          "Morton codes)");
  if (options.mortonGrid != defaults.mortonGrid && !info.usesMortonSizeBits)
    review.warnings.push_back(info.name + " ignores --morton-grid (only lbvh, ploc, hploc and their GPU versions build "
                                          "Morton codes)");
  return review;
}

const std::vector<std::string>& mortonGridNames() {
  static const std::vector<std::string> names = {"cube", "axes"};  // in MortonGrid's order
  return names;
}

MortonGrid parseMortonGrid(const std::string& name) {
  const std::vector<std::string>& names = mortonGridNames();
  for (size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return MortonGrid(i);
  throw std::invalid_argument("unknown --morton-grid '" + name + "'; valid: cube, axes");
}

const std::string& mortonGridName(MortonGrid grid) { return mortonGridNames().at(size_t(grid)); }

const std::vector<std::string>& optimizePasses() {
  static const std::vector<std::string> names = {"reinsert"};
  return names;
}

Bvh buildBvh(const std::string& builder, const BuildInput& input, const BuildOptions& options,
             BuildStats* stats) {
  const BuilderInfo& info = findBuilder(builder);
  if (!options.optimize.empty() && options.optimize != "reinsert")
    throw std::invalid_argument("unknown --optimize pass '" + options.optimize + "'; valid: reinsert");
  validateBuildInput(input, options);
  const auto start = std::chrono::steady_clock::now();
  Bvh bvh = info.build(input, options);
  double sahBefore = 0.0, optimizeMs = 0.0;
  if (!options.optimize.empty()) {
    sahBefore = sahCost(bvh, options.cost);
    const auto t0 = std::chrono::steady_clock::now();
    optimizeReinsert(bvh, input, options);  // leaves re-formed where the input allows
    optimizeMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  }
  const auto stop = std::chrono::steady_clock::now();
  if (stats) {
    *stats = computeStats(bvh, options.cost);
    stats->builder = info.name;
    stats->leafSize = std::min(options.maxLeafSize, info.leafSizeCap);  // what the leaves were limited to
    stats->primitives = input.boxes.size();
    stats->buildMs = std::chrono::duration<double, std::milli>(stop - start).count();
    stats->sahBeforeOptimize = options.optimize.empty() ? stats->sahCost : sahBefore;
    stats->optimizeMs = optimizeMs;
  }
  return bvh;
}

}  // namespace bvhlab
