// The `two-level` update strategy (layout/two_level_update.hpp) over animated scenes: at every frame
// the two-level tree's C++ mirror traversal equals brute force over the frame's flat scene (rigid
// instances moving, rotating and scaled non-uniformly, and a deforming object under each BLAS
// policy), the streams are the same for any thread count, and bad specs and a static BLAS under a
// deforming object are refused. No GL context ("cpu"); `trace --update two-level` on llvmpipe is in
// tests/test_dynamic.cpp.
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "builders/update.hpp"
#include "cli_run.hpp"
#include "datasets/animation.hpp"
#include "datasets/random_draws.hpp"
#include "datasets/scene_io.hpp"
#include "layout/two_level_update.hpp"
#include "two_level_test_util.hpp"

namespace bvhlab {
namespace {

using namespace traversaltest;
using namespace twoleveltest;

// Objects: two terrain patches sharing a rest mesh and a third of another size, keyed (moving,
// turning, one scaled (1, 3, 0.5) at its last key); `deform` adds a twisting patch.
std::string clipScene(bool deform) {
  std::string s = "[clip]\nframes = 12\nfps = 10\n[camera]\neye = [0, 3, 6]\ntarget = [0, 0, 0]\n";
  const char* keyed[] = {
      "[[object.keys]]\nframe = 0\nposition = [-1, 0, 0]\n"
      "[[object.keys]]\nframe = 11\nposition = [1, 0.5, 0]\nrotation = { axis = [0, 1, 0], angle = 120 }\n",
      "[[object.keys]]\nframe = 0\nposition = [1, 0, 0]\n"
      "[[object.keys]]\nframe = 11\nposition = [-1, -0.5, 0.5]\nrotation = { axis = [1, 0, 0], angle = -70 }\n"
      "scale = [1, 3, 0.5]\n",
      "[[object.keys]]\nframe = 0\nposition = [0, 0, -1]\nrotation = { axis = [0, 0, 1], angle = 30 }\n"
      "[[object.keys]]\nframe = 11\nposition = [0, 0.3, 1]\n",
  };
  const int triangles[] = {1000, 1000, 1200};
  for (int i = 0; i < 3; ++i)
    s += "[[object]]\nkind = \"mesh\"\ngenerate = \"terrain\"\ntriangles = " + std::to_string(triangles[i]) +
         "\nfit = 1.5\n" + keyed[i];
  if (deform)
    s += "[[object]]\nkind = \"mesh\"\nname = \"twister\"\ngenerate = \"terrain\"\ntriangles = 1000\nfit = 1.2\n"
         "[object.deform]\nkind = \"twist\"\nangle = 80\nfrequency = 0.5\naxis = [1, 0, 0]\n";
  return clitest::writeTemp(deform ? "two_level_clip/deform.toml" : "two_level_clip/rigid.toml", s).string();
}

// The frame's flat scene in double, each triangle named (mesh-object index, its own triangle): the
// instance ids and triangle ids TwoLevelUpdater gives.
std::vector<FlatTriangle> flatFrame(const Scene& scene, int frame) {
  const TriangleSoup soup = gatherTriangles(scene);
  std::vector<FlatTriangle> out;
  uint32_t instance = 0;
  for (const ObjectInstance& o : objectInstances(scene, frame)) {
    if (o.mesh < 0 || o.triangleCount == 0) continue;
    for (uint32_t k = 0; k < o.triangleCount; ++k) {
      const uint32_t t = o.firstTriangle + k;
      out.push_back({glm::dvec3(soup.v0[t]), glm::dvec3(soup.v1[t]), glm::dvec3(soup.v2[t]), instance, k});
    }
    ++instance;
  }
  return out;
}

// Rays over the frame's bounds, half random, half aimed at triangle centres (so every object is hit).
std::vector<RayQuery> frameRays(const std::vector<FlatTriangle>& flat, size_t count, uint32_t seed) {
  Aabb bounds;
  for (const FlatTriangle& f : flat)
    for (const glm::dvec3& v : {f.v0, f.v1, f.v2}) bounds.grow(glm::vec3(v));
  std::vector<RayQuery> rays = randomRays(bounds, count / 2, seed);
  std::mt19937 rng(seed + 1);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  const glm::vec3 c = bounds.center(), e = bounds.extent();
  for (size_t i = rays.size(); i < count; ++i) {
    const FlatTriangle& f = flat[(i * 7919u) % flat.size()];
    const glm::vec3 from = c + 1.5f * draw3<glm::vec3>(u, rng) * e;
    const glm::vec3 to = glm::vec3((f.v0 + f.v1 + f.v2) / 3.0);
    rays.push_back({{from, to - from}, 0.0f, glsl::INF});
  }
  return rays;
}

// Runs `spec` over every other frame of the scene's clip and checks the mirror of each two-level
// kernel against brute force at each; returns the rays checked that were clear hits.
size_t checkClip(const std::string& path, const std::string& spec, size_t blasesExpected) {
  SCOPED_TRACE(spec + " over " + path);
  Scene scene = loadScene(path);
  size_t clearHits = 0;
  for (const auto& [layout, kernel] : {layoutKernels()[0], layoutKernels()[3]}) {
    Scene s = scene;
    TwoLevelUpdater updater(parseUpdateSpec(spec), UpdateOptions{}, layout);
    const TwoLevelMirror m = twoLevelMirror(kernel, Robustness::Watertight);
    for (int frame = 0; frame < clipFrames(s); frame += 2) {
      SCOPED_TRACE(layout + "/" + kernel + " frame " + std::to_string(frame));
      setFrame(s, frame);
      updater.update(s, frame);
      EXPECT_EQ(updater.blasCount(), blasesExpected);
      const PackedTwoLevel& packed = updater.packed();
      const glsl::Storage storage(packed.streams);
      const std::vector<FlatTriangle> flat = flatFrame(s, frame);
      Tally tally;
      for (const RayQuery& q : frameRays(flat, 200, 31u + uint32_t(frame))) {
        const MirrorRun r = runMirror(m, storage, q);
        agrees(packed, r.closest, r.any, r.hit, reference(flat, q), q, "mirror", tally);
      }
      EXPECT_EQ(tally.failures, 0u);
      EXPECT_GT(tally.hits, tally.clear / 5) << "too few hits to check";
      clearHits += tally.hits;
      // A hit maps back to the flat scene's triangle of the same (object, triangle).
      for (uint32_t i = 0; i < updater.instanceCount(); ++i)
        EXPECT_EQ(updater.flatTriangle(i, 0), objectInstances(s, frame)[i].firstTriangle);
    }
  }
  return clearHits;
}

TEST(TwoLevelClip, MirrorEqualsBruteForceEveryFrame) {
  // Rigid objects: two share one BLAS (one rest mesh), whatever the policy.
  const std::string rigid = clipScene(false);
  for (const std::string spec : {"two-level", "two-level:blas=refit", "two-level:tlas=lbvh"})
    EXPECT_GT(checkClip(rigid, spec, 2), 0u);
  // A deforming object gets a BLAS of its own, refit or rebuilt every frame.
  const std::string deform = clipScene(true);
  for (const std::string spec : {"two-level:blas=refit", "two-level:blas=rebuild,tlas=ploc"})
    EXPECT_GT(checkClip(deform, spec, 3), 0u);
}

TEST(TwoLevelClip, StreamsAreTheSameForAnyThreadCount) {
  const Scene scene = loadScene(clipScene(true));
  for (const std::string spec : {"two-level:blas=rebuild", "two-level:blas=refit,tlas=lbvh"}) {
    SCOPED_TRACE(spec);
    UpdateOptions one, many;
    one.build.threads = 1;
    many.build.threads = 4;
    TwoLevelUpdater a(parseUpdateSpec(spec), one, "v1"), b(parseUpdateSpec(spec), many, "v1");
    Scene sa = scene, sb = scene;
    for (int frame = 0; frame < clipFrames(scene); frame += 3) {
      setFrame(sa, frame);
      setFrame(sb, frame);
      a.update(sa, frame);
      b.update(sb, frame);
      EXPECT_EQ(a.packed().streams.nodes, b.packed().streams.nodes) << "frame " << frame;
      EXPECT_EQ(a.packed().streams.triangles, b.packed().streams.triangles) << "frame " << frame;
      EXPECT_EQ(a.sahCost(), b.sahCost());
    }
  }
}

TEST(TwoLevelClip, TheTlasFollowsTheInstancesAndTheRigidBlasesStay) {
  Scene scene = loadScene(clipScene(false));
  TwoLevelUpdater updater(parseUpdateSpec("two-level:blas=rebuild"), UpdateOptions{}, "v1");
  const TwoLevelUpdater::Step first = updater.update(scene, 0);
  EXPECT_TRUE(first.blasBuilt);
  EXPECT_EQ(first.blasUpdated, 2u);
  const PackedTwoLevel at0 = updater.packed();
  setFrame(scene, 11);
  const TwoLevelUpdater::Step later = updater.update(scene, 11);
  // Rigid BLASes are never touched after frame 0 (their triangles do not change), whatever the policy.
  EXPECT_FALSE(later.blasBuilt);
  EXPECT_EQ(later.blasUpdated, 0u);
  EXPECT_EQ(later.packMs, 0.0);
  const PackedTwoLevel& at11 = updater.packed();
  ASSERT_EQ(at0.dynamicTexelBegin, at11.dynamicTexelBegin);
  EXPECT_TRUE(std::equal(at0.streams.nodes.begin(), at0.streams.nodes.begin() + ptrdiff_t(at0.dynamicTexelBegin),
                         at11.streams.nodes.begin()));
  EXPECT_NE(at0.streams.nodes, at11.streams.nodes) << "the TLAS and the instance records must follow the motion";
  EXPECT_GT(updater.sahCost(), 0.0);
  EXPECT_GT(updater.tlasSahCost(), 0.0);
}

TEST(TwoLevelClip, BadSpecsAndAStaticBlasUnderADeformingObjectAreRefused) {
  const auto message = [](const std::string& spec) -> std::string {
    try {
      parseUpdateSpec(spec);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "accepted";
  };
  for (const std::string bad : {"two-level:", "two-level:blas", "two-level:blas=", "two-level:blas=sometimes",
                                "two-level:tlas=nope", "two-level:blas=refit,blas=rebuild", "two-level:tlas=lbvh,",
                                "two-level:color=red", "two-levels", "two-level:blas=refit;tlas=lbvh"}) {
    SCOPED_TRACE(bad);
    const std::string what = message(bad);
    EXPECT_NE(what.find("'" + bad + "'"), std::string::npos) << what;
    EXPECT_NE(what.find("two-level[:blas=static|refit|rebuild][,tlas=BUILDER]"), std::string::npos) << what;
  }
  EXPECT_NE(message("two-level:tlas=nope").find("sah-binned"), std::string::npos) << "the builders are named";
  EXPECT_NE(message("two-level:blas=sometimes").find("static, refit or rebuild"), std::string::npos);
  // Good forms and what they say.
  EXPECT_EQ(parseUpdateSpec("two-level").blas, "static");
  EXPECT_EQ(parseUpdateSpec("two-level").tlasBuilder, "");
  const UpdateSpec both = parseUpdateSpec("two-level:tlas=lbvh,blas=rebuild");
  EXPECT_EQ(both.name, "two-level");
  EXPECT_EQ(both.blas, "rebuild");
  EXPECT_EQ(both.tlasBuilder, "lbvh");
  // A flat triangle list cannot drive it.
  EXPECT_THROW(makeUpdateStrategy("two-level", {}), std::invalid_argument);
  // A layout without a two-level walk, and a spec of another strategy.
  EXPECT_THROW(TwoLevelUpdater(parseUpdateSpec("two-level"), UpdateOptions{}, "bvh4"), std::invalid_argument);
  EXPECT_THROW(TwoLevelUpdater(parseUpdateSpec("refit"), UpdateOptions{}, "v1"), std::invalid_argument);
  // blas=static under a deforming object: refused, naming it and the policies that work.
  Scene scene = loadScene(clipScene(true));
  TwoLevelUpdater updater(parseUpdateSpec("two-level"), UpdateOptions{}, "v1");
  std::string what;
  try {
    updater.update(scene, 0);
  } catch (const std::invalid_argument& e) {
    what = e.what();
  }
  EXPECT_NE(what.find("'twister' deforms"), std::string::npos) << what;
  EXPECT_NE(what.find("blas=refit"), std::string::npos) << what;
}

}  // namespace
}  // namespace bvhlab
