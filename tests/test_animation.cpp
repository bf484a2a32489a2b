// Animated scenes (datasets/animation.hpp, docs/scene-format.md "Animation"): keyframe interpolation,
// the procedural deformations, a scene at a frame and its per-object instances, the bench animations,
// and every refused animation input naming FILE:LINE and the key.
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>
#include <gtest/gtest.h>

#include "datasets/animation.hpp"
#include "datasets/scene_io.hpp"
#include "layout/layout.hpp"
#include "require.hpp"

using namespace bvhlab;
namespace fs = std::filesystem;

namespace {

const fs::path kBench = fs::path(BVHLAB_SOURCE_DIR) / "datasets/scenes/bench";

fs::path writeScene(const std::string& name, const std::string& text) {
  const fs::path p = fs::temp_directory_path() / ("bvhlab_test_animation_" + std::to_string(::getpid()) + "_" + name + ".toml");
  std::ofstream(p) << text;
  return p;
}

std::string loadError(const fs::path& p) {
  try {
    loadScene(p);
  } catch (const InputError& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("UNEXPECTED EXCEPTION: ") + e.what();
  }
  return "";
}

const std::string kCamera = "[camera]\neye = [0, 1, 5]\ntarget = [0, 0, 0]\n";
const std::string kClip = "[clip]\nframes = 40\nfps = 20\n";

// A generated terrain patch (welded heightfield, 2000 triangles) with a deformation.
std::string deformedTerrain(const std::string& deform) {
  return kClip + kCamera + "[[object]]\nkind = \"mesh\"\ngenerate = \"terrain\"\ntriangles = 2000\nfit = 2\n" +
         "[object.deform]\n" + deform;
}

bool sameBits(const std::vector<glm::vec3>& a, const std::vector<glm::vec3>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(glm::vec3)) == 0;
}

bool allFinite(const Mesh& m) {
  for (const glm::vec3& p : m.positions)
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) return false;
  return true;
}

RigidKey key(int frame, glm::dvec3 position, glm::dquat rotation, glm::dvec3 scale) {
  RigidKey k;
  k.frame = frame;
  k.position = position;
  k.rotation = rotation;
  k.scale = scale;
  return k;
}

}  // namespace

// ---- keyframes ----

TEST(Keyframes, AtKeysExactlyTheKeyValues) {
  const glm::dquat r1 = glm::angleAxis(0.7, glm::normalize(glm::dvec3(1, 2, 3)));
  const glm::dquat r2 = glm::angleAxis(-1.9, glm::normalize(glm::dvec3(-1, 0.5, 0.2)));
  const std::vector<RigidKey> keys = {key(0, {1, 2, 3}, glm::dquat(1, 0, 0, 0), glm::dvec3(1)),
                                      key(7, {-4, 0.25, 9}, r1, {2, 3, 0.5}),
                                      key(20, {0.1, 0.2, 0.3}, r2, glm::dvec3(0.3))};
  for (const RigidKey& k : keys) {
    const RigidPose p = samplePose(keys, double(k.frame));
    EXPECT_EQ(p.position, k.position) << k.frame;
    EXPECT_EQ(p.rotation, k.rotation) << k.frame;
    EXPECT_EQ(p.scale, k.scale) << k.frame;
  }
}

