#include "render/hard_cases_command.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <optional>
#include <stdexcept>
#include <tuple>

#include "builders/builder.hpp"
#include "datasets/cgal_oracle.hpp"
#include "layout/layout.hpp"
#include "layout/layouts.hpp"
#include "render/gl_context.hpp"
#include "render/gpu_renderer.hpp"
#include "shaders/tracer.hpp"
#include "traversal/intersectors.hpp"  // the box tests, for the NaN count
#include "traversal/kernels.hpp"

namespace bvhlab {

namespace {

using glm::vec2;
using glm::vec3;

// A float first hit this close to an edge (smallest exact barycentric) may go to the neighbour for
// any float test: rounding the sheared coordinates moves it by a few ulps relative to the
// coordinates' magnitude over the edge length (<= 16 in the unit-scale cases). 2^-16 = 256 u
// (u = 2^-24) bounds that with a factor ~16 to spare; tests/test_robust.cpp uses the same bound.
constexpr double kClearMargin = 0x1p-16;

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

Scene meshScene(const hard::HardCase& c) {
  Scene s;
  Mesh m;
  m.name = c.name;
  m.positions = c.positions;
  m.triangles = c.triangles;
  s.meshes.push_back(std::move(m));
  Object o;
  o.kind = ObjectKind::Mesh;
  o.mesh = 0;
  s.objects.push_back(o);
  s.materials.push_back(Material{});
  s.world.kind = WorldKind::Color;
  return s;
}

bool finite(vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

}  // namespace

void HardCaseCounts::add(const HardCaseCounts& o) {
  rays += o.rays;
  mustHit += o.mustHit;
  leaks += o.leaks;
  oracleDecisive += o.oracleDecisive;
  oracleHitDisagree += o.oracleHitDisagree;
  oracleFirstDecisive += o.oracleFirstDecisive;
  oracleFirstDisagree += o.oracleFirstDisagree;
  oracleFirstClear += o.oracleFirstClear;
  oracleFirstClearDisagree += o.oracleFirstClearDisagree;
  boxTests += o.boxTests;
  nanBoxEntries += o.nanBoxEntries;
  nonFiniteHits += o.nonFiniteHits;
  secondaryRays += o.secondaryRays;
  secondarySelfHits += o.secondarySelfHits;
  secondaryLost += o.secondaryLost;
}

// The JSON keys of the counts (one object per case and per variant's total).
nlohmann::json HardCaseCounts::toJson() const {
  nlohmann::json j;
  if (!name.empty()) j["name"] = name;
  j["rays"] = rays;
  j["must_hit"] = mustHit;  // rays that must hit
  j["leaks"] = leaks;       // ... and missed
  j["oracle_decisive"] = oracleDecisive;            // exact hit/miss is not a tie (unit-scale cases)
  j["oracle_hit_disagree"] = oracleHitDisagree;     // ... and the mirror decided otherwise
  j["oracle_first_decisive"] = oracleFirstDecisive;  // exact first hit decided
  j["oracle_first_disagree"] = oracleFirstDisagree;  // ... and the mirror hit another triangle
  j["oracle_first_clear"] = oracleFirstClear;        // ... at least 2^-16 from an edge
  j["oracle_first_clear_disagree"] = oracleFirstClearDisagree;
  j["box_tests"] = boxTests;
  j["nan_box_entries"] = nanBoxEntries;  // box tests whose entry distance is NaN
  j["nonfinite_hits"] = nonFiniteHits;   // hits with a non-finite t or barycentric
  j["secondary_rays"] = secondaryRays;
  j["secondary_self_hits"] = secondarySelfHits;
  j["secondary_lost"] = secondaryLost;
  return j;
}

// ---- the suite ------------------------------------------------------------------------------------

struct HardCaseSuite::Impl {
  std::string layout;
  const KernelInfo* kernel = nullptr;
  std::vector<hard::HardCase> cases;
  std::vector<PackedBvh> packed;  // in `layout`, what the kernel walks
  std::vector<PackedBvh> v1;      // the same trees in v1: their nodes are the boxes the NaN count tests
  std::vector<std::vector<oracle::ExactFirstHit>> exact;  // per case, per ray; empty for far/scaled copies
  // NaN entry distances per box test and case (the only knob they depend on), computed when asked.
  mutable std::optional<std::vector<size_t>> nanEntries[2];

