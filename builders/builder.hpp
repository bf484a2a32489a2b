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
};

const std::vector<BuilderInfo>& builders();
// Throws std::invalid_argument naming the valid builders when `name` is unknown.
const BuilderInfo& findBuilder(const std::string& name);

// The checks buildBvh makes before it calls a builder (a BuilderInfo::build function assumes them):
// non-empty input, as many centroids as boxes, at most 2^32 - 1 primitives, maxLeafSize in
// 1..kMaxLeafSize, every box and centroid finite with min <= max, and a scene small enough that its
// half area is finite. Throws InputError for bad data (naming the primitive index) and
// std::invalid_argument for bad options.
void validateBuildInput(const BuildInput& input, const BuildOptions& options);

// The post-passes BuildOptions::optimize accepts (besides "" = none).
const std::vector<std::string>& optimizePasses();

// Times the build (post-pass included), validates the input (empty input is an error) and the
// options (an unknown builder or optimize pass: std::invalid_argument naming the valid ones), fills
// BuildStats.
Bvh buildBvh(const std::string& builder, const BuildInput& input, const BuildOptions& options,
             BuildStats* stats = nullptr);

}  // namespace bvhlab
