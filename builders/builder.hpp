// Builder interface and registry. Adding a builder = one .cpp file + one line in registry.cpp.
#pragma once
#include <functional>
#include <string>
#include <vector>

#include "builders/bvh.hpp"

namespace bvhlab {

struct BuilderInfo {
  std::string name;         // e.g. "sah-binned"
  std::string description;  // one line for `bvhlab builders`
  std::function<Bvh(const BuildInput&, const BuildOptions&)> build;
  // Which options it reads (the others are ignored: a user who sets them gets a warning) and the
  // largest leaf it builds (a larger --leaf-size is capped, with a warning).
  bool usesBins = false, usesSbvhAlpha = false, usesPlocRadius = false;
  uint32_t leafSizeCap = kMaxLeafSize;
  bool usesMortonSizeBits = false;  // builds Morton codes (builders/morton.hpp): reads mortonSizeBits and mortonGrid
  bool gpu = false;  // builds in GL compute shaders (builders/gpu/gpu_builders.hpp registers these)
};

const std::vector<BuilderInfo>& builders();
// Adds a builder to builders() (a library above this one registers its builders at start-up, so
// this library needs none of theirs: the GPU builders, builders/gpu/gpu_builders.hpp). Throws
// std::invalid_argument when the name is taken.
void registerBuilder(BuilderInfo info);
// Throws std::invalid_argument naming the valid builders when `name` is unknown.
const BuilderInfo& findBuilder(const std::string& name);

// The checks buildBvh makes before it calls a builder (a BuilderInfo::build function assumes them):
// non-empty input, as many centroids as boxes, at most 2^32 - 1 primitives, maxLeafSize in
// 1..kMaxLeafSize, every box and centroid finite with min <= max, and a scene small enough that its
// half area is finite. Throws InputError for bad data (naming the primitive index) and
// std::invalid_argument for bad options.
void validateBuildInput(const BuildInput& input, const BuildOptions& options);

// What `builder` will do with `options`, known before anything is loaded: throws
// std::invalid_argument (naming the flag) for values no builder accepts (unknown builder or pass,
// leaf size outside 1..kMaxLeafSize, bins not 0 or 2..kMaxBins, Morton size bits above
// kMaxMortonSizeBits), and returns the leaf size the builder
// honours plus one warning per option it ignores or caps. Options equal to BuildOptions{}'s defaults
// are taken as not set.
struct OptionReview {
  uint32_t leafSize = 0;  // what the tree's leaves are limited to (= options.maxLeafSize unless capped)
  std::vector<std::string> warnings;
};
OptionReview reviewBuildOptions(const std::string& builder, const BuildOptions& options);
constexpr uint32_t kMaxBuildBins = 256;  // sah-binned and sbvh store a bin index in one byte
constexpr uint32_t kEmbreeMaxLeafSize = 32;  // RTC_BUILD_MAX_PRIMITIVES_PER_LEAF (checked in builders/embree.cpp)

// BuildOptions::mortonGrid by name ("cube", "axes"), and back; parseMortonGrid throws
// std::invalid_argument naming the valid names.
const std::vector<std::string>& mortonGridNames();
MortonGrid parseMortonGrid(const std::string& name);
const std::string& mortonGridName(MortonGrid grid);

// The post-passes BuildOptions::optimize accepts (besides "" = none).
const std::vector<std::string>& optimizePasses();

// Times the build (post-pass included), validates the input (empty input is an error) and the
// options (an unknown builder or optimize pass: std::invalid_argument naming the valid ones), fills
// BuildStats.
Bvh buildBvh(const std::string& builder, const BuildInput& input, const BuildOptions& options,
             BuildStats* stats = nullptr);

}  // namespace bvhlab
