#include <chrono>
#include <cstdio>
#include <gtest/gtest.h>
#include "builders/builder.hpp"
#include "builders/reinsert.hpp"
#include "builders/test_inputs.hpp"
#include "datasets/procedural.hpp"

namespace bvhlab {
namespace {
using testing::PrimitiveSet;

PrimitiveSet fromMesh(const Mesh& mesh, const std::string& name) {
  PrimitiveSet set;
  set.name = name;
  for (const glm::uvec3& t : mesh.triangles) set.addTriangle(mesh.positions[t.x], mesh.positions[t.y], mesh.positions[t.z]);
  return set;
}

TEST(ReinsertMeasure, DISABLED_Meshes) {
  std::vector<PrimitiveSet> sets;
  const char* only = std::getenv("RI_MESH");
  for (const char* m : {"bunny00", "refined_elephant", "armadillo"})
    if (!only || std::string(only) == m)
      sets.push_back(testing::loadTriangles(std::filesystem::path(BVHLAB_SOURCE_DIR) / "datasets/cache/meshes" / (std::string(m) + ".off")));
  if (!only || std::string(only) == "large") sets.push_back(fromMesh(makeLargeMesh(1000000), "large1M"));
  const char* bl = std::getenv("RI_BUILDERS");
  std::vector<std::string> names = {"lbvh", "median", "sah-binned"};
  if (bl) { names.clear(); std::string s = bl; size_t p = 0; while (p <= s.size()) { size_t q = s.find(',', p); if (q == std::string::npos) q = s.size(); names.push_back(s.substr(p, q - p)); p = q + 1; } }
  for (const PrimitiveSet& set : sets) {
    for (const std::string& b : names) {
      BuildOptions o;
      o.optimize = "reinsert";
      BuildStats st;
      buildBvh(b, set.input(), o, &st);
      std::printf("| %s | %s (%zu) | %.3f | %.3f | %.2f%% | %.0f | depth %u |\n", b.c_str(), set.name.c_str(), set.size(),
                  st.sahBeforeOptimize, st.sahCost, 100.0 * (st.sahCost / st.sahBeforeOptimize - 1.0), st.optimizeMs, st.depth);
      std::fflush(stdout);
    }
  }
}
}  // namespace
}  // namespace bvhlab