TEST(Keyframes, SlerpMidpointOfA90DegreeTurnIs45Degrees) {
  const std::vector<RigidKey> keys = {key(0, glm::dvec3(0), glm::dquat(1, 0, 0, 0), glm::dvec3(1)),
                                      key(10, glm::dvec3(0), glm::angleAxis(glm::radians(90.0), glm::dvec3(0, 1, 0)),
                                          glm::dvec3(1))};
  const RigidPose mid = samplePose(keys, 5.0);
  EXPECT_NEAR(glm::degrees(glm::angle(mid.rotation)), 45.0, 1e-9);
  const glm::dvec3 x = mid.rotation * glm::dvec3(1, 0, 0);
  EXPECT_NEAR(x.x, std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(x.z, -std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(x.y, 0.0, 1e-12);
  // A quarter of the way: 22.5 degrees (slerp is uniform in angle; a normalised lerp would give ~22.0).
  EXPECT_NEAR(glm::degrees(glm::angle(samplePose(keys, 2.5).rotation)), 22.5, 1e-9);
}

TEST(Keyframes, SlerpTakesTheShortArc) {
  // The same 90-degree turn written with the opposite sign of the second quaternion: still 45 at the middle.
  const glm::dquat q = glm::angleAxis(glm::radians(90.0), glm::dvec3(0, 1, 0));
  const std::vector<RigidKey> keys = {key(0, glm::dvec3(0), glm::dquat(1, 0, 0, 0), glm::dvec3(1)),
                                      key(10, glm::dvec3(0), -q, glm::dvec3(1))};
  EXPECT_NEAR(glm::degrees(glm::angle(samplePose(keys, 5.0).rotation * (glm::dquat(1, 0, 0, 0)))) , 45.0, 1e-9);
}

TEST(Keyframes, PositionAndScaleAreLinearAndClampedOutsideTheKeys) {
  const std::vector<RigidKey> keys = {key(4, {0, 0, 0}, glm::dquat(1, 0, 0, 0), glm::dvec3(1)),
                                      key(8, {4, -8, 2}, glm::dquat(1, 0, 0, 0), glm::dvec3(3))};
  const RigidPose q = samplePose(keys, 5.0);
  EXPECT_DOUBLE_EQ(q.position.x, 1.0);
  EXPECT_DOUBLE_EQ(q.position.y, -2.0);
  EXPECT_DOUBLE_EQ(q.scale.z, 1.5);
  for (double f : {-3.0, 0.0, 3.999}) EXPECT_EQ(samplePose(keys, f).position, keys[0].position) << f;
  for (double f : {8.0, 9.0, 1e6}) EXPECT_EQ(samplePose(keys, f).position, keys[1].position) << f;
}

TEST(Keyframes, CameraPathInterpolatesAndClamps) {
  CameraKey a, b;
  a.frame = 2, a.eye = {0, 0, 10}, a.target = {0, 0, 0}, a.fovDeg = 40;
  b.frame = 6, b.eye = {4, 0, 10}, b.target = {0, 4, 0}, b.fovDeg = 60;
  const Camera base;
  const Camera mid = sampleCamera({a, b}, 4.0, base);
  EXPECT_FLOAT_EQ(mid.eye.x, 2.0f);
  EXPECT_FLOAT_EQ(mid.target.y, 2.0f);
  EXPECT_FLOAT_EQ(mid.fovDeg, 50.0f);
  EXPECT_EQ(sampleCamera({a, b}, 0.0, base).eye, glm::vec3(0, 0, 10));
  EXPECT_EQ(sampleCamera({a, b}, 30.0, base).target, glm::vec3(0, 4, 0));
}

// Keys in a scene file arrive as written: quaternion [w, x, y, z], axis-angle and Euler spellings agree.
TEST(Keyframes, SceneFileKeysPlaceTheObject) {
  const fs::path p = writeScene("keys", kClip + kCamera +
                                            "[[object]]\nkind = \"box\"\n"
                                            "[[object.keys]]\nframe = 0\nposition = [1, 2, 3]\nrotation = [1, 0, 0, 0]\n"
                                            "[[object.keys]]\nframe = 10\nrotation = { axis = [0, 1, 0], angle = 90 }\nscale = 2\n"
                                            "[[object.keys]]\nframe = 20\nrotation = [0, 90, 0]\nposition = [5, 2, 3]\n");
  Scene s = loadScene(p);
  ASSERT_TRUE(s.animation);
  EXPECT_EQ(clipFrames(s), 40);
  EXPECT_DOUBLE_EQ(clipFps(s), 20.0);
  const auto& keys = s.animation->objects.at(0).keys;
  ASSERT_EQ(keys.size(), 3u);
  EXPECT_EQ(keys[1].position, glm::dvec3(1, 2, 3));  // carried over from the previous key
  EXPECT_EQ(keys[2].scale, glm::dvec3(2));
  EXPECT_NEAR(std::abs(glm::dot(keys[1].rotation, keys[2].rotation)), 1.0, 1e-12);  // same rotation, two spellings
  EXPECT_EQ(s.objects[0].transform, glm::mat4(1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 1, 2, 3, 1));
  setFrame(s, 30);  // after the last key: the last key's pose
  const glm::vec3 x = glm::vec3(s.objects[0].transform * glm::vec4(1, 0, 0, 1));
  EXPECT_NEAR(x.x, 5.0f, 1e-5f);
  EXPECT_NEAR(x.y, 2.0f, 1e-5f);
  EXPECT_NEAR(x.z, 3.0f - 2.0f, 1e-5f);  // scaled by 2, turned 90 degrees about +Y: +X goes to -Z
}

// ---- deformations ----

TEST(Deformations, FrameZeroIsTheRestMeshAndLaterFramesMove) {
  for (const std::string& d : {std::string("kind = \"wave\"\namplitude = 0.1\nwavelength = 0.5\n"),
                               std::string("kind = \"twist\"\nangle = 60\n"),
                               std::string("kind = \"breathe\"\namplitude = 0.2\n"),
                               std::string("kind = \"explode\"\nspeed = 0.5\n")}) {
    SCOPED_TRACE(d);
    const Scene s = loadScene(writeScene("rest", deformedTerrain(d)));
    ASSERT_TRUE(s.animation);
    const Mesh& rest = s.animation->localMeshes.at(size_t(s.animation->objects.at(0).localMesh));
    EXPECT_TRUE(sameBits(s.meshes[0].positions, rest.positions));  // no placement: world = object space
    EXPECT_TRUE(sameBits(localMeshAt(s, 0, 0).positions, rest.positions));
    const Scene later = sceneAtFrame(s, 7);
    ASSERT_EQ(later.meshes[0].positions.size(), rest.positions.size());
    double moved = 0.0;
    for (size_t i = 0; i < rest.positions.size(); ++i)
      moved = std::max(moved, double(glm::length(later.meshes[0].positions[i] - rest.positions[i])));
    EXPECT_GT(moved, 0.01);
    EXPECT_EQ(later.meshes[0].triangles, s.meshes[0].triangles);
  }
}

TEST(Deformations, BreatheAtAQuarterPeriodScalesByOnePlusTheAmplitude) {
  // fps 20, frequency 0.5 Hz: frame 10 is t = 0.5 s, a quarter period: sin = 1.
  const Scene s = loadScene(writeScene("breathe", deformedTerrain("kind = \"breathe\"\namplitude = 0.2\nfrequency = 0.5\n")));
  const Deform& d = s.animation->objects[0].deform;
  const Mesh& rest = s.animation->localMeshes[0];
  const Scene q = sceneAtFrame(s, 10);
  for (size_t i = 0; i < rest.positions.size(); i += 97) {
    const glm::dvec3 expect = d.centre + (glm::dvec3(rest.positions[i]) - d.centre) * 1.2;
    EXPECT_NEAR(q.meshes[0].positions[i].x, expect.x, 1e-5);
    EXPECT_NEAR(q.meshes[0].positions[i].y, expect.y, 1e-5);
  }
}

TEST(Deformations, TwistTurnsTheEndsByTheAngleAndKeepsTheMiddle) {
  // Twist about +X (the terrain is 2 wide along X after fit): at a quarter period the ends turn by +-90.
  const Scene s = loadScene(writeScene("twist", deformedTerrain("kind = \"twist\"\nangle = 90\nfrequency = 0.5\naxis = [1, 0, 0]\n")));
  const ObjectAnimation& a = s.animation->objects[0];
  const Mesh& rest = s.animation->localMeshes[0];
  const Scene q = sceneAtFrame(s, 10);
  for (size_t i = 0; i < rest.positions.size(); ++i) {
    const glm::dvec3 r = glm::dvec3(rest.positions[i]) - a.deform.centre;
    const glm::dvec3 p = glm::dvec3(q.meshes[0].positions[i]) - a.deform.centre;
    EXPECT_NEAR(p.x, r.x, 1e-5);  // along the axis nothing moves
    EXPECT_NEAR(glm::length(glm::dvec2(p.y, p.z)), glm::length(glm::dvec2(r.y, r.z)), 1e-5);  // a rotation about it
    if (std::abs(std::abs(r.x) - a.halfHeight) < 1e-9 && glm::length(glm::dvec2(r.y, r.z)) > 1e-3) {
      const double turned = std::atan2(p.z, p.y) - std::atan2(r.z, r.y);
      EXPECT_NEAR(std::abs(std::remainder(turned, 2 * glm::pi<double>())), glm::pi<double>() / 2, 1e-4) << i;
    }
  }
}

TEST(Deformations, ExplodeMovesPiecesApartMonotonically) {
  const Scene s = loadScene(writeScene("explode", deformedTerrain("kind = \"explode\"\nspeed = 0.4\njitter = 0.5\nseed = 3\n")));
  const ObjectAnimation& a = s.animation->objects[0];
  const size_t triangles = s.meshes[0].triangles.size();
  ASSERT_EQ(a.pieceVelocity.size(), triangles);  // one piece per triangle
  std::vector<double> last(triangles, -1.0);
  double lastMean = -1.0;
  for (int f = 0; f < clipFrames(s); f += 3) {
    const Scene q = sceneAtFrame(s, f);
    const Mesh& m = q.meshes[0];
    double mean = 0.0;
    for (size_t t = 0; t < triangles; ++t) {
      const glm::uvec3 tri = m.triangles[t];
      const glm::dvec3 c = (glm::dvec3(m.positions[tri.x]) + glm::dvec3(m.positions[tri.y]) + glm::dvec3(m.positions[tri.z])) / 3.0;
      const double dist = glm::length(c - a.deform.centre);
      if (f > 0) {
        ASSERT_GT(dist, last[t]) << "triangle " << t << " frame " << f;
      }
      last[t] = dist;
      mean += dist / double(triangles);
    }
    EXPECT_GT(mean, lastMean) << f;
    lastMean = mean;
  }
  // Seeded: the same seed gives the same velocities, another seed others.
  const Scene same = loadScene(writeScene("explode2", deformedTerrain("kind = \"explode\"\nspeed = 0.4\njitter = 0.5\nseed = 3\n")));
  const Scene other = loadScene(writeScene("explode3", deformedTerrain("kind = \"explode\"\nspeed = 0.4\njitter = 0.5\nseed = 4\n")));
  EXPECT_EQ(same.animation->objects[0].pieceVelocity, a.pieceVelocity);
  EXPECT_NE(other.animation->objects[0].pieceVelocity, a.pieceVelocity);
  // And the same with every compiler: the velocities are pinned by a hash of their bits (FNV-1a 64). The
  // three draws of a jitter vector were once the arguments of one constructor, an order each compiler
  // chose for itself; a deliberate change to the explosion updates this value.
  uint64_t hash = 0xcbf29ce484222325ull;
  for (const glm::dvec3& v : a.pieceVelocity)
    for (int k = 0; k < 3; ++k) {
      uint64_t bits;
      std::memcpy(&bits, &v[k], sizeof bits);
      for (int b = 0; b < 8; ++b) hash = (hash ^ ((bits >> (8 * b)) & 0xffu)) * 0x100000001b3ull;
    }
  EXPECT_EQ(hash, 0xccb4bd7219ea7b32ull) << std::hex << "velocity hash 0x" << hash;
}

TEST(Deformations, ExplodeByComponentsKeepsEachComponentRigid) {
  // Two separate triangles' worth of components: the hairball's ribbons are separate strips.
  const Scene s = loadScene(writeScene("components", kClip + kCamera +
                                                         "[[object]]\nkind = \"mesh\"\ngenerate = \"hairball\"\ntriangles = 2000\n"
                                                         "[object.deform]\nkind = \"explode\"\npieces = \"components\"\n"));
  const ObjectAnimation& a = s.animation->objects[0];
  ASSERT_GT(a.pieceVelocity.size(), 1u);
  ASSERT_LT(a.pieceVelocity.size(), s.meshes[0].triangles.size());
  const Scene q = sceneAtFrame(s, 20);
  // Every vertex of a piece moves by the same vector.
  std::vector<glm::dvec3> shift(a.pieceVelocity.size(), glm::dvec3(NAN));
  for (size_t v = 0; v < q.meshes[0].positions.size(); ++v) {
    const glm::dvec3 d = glm::dvec3(q.meshes[0].positions[v]) - glm::dvec3(s.meshes[0].positions[v]);
    glm::dvec3& sh = shift[a.vertexPiece[v]];
    if (std::isnan(sh.x)) sh = d;
    EXPECT_NEAR(glm::length(d - sh), 0.0, 1e-5) << v;
  }
}

// Normals follow the deformation through its Jacobian: deformJacobian matches central differences of
// deformPositions. Step ~1e-5 (rest positions are float, so the step actually taken divides): the
// truncation error is ~h^2 times the third derivative (<= (2 pi / 0.7)^3 ~ 700 here: ~1e-7) and the
// rounding error ~1e-16 / h = 1e-11, both below the 1e-6 bound.
TEST(Deformations, JacobianMatchesFiniteDifferences) {
  std::vector<ObjectAnimation> anims(3);
  anims[0].deform.kind = DeformKind::Wave;
  anims[0].deform.amplitude = 0.3, anims[0].deform.wavelength = 0.7, anims[0].deform.frequency = 0.8;
  anims[0].deform.direction = glm::normalize(glm::dvec3(1, 0.2, 0.3));
  anims[1].deform.kind = DeformKind::Twist;
  anims[1].deform.angleDeg = 70, anims[1].deform.frequency = 0.3, anims[1].halfHeight = 1.3;
  anims[1].deform.axis = glm::normalize(glm::dvec3(0.2, 1, -0.1));
  anims[1].deform.centre = glm::dvec3(0.1, 0.2, -0.3);
  anims[2].deform.kind = DeformKind::Breathe;
  anims[2].deform.amplitude = 0.4, anims[2].deform.frequency = 0.6;
  const double t = 0.45, h = 1e-5;
  for (const ObjectAnimation& a : anims)
    for (const glm::dvec3 p : {glm::dvec3(0.3, -0.7, 0.2), glm::dvec3(-1.1, 0.9, 0.4), glm::dvec3(0.05, 1.2, -0.8)}) {
      SCOPED_TRACE(deformKindName(a.deform.kind));
      const glm::dmat3 j = deformJacobian(a, p, t);
      for (int axis = 0; axis < 3; ++axis) {
        Mesh two;
        glm::dvec3 e(0.0);
        e[axis] = h;
        two.positions = {glm::vec3(p + e), glm::vec3(p - e)};
        std::vector<glm::dvec3> out;
        deformPositions(a, two, t, out);
        const glm::dvec3 column = (out[0] - out[1]) / (glm::dvec3(two.positions[0]) - glm::dvec3(two.positions[1]))[axis];
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(j[axis][k], column[k], 1e-6) << axis << "," << k;
      }
    }
}

TEST(Deformations, EvaluationIsBitForBitDeterministic) {
  const std::vector<std::string> deforms = {"kind = \"wave\"\namplitude = 0.1\n", "kind = \"twist\"\n",
                                            "kind = \"breathe\"\n", "kind = \"explode\"\n"};
  for (const std::string& d : deforms) {
    SCOPED_TRACE(d);
    const Scene s = loadScene(writeScene("det", deformedTerrain(d) + "[[object]]\nkind = \"sphere\"\n"
                                                                     "[[object.keys]]\nframe = 0\n[[object.keys]]\nframe = 39\nposition = [3, 1, 0]\nrotation = [20, 40, 60]\n"));
    const Scene again = loadScene(writeScene("det", deformedTerrain(d) + "[[object]]\nkind = \"sphere\"\n"
                                                                         "[[object.keys]]\nframe = 0\n[[object.keys]]\nframe = 39\nposition = [3, 1, 0]\nrotation = [20, 40, 60]\n"));
    for (int f : {0, 13, 39}) {
      const Scene a = sceneAtFrame(s, f), b = sceneAtFrame(s, f), c = sceneAtFrame(again, f);
      EXPECT_TRUE(sameBits(a.meshes[0].positions, b.meshes[0].positions)) << f;
      EXPECT_TRUE(sameBits(a.meshes[0].positions, c.meshes[0].positions)) << f;
      EXPECT_EQ(a.objects[1].transform, c.objects[1].transform) << f;
    }
    // Going to a frame and back gives the loaded scene again.
    Scene back = sceneAtFrame(s, 25);
    setFrame(back, 0);
    EXPECT_TRUE(sameBits(back.meshes[0].positions, s.meshes[0].positions));
    EXPECT_EQ(back.objects[1].transform, s.objects[1].transform);
  }
}

// ---- a scene at a frame; instances ----

TEST(SceneAtFrame, StaticScenesAreUnchangedAndHaveOneFrame) {
  const Scene s = loadScene(writeScene("static", kCamera + "[[object]]\nkind = \"mesh\"\ngenerate = \"terrain\"\ntriangles = 2000\n"));
  EXPECT_FALSE(s.animation);
  EXPECT_EQ(clipFrames(s), 1);
  const Scene same = sceneAtFrame(s, 0);
  EXPECT_TRUE(sameBits(same.meshes[0].positions, s.meshes[0].positions));
  EXPECT_THROW(sceneAtFrame(s, 1), std::out_of_range);
  const std::vector<ObjectInstance> inst = objectInstances(s, 0);
  ASSERT_EQ(inst.size(), 1u);
  EXPECT_EQ(inst[0].localMesh, -1);
  EXPECT_EQ(inst[0].transform, glm::mat4(1.0f));
  EXPECT_FALSE(inst[0].moves || inst[0].deforms);
}

TEST(SceneAtFrame, InstancesCoverTheSoupAndTheirTransformPlacesTheLocalTriangles) {
  const Scene s = loadScene(writeScene("instances", kClip + kCamera +
                                                        "[[object]]\nkind = \"mesh\"\ngenerate = \"terrain\"\ntriangles = 2000\nfit = 1\n"
                                                        "[[object.keys]]\nframe = 0\nposition = [-2, 0, 0]\n"
                                                        "[[object.keys]]\nframe = 30\nposition = [2, 1, 0]\nrotation = { axis = [0, 0, 1], angle = 120 }\nscale = [1, 2, 1]\n"
                                                        "[[object]]\nkind = \"sphere\"\n"
                                                        "[[object]]\nkind = \"mesh\"\ngenerate = \"terrain\"\ntriangles = 2000\nfit = 1\n"
                                                        "[[object.keys]]\nframe = 5\nposition = [0, 3, 0]\n"
                                                        "[object.deform]\nkind = \"wave\"\namplitude = 0.2\n"
                                                        "[[object]]\nkind = \"mesh\"\ngenerate = \"hairball\"\ntriangles = 2000\n"));
  for (int f : {0, 17, 39}) {
    SCOPED_TRACE(f);
    const Scene q = sceneAtFrame(s, f);
    const TriangleSoup soup = gatherTriangles(q);
    const std::vector<ObjectInstance> inst = objectInstances(s, f);
    ASSERT_EQ(inst.size(), 4u);
    EXPECT_EQ(inst[1].mesh, -1);
    EXPECT_TRUE(inst[0].moves && !inst[0].deforms);
    EXPECT_TRUE(!inst[2].moves && inst[2].deforms);
    EXPECT_EQ(inst[3].localMesh, -1);
    EXPECT_EQ(inst[0].localMesh, inst[2].localMesh);  // one rest mesh for the two terrain instances
    uint32_t next = 0;
    for (const ObjectInstance& i : inst) {
      if (i.mesh < 0) continue;
      EXPECT_EQ(i.firstTriangle, next);
      next += i.triangleCount;
      EXPECT_EQ(i.transform, q.objects[size_t(i.object)].kind == ObjectKind::Mesh && i.localMesh < 0
                                 ? glm::mat4(1.0f) : q.objects[size_t(i.object)].transform);
      const Mesh local = localMeshAt(s, i.object, f);
      ASSERT_EQ(local.triangles.size(), i.triangleCount);
      for (uint32_t t = 0; t < i.triangleCount; t += 37) {
        const glm::vec3 w = glm::vec3(i.transform * glm::vec4(local.positions[local.triangles[t].x], 1.0f));
        const glm::vec3 soupV0 = soup.v0[i.firstTriangle + t];
        EXPECT_NEAR(glm::length(w - soupV0), 0.0f, 1e-5f) << t;
      }
    }
    EXPECT_EQ(next, soup.size());
    std::vector<glm::vec3> v0, v1, v2;
    triangleCorners(q, v0, v1, v2);
    EXPECT_TRUE(sameBits(v0, soup.v0) && sameBits(v1, soup.v1) && sameBits(v2, soup.v2));
  }
}

TEST(SceneAtFrame, CameraPathMovesTheCamera) {
  const Scene s = loadScene(writeScene("camera", kClip +
                                                     "[camera]\nfov = 40\n"
                                                     "[[camera.keys]]\nframe = 0\neye = [0, 1, 5]\ntarget = [0, 0, 0]\n"
                                                     "[[camera.keys]]\nframe = 20\neye = [5, 1, 0]\nfov = 60\n" + "[[object]]\nkind = \"sphere\"\n"));
  EXPECT_EQ(s.camera.eye, glm::vec3(0, 1, 5));
  EXPECT_EQ(s.camera.fovDeg, 40.0f);
  const Scene q = sceneAtFrame(s, 10);
  EXPECT_FLOAT_EQ(q.camera.eye.x, 2.5f);
  EXPECT_FLOAT_EQ(q.camera.eye.z, 2.5f);
  EXPECT_FLOAT_EQ(q.camera.fovDeg, 50.0f);
  EXPECT_EQ(sceneAtFrame(s, 39).camera.eye, glm::vec3(5, 1, 0));
}

// The example of docs/scene-format.md's "Animation" section loads and moves as the page says.
TEST(AnimationDocs, TheExampleLoadsAndMoves) {
  if (!fs::exists(fs::path(BVHLAB_SOURCE_DIR) / "datasets/cache/meshes/cow.off"))
    BVHLAB_SKIP_OR_FAIL("needs the dataset cache: run `bash datasets/fetch.sh`");
  std::ifstream in(fs::path(BVHLAB_SOURCE_DIR) / "docs/scene-format.md");
  const std::string doc((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t section = doc.find("\n## Animation\n");
  ASSERT_NE(section, std::string::npos);
  const size_t begin = doc.find("```toml\n", section);
  ASSERT_NE(begin, std::string::npos);
  std::string example = doc.substr(begin + 8, doc.find("```", begin + 8) - begin - 8);
  for (size_t at = example.find("../cache/"); at != std::string::npos; at = example.find("../cache/", at))
    example.replace(at, 9, (fs::path(BVHLAB_SOURCE_DIR) / "datasets/cache").string() + "/");
  const Scene s = loadScene(writeScene("docs", example));
  ASSERT_TRUE(s.animation);
  EXPECT_EQ(clipFrames(s), 60);
  const Scene q = sceneAtFrame(s, 30);
  EXPECT_EQ(glm::vec3(q.objects[0].transform[3]), glm::vec3(2, 0, 0));
  EXPECT_TRUE(s.animation->objects[1].deforms());
  EXPECT_FLOAT_EQ(sceneAtFrame(s, 59).camera.eye.x, 6.0f);
}

// ---- the bench animations ----

class BenchAnimation : public ::testing::TestWithParam<std::string> {};

TEST_P(BenchAnimation, LoadsAndEvaluatesAtFirstMiddleAndLastFrame) {
  Scene s;
  try {
    s = loadScene(kBench / GetParam());
  } catch (const InputError& e) {
    if (std::string(e.what()).find("fetch.sh") != std::string::npos) BVHLAB_SKIP_OR_FAIL(e.what());
    FAIL() << e.what();
  }
  ASSERT_TRUE(s.animation);
  const int frames = clipFrames(s);
  ASSERT_GE(frames, 2);
  const size_t triangles = s.triangleCount();
  for (int f : {0, frames / 2, frames - 1}) {
    const Scene q = sceneAtFrame(s, f);
    EXPECT_EQ(q.triangleCount(), triangles);
    for (const Mesh& m : q.meshes) ASSERT_TRUE(allFinite(m)) << GetParam() << " frame " << f;
    EXPECT_EQ(gatherTriangles(q).size(), triangles);
  }
  const std::string name = GetParam();
  size_t moving = 0, deforming = 0;
  for (const ObjectInstance& i : objectInstances(s, 0)) moving += i.moves, deforming += i.deforms;
  if (name == "anim-rigid.toml") {
    EXPECT_GE(moving, 100u);
    EXPECT_EQ(deforming, 0u);
    EXPECT_LE(s.animation->localMeshes.size(), 4u);  // a few meshes, many instances
  } else if (name == "anim-deform.toml" || name == "anim-explode.toml") {
    EXPECT_GE(deforming, 1u);
  } else if (name == "anim-flythrough.toml") {
    EXPECT_EQ(moving + deforming, 0u);
    EXPECT_FALSE(s.animation->camera.empty());
    EXPECT_NE(sceneAtFrame(s, frames - 1).camera.eye, s.camera.eye);
  }
}

INSTANTIATE_TEST_SUITE_P(Bench, BenchAnimation,
                         ::testing::Values("anim-rigid.toml", "anim-deform.toml", "anim-explode.toml", "anim-flythrough.toml"),
                         [](const ::testing::TestParamInfo<std::string>& i) {
                           std::string n = i.param.substr(5, i.param.size() - 10);
                           return n;
                         });

// ---- refused input ----

struct BadAnimation {
  const char* label;
  std::string text;
  std::string expect;
};

TEST(AnimationErrors, EveryProblemNamesFileLineAndKey) {
  const std::string box = "[[object]]\nkind = \"box\"\n";
  const std::string mesh = "[[object]]\nkind = \"mesh\"\ngenerate = \"terrain\"\ntriangles = 2000\n";
  const std::vector<BadAnimation> cases = {
      {"unknown clip key", "[clip]\nframes = 10\nspeed = 2 #!\n" + kCamera + box, "unknown key 'speed' in [clip]"},
      {"missing frames", "[clip] #!\nfps = 24\n" + kCamera + box, "clip: missing required key 'frames'"},
      {"negative frames", "[clip]\nframes = -5 #!\n" + kCamera + box, "clip.frames must be in [1, 1000000]"},
      {"zero frames", "[clip]\nframes = 0 #!\n" + kCamera + box, "clip.frames must be in [1"},
      {"fractional frames", "[clip]\nframes = 2.5 #!\n" + kCamera + box, "clip.frames must be an integer"},
      {"zero fps", "[clip]\nframes = 10\nfps = 0 #!\n" + kCamera + box, "clip.fps must be > 0"},
      {"NaN fps", "[clip]\nframes = 10\nfps = nan #!\n" + kCamera + box, "clip.fps is NaN or infinite"},
      {"clip not a table", "clip = 3 #!\n" + kCamera + box, "'clip' must be a table"},
      {"keys without clip", kCamera + box + "[[object.keys]] #!\nframe = 0\n", "keys need a [clip]"},
      {"keys not tables", kClip + kCamera + box + "keys = 3 #!\n", "keys must be an array of tables"},
      {"key without frame", kClip + kCamera + box + "[[object.keys]] #!\nposition = [0, 0, 0]\n",
       "keys[0]: missing required key 'frame'"},
      {"negative key frame", kClip + kCamera + box + "[[object.keys]]\nframe = -1 #!\n", "keys[0].frame must be in [0, 39]"},
      {"key frame past the clip", kClip + kCamera + box + "[[object.keys]]\nframe = 40 #!\n", "keys[0].frame must be in [0, 39]"},
      {"non-increasing key frames", kClip + kCamera + box + "[[object.keys]]\nframe = 5\n[[object.keys]]\nframe = 5 #!\n",
       "keys[1].frame must be greater than the previous key's frame (5, got 5)"},
      {"decreasing key frames", kClip + kCamera + box + "[[object.keys]]\nframe = 5\n[[object.keys]]\nframe = 2 #!\n",
       "must be greater than the previous key's frame"},
      {"zero quaternion", kClip + kCamera + box + "[[object.keys]]\nframe = 0\nrotation = [0, 0, 0, 0] #!\n",
       "keys[0].rotation must not be a zero quaternion"},
      {"rotation length", kClip + kCamera + box + "[[object.keys]]\nframe = 0\nrotation = [1, 0] #!\n",
       "keys[0].rotation must be a quaternion [w, x, y, z]"},
      {"rotation zero axis", kClip + kCamera + box + "[[object.keys]]\nframe = 0\nrotation = { axis = [0, 0, 0], angle = 3 } #!\n",
       "rotation.axis must not be zero"},
      {"NaN position", kClip + kCamera + box + "[[object.keys]]\nframe = 0\nposition = [0, nan, 0] #!\n",
       "keys[0].position[1] is NaN or infinite"},
      {"NaN quaternion", kClip + kCamera + box + "[[object.keys]]\nframe = 0\nrotation = [1, 0, nan, 0] #!\n",
       "keys[0].rotation[2] is NaN or infinite"},
      {"negative key scale", kClip + kCamera + box + "[[object.keys]]\nframe = 0\nscale = -1 #!\n", "keys[0].scale must be > 0"},
      {"unknown key in keys", kClip + kCamera + box + "[[object.keys]]\nframe = 0\ntranslate = [1, 0, 0] #!\n",
       "unknown key 'translate' in [[object.keys]]"},
      {"translate with keys", kClip + kCamera + "[[object]]\nkind = \"box\"\ntranslate = [1, 0, 0] #!\n[[object.keys]]\nframe = 0\n",
       "'translate' and keys exclude each other"},
      {"deform without clip", kCamera + mesh + "[object.deform] #!\nkind = \"wave\"\n", "a deformation needs a [clip]"},
      {"unknown deform kind", kClip + kCamera + mesh + "[object.deform]\nkind = \"melt\" #!\n",
       "deform.kind: unknown deformation \"melt\" (wave, twist, breathe, explode)"},
      {"deform without kind", kClip + kCamera + mesh + "[object.deform] #!\namplitude = 1\n", "deform: missing required key 'kind'"},
      {"deform on a sphere", kClip + kCamera + "[[object]]\nkind = \"sphere\"\n[object.deform] #!\nkind = \"wave\"\n",
       "key 'deform' is only valid with kind = \"mesh\""},
      {"deform key of another kind", kClip + kCamera + mesh + "[object.deform]\nkind = \"twist\"\namplitude = 1 #!\n",
       "unknown key 'amplitude' in object 1 (mesh1).deform (kind = \"twist\")"},
      {"wave wavelength", kClip + kCamera + mesh + "[object.deform]\nkind = \"wave\"\nwavelength = 0 #!\n", "deform.wavelength must be > 0"},
      {"wave zero axis", kClip + kCamera + mesh + "[object.deform]\nkind = \"wave\"\naxis = [0, 0, 0] #!\n", "deform.axis must not be zero"},
      {"breathe amplitude", kClip + kCamera + mesh + "[object.deform]\nkind = \"breathe\"\namplitude = 1 #!\n",
       "deform.amplitude must be [0, 1)"},
      {"explode jitter", kClip + kCamera + mesh + "[object.deform]\nkind = \"explode\"\njitter = 1 #!\n", "deform.jitter must be [0, 1)"},
      {"explode speed", kClip + kCamera + mesh + "[object.deform]\nkind = \"explode\"\nspeed = -2 #!\n", "deform.speed must be > 0"},
      {"explode pieces", kClip + kCamera + mesh + "[object.deform]\nkind = \"explode\"\npieces = \"atoms\" #!\n",
       "deform.pieces must be \"triangles\" or \"components\""},
      {"explode seed", kClip + kCamera + mesh + "[object.deform]\nkind = \"explode\"\nseed = -1 #!\n", "deform.seed must be a non-negative integer"},
      {"NaN deform value", kClip + kCamera + mesh + "[object.deform]\nkind = \"twist\"\nangle = nan #!\n", "deform.angle is NaN or infinite"},
      {"explode past float's range", kClip + kCamera + mesh + "[object.deform] #!\nkind = \"explode\"\nspeed = 3e38\nspeed_jitter = 0\n",
       "leaves float's range"},
      {"key position past float's range", kClip + kCamera + mesh + "[[object.keys]] #!\nframe = 0\n[[object.keys]]\nframe = 9\nposition = [1e39, 0, 0]\n",
       "object 'mesh1' at frame 39: vertex 0 leaves float's range"},
      {"camera keys and eye", kClip + "[camera]\neye = [0, 1, 5] #!\n[[camera.keys]]\nframe = 0\neye = [0, 1, 5]\ntarget = [0, 0, 0]\n" + box,
       "give either eye and target or [[camera.keys]]"},
      {"camera keys without clip", "[camera]\n[[camera.keys]] #!\nframe = 0\neye = [0, 1, 5]\ntarget = [0, 0, 0]\n" + box,
       "keys need a [clip]"},
      {"first camera key without target", kClip + "[camera]\n[[camera.keys]] #!\nframe = 0\neye = [0, 1, 5]\n" + box,
       "camera.keys[0]: missing required key 'target'"},
      {"camera path through its target", kClip +
           "[camera]\n[[camera.keys]] #!\nframe = 0\neye = [0, 1, 5]\ntarget = [0, 1, -5]\n[[camera.keys]]\nframe = 20\neye = [0, 1, -5]\ntarget = [0, 1, 5]\n" + box,
       "camera.keys: at frame 10 eye and target coincide"},
      {"camera key fov", kClip + "[camera]\n[[camera.keys]]\nframe = 0\neye = [0, 1, 5]\ntarget = [0, 0, 0]\nfov = 0 #!\n" + box,
       "camera.keys[0].fov must be (0, 180)"},
  };
  for (const BadAnimation& c : cases) {
    SCOPED_TRACE(c.label);
    const fs::path file = writeScene("bad", c.text);
    size_t line = 1;
    const size_t marker = c.text.find("#!");
    ASSERT_NE(marker, std::string::npos);
    for (size_t i = 0; i < marker; ++i) line += c.text[i] == '\n';
    const std::string msg = loadError(file);
    EXPECT_EQ(msg.rfind(file.string() + ":" + std::to_string(line) + ": ", 0), 0u) << msg;
    EXPECT_NE(msg.find(c.expect), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
  }
}
