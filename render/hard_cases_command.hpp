// `bvhlab hard-cases`: the hard-case suite (datasets/hard_cases.hpp) run under each robustness
// variant (traversal/robustness.hpp), with CGAL's exact answers (datasets/cgal_oracle.hpp) as ground
// truth. Per variant it counts
//   - leaks: rays that must hit (they start inside a closed mesh or cross the inside of an open one)
//     and miss, traced by the C++ kernel mirror through a BVH of the case, so the box test counts too;
//   - oracle disagreement on the unit-scale cases: hit/miss where the exact answer is not a tie, and
//     the first triangle hit where the exact first hit is decided (and, "clear", at least 2^-16 in
//     barycentric terms away from an edge, where no float test has an excuse);
//   - non-finite values: box tests whose entry distance is NaN (every node of the case's BVH against
//     every ray), reported hits with a non-finite t or barycentric;
//   - secondary rays on the closed (convex) cases: from the inside points to every triangle's
//     centroid, and from each hit a reflected ray (offset to the inside, must hit another triangle)
//     and a straight-through ray (offset to the outside, must hit nothing): a self-hit is the reflected
//     ray hitting its own triangle or the outgoing one hitting anything; a lost ray is a reflected ray
//     that hits nothing (the offset pushed its origin out of the mesh);
//   - with --layout: every count above through a kernel of that layout (the trees packed in it); the
//     NaN and box-test counts stay per node of the binary tree (v1), what the box test sees whatever
//     the node format;
//   - with --gpu: leaks of the GLSL kernel, a camera inside closed tessellated meshes (unit scale, far,
//     tiny, huge) in the primid view, each pixel a must-hit ray, plus how many pixels' hit ids differ
//     from the C++ mirror's.
// A table goes to stdout; --json FILE writes everything as one JSON object ("-" = stdout, the table
// then goes to stderr). Key names: docs in hard_cases_command.cpp, next to where they are written.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "datasets/hard_cases.hpp"
#include "render/prepared_scene.hpp"
#include "traversal/robustness.hpp"

namespace bvhlab {

struct HardCasesCommand {
  std::vector<std::string> robust;  // variant names (robustnessNames()); empty = every variant
  std::string json;                 // write the JSON object here; "-" = stdout; "" = no JSON
  bool gpu = false;                 // also count the GLSL kernel's leaks (needs a GL context)
  std::string backend = "osmesa";   // osmesa | egl, for --gpu
  std::string layout = "v1";         // texture layout the cases' trees are packed in (layout/layouts.hpp)
  std::string kernel;                // "" = the layout's default kernel
  std::string builder = "sah-binned";
};

// Runs it; returns the process exit code (bad names throw std::invalid_argument first).
int runHardCases(const HardCasesCommand& cmd);

// ---- the library behind it ------------------------------------------------------------------------

// Counts of one case (or a sum of cases) under one variant, C++ mirror.
struct HardCaseCounts {
  std::string name;
  size_t rays = 0;
  size_t mustHit = 0, leaks = 0;
  size_t oracleDecisive = 0, oracleHitDisagree = 0;  // exact hit/miss not a tie; the mirror differs
  size_t oracleFirstDecisive = 0, oracleFirstDisagree = 0;  // exact first hit decided; other triangle
  size_t oracleFirstClear = 0, oracleFirstClearDisagree = 0;  // ... and >= 2^-16 from an edge
  size_t boxTests = 0, nanBoxEntries = 0;  // every node x every ray: entry distance NaN
  size_t nonFiniteHits = 0;                // hit with a non-finite t or barycentric
  size_t secondaryRays = 0, secondarySelfHits = 0, secondaryLost = 0;
  void add(const HardCaseCounts& other);
  nlohmann::json toJson() const;
};

// The suite with a BVH per case and the oracle's answers, computed once and shared by every variant.
class HardCaseSuite {
 public:
  // `kernel` "" = the layout's default; a kernel of another layout is refused (traversal/kernels.hpp).
  HardCaseSuite(const std::string& layout, const std::string& kernel, const std::string& builder);
  const std::string& layout() const;
  const std::string& kernel() const;  // the resolved name
  ~HardCaseSuite();
  // One entry per case, in makeHardCases() order.
  std::vector<HardCaseCounts> evaluate(Robustness variant) const;
  const std::vector<hard::HardCase>& cases() const;
  nlohmann::json summaryJson() const;  // rays, must-hit rays, oracle ties / decisive counts

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The GPU part: a camera inside closed tessellated meshes, every pixel a must-hit ray.
struct InsideView {
  std::string name;  // e.g. "cube_far1e4"
  hard::HardCase mesh;
  Camera camera;
};
// The cube (6 x 6 quads a face) and the sphere (48 x 24) at unit scale, far (offset 1e4), tiny (1e-3)
// and huge (1e3), seen from a point slightly off the centre (rays cross edges and vertices at many
// angles); and the cube seen from its exact centre through the middle of a face with a 90 degree
// field of view, where kInsideViewSize = 3 * 53 puts pixel centres on the quads' edges and diagonals.
std::vector<InsideView> insideViews();
std::unique_ptr<PreparedScene> prepareInsideView(const InsideView& view, const std::string& builder,
                                                 const std::string& layout = "v1");
constexpr int kInsideViewSize = 159;  // pixels per side: 25,281 must-hit rays per view

struct GpuLeakCounts {
  std::string name;
  size_t rays = 0, leaks = 0;
  size_t mirrorIdMismatch = 0;  // pixels whose hit id differs from the C++ mirror's (same variant)
};
// Renders `scene` (a prepared inside view, in any layout) in the primid view with the GLSL kernel and
// the mirror; `kernel` must walk the scene's layout. Needs a current GL context.
GpuLeakCounts gpuLeaks(const PreparedScene& scene, const std::string& name, Robustness variant,
                       const std::string& kernel);

}  // namespace bvhlab