  const std::vector<size_t>& nanBoxEntries(BoxTest box) const {
    std::optional<std::vector<size_t>>& slot = nanEntries[int(box)];
    if (slot) return *slot;
    slot.emplace();
    for (size_t i = 0; i < cases.size(); ++i) {
      size_t nans = 0;
      const uint32_t nodes = uint32_t(v1[i].nodes.size() / kNodeTexels);
      for (const hard::HardRay& r : cases[i].rays) {
        const vec3 invDir = box == BoxTest::Robust ? glsl::robust::rayInverseDirection(r.dir)
                                                   : glsl::rayInverseDirection(r.dir);
        for (uint32_t n = 0; n < nodes; ++n) {
          const NodeRecord node = unpackNode(v1[i], n);
          float tEnter;
          if (box == BoxTest::Robust)
            glsl::robust::intersectAabb(r.origin, invDir, node.bmin, node.bmax, r.tMin, r.tMax, tEnter);
          else
            glsl::intersectAabb(r.origin, invDir, node.bmin, node.bmax, r.tMin, r.tMax, tEnter);
          nans += std::isnan(tEnter);
        }
      }
      slot->push_back(nans);
    }
    return *slot;
  }
};

HardCaseSuite::HardCaseSuite(const std::string& layout, const std::string& kernel, const std::string& builder)
    : impl_(std::make_unique<Impl>()) {
  const LayoutInfo& l = findLayout(layout);  // an unknown layout or a kernel of another one fails here
  impl_->layout = l.name;
  impl_->kernel = &findKernel(l.name, kernel);
  findBuilder(builder);  // an unknown name fails here, naming the valid ones
  impl_->cases = hard::makeHardCases();
  for (const hard::HardCase& c : impl_->cases) {
    const TriangleSoup soup = gatherTriangles(meshScene(c));
    const std::vector<Aabb> boxes = triangleBoxes(soup);
    const std::vector<vec3> centroids = triangleCentroids(soup);
    const Bvh bvh = buildBvh(builder, BuildInput{boxes, centroids}, BuildOptions{});
    impl_->v1.push_back(packBvh(bvh, soup));
    impl_->packed.push_back(l.name == "v1" ? impl_->v1.back() : l.pack(bvh, soup));
    std::vector<oracle::ExactFirstHit> answers;
    if (!c.farOrScaled)  // the oracle runs at unit scale; the copies repeat the same rays
      for (const hard::HardRay& r : c.rays)
        answers.push_back(oracle::exactFirstHit(c.positions, c.triangles, r.origin, r.dir, r.tMin, r.tMax));
    impl_->exact.push_back(std::move(answers));
  }
}

HardCaseSuite::~HardCaseSuite() = default;

const std::string& HardCaseSuite::layout() const { return impl_->layout; }
const std::string& HardCaseSuite::kernel() const { return impl_->kernel->name; }

const std::vector<hard::HardCase>& HardCaseSuite::cases() const { return impl_->cases; }

nlohmann::json HardCaseSuite::summaryJson() const {
  size_t rays = 0, mustHit = 0, closedMustHit = 0, oracleRays = 0, ties = 0, decisive = 0, first = 0, clear = 0;
  for (size_t i = 0; i < impl_->cases.size(); ++i) {
    const hard::HardCase& c = impl_->cases[i];
    rays += c.rays.size();
    for (const hard::HardRay& r : c.rays) {
      mustHit += r.mustHit;
      closedMustHit += r.mustHit && c.closed;
    }
    for (const oracle::ExactFirstHit& e : impl_->exact[i]) {
      ++oracleRays;
      ties += e.hit == oracle::Decision::Tie;
      decisive += e.hit != oracle::Decision::Tie;
      first += e.firstDecisive;
      clear += e.firstDecisive && e.firstMargin >= kClearMargin;
    }
  }
  return {{"cases", impl_->cases.size()}, {"rays", rays},
          {"must_hit", mustHit},          {"must_hit_closed", closedMustHit},
          {"oracle_rays", oracleRays},     {"oracle_ties", ties},
          {"oracle_decisive", decisive},   {"oracle_first_decisive", first},
          {"oracle_first_clear", clear}};
}

namespace {

// Secondary rays on a closed case, spawned where the tracer spawns them (shade.glsl, trace_full.glsl):
// p = o + t d, the geometric normal facing the incoming ray, the variant's origin offset. Primary rays
// go from the case's inside points (the origins of its must-hit rays) to every triangle's centroid,
// so each hit lies inside its triangle: there the exact answer is clear. The closed cases are convex,
// so a reflected ray must hit another triangle, and a ray going straight out must hit nothing.
void secondaryRays(const glsl::Storage& storage, const hard::HardCase& c, Robustness variant, TraceClosestFn closest,
                   TraceAnyFn any, HardCaseCounts& n) {
  std::vector<vec3> origins;
  for (const hard::HardRay& r : c.rays)
    if (r.mustHit && std::find(origins.begin(), origins.end(), r.origin) == origins.end()) origins.push_back(r.origin);
  glsl::Counters counters;
  for (const vec3& origin : origins)
    for (const glm::uvec3& tri : c.triangles) {
      const vec3 centroid = (c.positions[tri.x] + c.positions[tri.y] + c.positions[tri.z]) / 3.0f;
      const glsl::Ray primary{origin, centroid - origin};
      glsl::MeshHit hit;
      if (!closest(storage, primary, 0.0f, glsl::INF, hit, counters)) continue;  // a leak: nothing to spawn
      vec3 v0, v1, v2;
      glsl::loadTriangle(storage, hit.tri, v0, v1, v2);
      const vec3 dir = glm::normalize(primary.dir);
      const vec3 p = primary.origin + hit.t * primary.dir;
      const vec3 ng = glm::normalize(glm::cross(v1 - v0, v2 - v0));
      if (!finite(ng) || !finite(p)) continue;  // a closed case has no zero-area triangle; be safe
      const vec3 nIn = glm::dot(dir, ng) < 0.0f ? ng : -ng;  // faces the ray: points into the mesh
      glsl::MeshHit next;
      // shade.glsl's hitMagnitude of the primary ray.
      const float magnitude = std::max({std::abs(primary.origin.x), std::abs(primary.origin.y), std::abs(primary.origin.z)}) + hit.t * glm::length(primary.dir);
      const glsl::Ray reflected{offsetRayOrigin(p, nIn, magnitude, variant.offset), glm::reflect(dir, nIn)};
      const bool reflectedHit = closest(storage, reflected, 0.0f, glsl::INF, next, counters);
      const glsl::Ray outgoing{offsetRayOrigin(p, -nIn, magnitude, variant.offset), dir};
      const bool outgoingHit = any(storage, outgoing, 0.0f, glsl::INF, counters);
      n.secondaryRays += 2;
      n.secondarySelfHits += (reflectedHit && next.tri == hit.tri) + outgoingHit;
      n.secondaryLost += !reflectedHit;
    }
}

}  // namespace

std::vector<HardCaseCounts> HardCaseSuite::evaluate(Robustness variant) const {
  const Impl& s = *impl_;
  const TraceClosestFn closest = s.kernel->closest(variant);
  const TraceAnyFn any = s.kernel->any(variant);
  const std::vector<size_t>& nans = s.nanBoxEntries(variant.box);
  std::vector<HardCaseCounts> out;
  for (size_t i = 0; i < s.cases.size(); ++i) {
    const hard::HardCase& c = s.cases[i];
    const PackedBvh& packed = s.packed[i];
    const glsl::Storage storage(packed, stackSizeFor(packed));
    HardCaseCounts n;
    n.name = c.name;
    n.boxTests = c.rays.size() * (s.v1[i].nodes.size() / kNodeTexels);
    n.nanBoxEntries = nans[i];
    for (size_t k = 0; k < c.rays.size(); ++k) {
      const hard::HardRay& r = c.rays[k];
      ++n.rays;
      glsl::MeshHit hit;
      glsl::Counters counters;
      const glsl::Ray ray{r.origin, r.dir};
      const bool found = closest(storage, ray, r.tMin, r.tMax, hit, counters);
      if (found && !(std::isfinite(hit.t) && std::isfinite(hit.bary.x) && std::isfinite(hit.bary.y)))
        ++n.nonFiniteHits;
      if (r.mustHit) {
        ++n.mustHit;
        n.leaks += !found;
      }
      if (!s.exact[i].empty()) {
        const oracle::ExactFirstHit& e = s.exact[i][k];
        if (e.hit != oracle::Decision::Tie) {
          ++n.oracleDecisive;
          n.oracleHitDisagree += found != (e.hit == oracle::Decision::Hit);
        }
        if (e.firstDecisive) {
          // The packed stream's texel .w is the triangle's index in the case (one mesh).
          const int id = found ? int(packed.triangles[size_t(3 * hit.tri)].w) : -1;
          const bool agree = std::find(e.firstTriangles.begin(), e.firstTriangles.end(), id) != e.firstTriangles.end();
          ++n.oracleFirstDecisive;
          n.oracleFirstDisagree += !agree;
          if (e.firstMargin >= kClearMargin) {
            ++n.oracleFirstClear;
            n.oracleFirstClearDisagree += !agree;
          }
        }
      }
    }
    if (c.closed) secondaryRays(storage, c, variant, closest, any, n);
    out.push_back(std::move(n));
  }
  return out;
}

// ---- the GPU part -----------------------------------------------------------------------------------

std::vector<InsideView> insideViews() {
  std::vector<InsideView> out;
  const hard::HardCase cube = hard::closedCube(6), sphere = hard::closedSphere(48, 24);
  auto offCentre = [](vec3 centre, float scale) {
    Camera c;
    c.eye = centre + scale * vec3(0.13f, -0.07f, 0.05f);
    c.target = c.eye + vec3(0.3f, 0.2f, -1.0f);
    c.fovDeg = 120.0f;
    return c;
  };
  // Every closed case of the ray-level suite, at the offsets and scales the suite copies them to (plus
  // 1e-3 and 1e3): the GLSL must not leak where the mirror does not.
  const hard::HardCase* octahedron = nullptr;
  static const std::vector<hard::HardCase> suite = hard::makeHardCases();
  for (const hard::HardCase& c : suite)
    if (c.name == "duplicated-vertices") octahedron = &c;
  if (!octahedron) throw std::logic_error("hard-case suite lost its duplicated-vertices case");
  out.push_back({"octahedron_soup_unit", *octahedron, offCentre(vec3(0.0f), 0.5f)});
  for (const auto& [name, base] : {std::pair{"cube", cube}, std::pair{"sphere", sphere}}) {
    out.push_back({std::string(name) + "_unit", base, offCentre(vec3(0.0f), 1.0f)});
    for (auto [tag, offset, scale] : {std::tuple{"far1e4", vec3(1e4f, -2e4f, 3e4f), 1.0f},
                                      std::tuple{"far1e5", vec3(1e5f, -5e4f, 2.5e4f), 1.0f},
                                      std::tuple{"far1e6", vec3(1e6f, -5e5f, 2.5e5f), 1.0f},
                                      std::tuple{"scale1e-4", vec3(0.0f), 1e-4f},
                                      std::tuple{"scale1e-3", vec3(0.0f), 1e-3f},
                                      std::tuple{"scale1e-2", vec3(0.0f), 1e-2f},
                                      std::tuple{"scale1e2", vec3(0.0f), 1e2f},
                                      std::tuple{"scale1e3", vec3(0.0f), 1e3f},
                                      std::tuple{"scale1e4", vec3(0.0f), 1e4f}})
      out.push_back({std::string(name) + "_" + tag, hard::transformed(base, offset, scale), offCentre(offset, scale)});
  }
  // From the exact centre towards the face z = -1, 90 degrees: pixel centre i lies at
  // ndc (2i + 1) / 159 - 1, on a lattice line k/3 - 1 of the 6 x 6 face grid whenever 2i + 1 = 53 k, and
  // on a quad diagonal whenever ndc x = ndc y (up to the rounding of the camera basis: within ulps).
  static_assert(kInsideViewSize == 3 * 53, "the centre view needs 3 | size and an odd size / 3");
  Camera centre;
  centre.eye = vec3(0.0f);
  centre.target = vec3(0.0f, 0.0f, -1.0f);
  centre.fovDeg = 90.0f;
  out.push_back({"cube_centre", cube, centre});
  return out;
}

std::unique_ptr<PreparedScene> prepareInsideView(const InsideView& view, const std::string& builder,
                                                 const std::string& layout) {
  Scene s = meshScene(view.mesh);
  s.camera = view.camera;
  return prepareScene(std::move(s), builder, BuildOptions{}, layout);
}

GpuLeakCounts gpuLeaks(const PreparedScene& p, const std::string& name, Robustness variant, const std::string& kernel) {
  ShaderOptions o;
  o.view = View::PrimId;
  o.countStats = true;
  o.layout = p.packed.layout;
  o.kernel = findKernel(p.packed.layout, kernel).name;
  o.robust = variant;
  o.bvhStackSize = stackSizeFor(p.packed);
  FrameOptions f;
  f.width = f.height = kInsideViewSize;
  f.camera = p.scene.camera;
  f.exposure = p.scene.settings.exposure;
  GpuRenderer gpu(p, o, f);
  gpu.drawFrame();
  const std::vector<glm::uvec4> stats = gpu.readStats();
  const ReferenceImage mirror = renderReference(p.scene, p.data, p.packed, o, f);
  GpuLeakCounts n;
  n.name = name;
  n.rays = stats.size();
  // stats.w: primary id + 1 (0: the ray escaped) in bits 0..30; bit 31 flags a non-finite colour.
  constexpr uint32_t kIdBits = 0x7FFFFFFFu;
  for (size_t i = 0; i < stats.size(); ++i) {
    n.leaks += (stats[i].w & kIdBits) == 0;
    n.mirrorIdMismatch += (stats[i].w & kIdBits) != (mirror.stats[i].w & kIdBits);
  }
  return n;
}

// ---- the command ------------------------------------------------------------------------------------

namespace {

std::string cell(const nlohmann::json& n) { return std::to_string(n.get<size_t>()); }

void printTable(std::FILE* out, const nlohmann::json& report) {
  const bool gpu = report["gpu"].get<bool>();
  std::fprintf(out, "hard cases: %zu cases, %zu rays (%zu must hit); layout %s, kernel %s, builder %s\n",
               report["suite"]["cases"].get<size_t>(), report["suite"]["rays"].get<size_t>(),
               report["suite"]["must_hit"].get<size_t>(), report["layout"].get<std::string>().c_str(),
               report["kernel"].get<std::string>().c_str(), report["builder"].get<std::string>().c_str());
  std::fprintf(out, "oracle (unit-scale cases): %zu rays, %zu ties, %zu decisive hit/miss, %zu decided first hits "
               "(%zu clear of edges)\n",
               report["suite"]["oracle_rays"].get<size_t>(), report["suite"]["oracle_ties"].get<size_t>(),
               report["suite"]["oracle_decisive"].get<size_t>(), report["suite"]["oracle_first_decisive"].get<size_t>(),
               report["suite"]["oracle_first_clear"].get<size_t>());
  std::fprintf(out, "%-11s %-16s %-5s %-8s %7s %8s %9s %7s %5s %7s %6s", "variant", "triangle", "box", "offset",
               "leaks", "hit!=", "first!=", "clear!=", "NaN", "self", "lost");
  if (gpu) std::fprintf(out, " %8s %6s", "gpu-leak", "id!=");
  std::fprintf(out, " %6s\n", "s");
  for (const nlohmann::json& v : report["variants"]) {
    const nlohmann::json& t = v["total"];
    std::fprintf(out, "%-11s %-16s %-5s %-8s %7s %8s %9s %7s %5s %7s %6s", v["robust"].get<std::string>().c_str(),
                 v["triangle_test"].get<std::string>().c_str(), v["box_test"].get<std::string>().c_str(),
                 v["origin_offset"].get<std::string>().c_str(), cell(t["leaks"]).c_str(),
                 cell(t["oracle_hit_disagree"]).c_str(), cell(t["oracle_first_disagree"]).c_str(),
                 cell(t["oracle_first_clear_disagree"]).c_str(),
                 std::to_string(t["nan_box_entries"].get<size_t>() + t["nonfinite_hits"].get<size_t>()).c_str(),
                 cell(t["secondary_self_hits"]).c_str(), cell(t["secondary_lost"]).c_str());
    double seconds = v["cpu_s"].get<double>();
    if (gpu) {
      std::fprintf(out, " %8s %6s", cell(v["gpu"]["leaks"]).c_str(), cell(v["gpu"]["mirror_id_mismatch"]).c_str());
      seconds += v["gpu"]["s"].get<double>();
    }
    std::fprintf(out, " %6.2f\n", seconds);
  }
  std::fprintf(out, "leaks: of %zu must-hit rays (C++ mirror through a BVH); hit!= / first!= / clear!=: disagreements "
               "with the exact oracle; NaN: NaN box entries + non-finite hits; self / lost: secondary rays on the "
               "closed cases that re-hit their surface / left the mesh",
               report["suite"]["must_hit"].get<size_t>());
  if (gpu)
    std::fprintf(out, "; gpu-leak: GLSL primid pixels that escaped, of %zu; id!=: pixels whose hit differs from "
                 "the mirror's", report["gpu_rays"].get<size_t>());
  std::fprintf(out, "\n");
}

}  // namespace

int runHardCases(const HardCasesCommand& cmd) {
  std::vector<Robustness> variants;
  for (const std::string& name : cmd.robust) variants.push_back(parseRobustness(name));
  if (variants.empty()) variants = robustnessVariants();
  const Backend backend = parseBackend(cmd.backend);

  const auto setupStart = std::chrono::steady_clock::now();
  const HardCaseSuite suite(cmd.layout, cmd.kernel, cmd.builder);
  nlohmann::json report;
  report["command"] = "hard-cases";
  report["layout"] = suite.layout();
  report["kernel"] = suite.kernel();
  report["builder"] = cmd.builder;
  report["suite"] = suite.summaryJson();
  report["gpu"] = cmd.gpu;

  std::unique_ptr<GlContext> context;
  std::vector<std::pair<std::string, std::unique_ptr<PreparedScene>>> views;
  if (cmd.gpu) {
    context = createContext(backend);
    report["backend"] = backendName(backend);
    report["renderer"] = context->renderer();
    size_t rays = 0;
    for (const InsideView& v : insideViews()) {
      views.emplace_back(v.name, prepareInsideView(v, cmd.builder, suite.layout()));
      rays += size_t(kInsideViewSize) * kInsideViewSize;
    }
    report["gpu_rays"] = rays;
  }
  report["setup_s"] = secondsSince(setupStart);

  report["variants"] = nlohmann::json::array();
  for (Robustness variant : variants) {
    nlohmann::json v;
    v["robust"] = robustnessName(variant);
    v["triangle_test"] = triangleTestName(variant.triangle);
    v["box_test"] = boxTestName(variant.box);
    v["origin_offset"] = originOffsetName(variant.offset);
    const auto cpuStart = std::chrono::steady_clock::now();
    const std::vector<HardCaseCounts> perCase = suite.evaluate(variant);
    HardCaseCounts total, closed;
    v["cases"] = nlohmann::json::array();
    for (size_t i = 0; i < perCase.size(); ++i) {
      total.add(perCase[i]);
      if (suite.cases()[i].closed) closed.add(perCase[i]);
      v["cases"].push_back(perCase[i].toJson());
    }
    v["total"] = total.toJson();
    v["leaks_closed"] = closed.leaks;  // on the closed-mesh cases only
    v["must_hit_closed"] = closed.mustHit;
    v["cpu_s"] = secondsSince(cpuStart);
    if (cmd.gpu) {
      const auto gpuStart = std::chrono::steady_clock::now();
      GpuLeakCounts sum;
      nlohmann::json perView = nlohmann::json::array();
      for (const auto& [name, scene] : views) {
        const GpuLeakCounts n = gpuLeaks(*scene, name, variant, suite.kernel());
        sum.rays += n.rays;
        sum.leaks += n.leaks;
        sum.mirrorIdMismatch += n.mirrorIdMismatch;
        perView.push_back({{"name", n.name}, {"rays", n.rays}, {"leaks", n.leaks},
                           {"mirror_id_mismatch", n.mirrorIdMismatch}});
      }
      v["gpu"] = {{"rays", sum.rays}, {"leaks", sum.leaks}, {"mirror_id_mismatch", sum.mirrorIdMismatch},
                  {"views", perView}, {"s", secondsSince(gpuStart)}};
    }
    report["variants"].push_back(std::move(v));
  }

  const bool jsonToStdout = cmd.json == "-";
  printTable(jsonToStdout ? stderr : stdout, report);
  if (jsonToStdout) {
    std::cout << report.dump() << std::endl;
  } else if (!cmd.json.empty()) {
    std::ofstream out(cmd.json);
    out << report.dump(1) << "\n";
    if (!out) throw std::runtime_error("cannot write " + cmd.json);
  }
  return 0;
}

}  // namespace bvhlab
