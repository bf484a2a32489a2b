// Update strategies over animation clips (builders/update.hpp, builders/refit.hpp,
// builders/rotate.hpp), on the synthetic clips of tests/update_test_clips.hpp: a smooth travelling wave
// and an explosion. Refit on several threads: tests/test_refit_threads.cpp.
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "builders/builder.hpp"
#include "builders/refit.hpp"
#include "builders/test_inputs.hpp"
#include "builders/rotate.hpp"
#include "builders/update.hpp"
#include "builder_test_util.hpp"
#include "update_test_clips.hpp"
#include "datasets/scene.hpp"
#include "layout/layout.hpp"
#include "layout/tree_hash.hpp"

namespace bvhlab {
namespace {

using testing::builderNames;
using testing::identical;
using testing::sameBox;
using testing::Clip;
using testing::explodeClip;
using testing::waveClip;

// ---- checks -------------------------------------------------------------------------------------

// The invariants every consumer of a Bvh relies on, for a tree refit to `frame`: a tree (every node
// reached once from the root), leaves of 1..maxLeafSize primitives, every triangle referenced exactly
// once (at least once for a builder that splits primitives), every leaf box the exact union of its
// triangles' boxes in this frame and every inner box the exact union of its children's boxes.
void checkRefitTree(const Bvh& bvh, const FrameTriangles& frame, uint32_t maxLeafSize, bool splits) {
  ASSERT_FALSE(bvh.nodes.empty());
  const size_t n = frame.size();
  std::vector<int> reached(bvh.nodes.size(), 0), referenced(n, 0);
  std::vector<uint32_t> stack{0};
  size_t badLeaves = 0, badInner = 0;
  while (!stack.empty()) {
    const uint32_t index = stack.back();
    stack.pop_back();
    ASSERT_LT(index, bvh.nodes.size());
    ASSERT_EQ(reached[index]++, 0) << "node " << index << " reached twice";
    const BvhNode& node = bvh.nodes[index];
    if (node.isLeaf()) {
      EXPECT_LE(node.count, maxLeafSize);
      ASSERT_LE(size_t(node.first) + node.count, bvh.primIndices.size());
      Aabb tight;
      for (uint32_t k = node.first; k < node.first + node.count; ++k) {
        ASSERT_LT(bvh.primIndices[k], n);
        ++referenced[bvh.primIndices[k]];
        tight.grow(triangleBox(frame, bvh.primIndices[k]));
      }
      badLeaves += !sameBox(node.bounds, tight);
    } else {
      Aabb tight = bvh.nodes.at(node.left).bounds;
      tight.grow(bvh.nodes.at(node.right).bounds);
      badInner += !sameBox(node.bounds, tight);
      stack.push_back(node.right);
      stack.push_back(node.left);
    }
  }
  EXPECT_EQ(badLeaves, 0u) << "leaf boxes that are not the union of their triangles' boxes";
  EXPECT_EQ(badInner, 0u) << "inner boxes that are not the union of their children's boxes";
  EXPECT_EQ(std::count(reached.begin(), reached.end(), 0), 0) << "nodes unreachable from the root";
  for (size_t i = 0; i < n; ++i)
    if (splits ? referenced[i] < 1 : referenced[i] != 1) {
      ADD_FAILURE() << "triangle " << i << " referenced " << referenced[i] << " times";
      break;
    }
}

std::string treeHash(const Bvh& bvh, const FrameTriangles& frame) {
  TriangleSoup soup;
  const size_t n = frame.size();
  soup.v0.assign(frame.v0.begin(), frame.v0.end());
  soup.v1.assign(frame.v1.begin(), frame.v1.end());
  soup.v2.assign(frame.v2.begin(), frame.v2.end());
  for (size_t i = 0; i < n; ++i) {
    const glm::vec3 normal = geometricNormal(soup.v0[i], soup.v1[i], soup.v2[i]);
    soup.n0.push_back(normal), soup.n1.push_back(normal), soup.n2.push_back(normal);
  }
  soup.uv0.assign(n, glm::vec2(0.0f)), soup.uv1 = soup.uv0, soup.uv2 = soup.uv0;
  soup.material.assign(n, 0), soup.mesh.assign(n, 0);
  return packedTreeHash(packBvh(bvh, soup));
}

// The summed half areas of nodes a and b (by index): a swap at a node changes the boxes of its
// children only (of one of them for a child-grandchild swap), which stay at their indices. In double,
// exact for the boxes of these clips (sums of two floats whose exponents differ by far less than the
// 29 bits double has beyond float's 24).
double areas(const Bvh& bvh, uint32_t a, uint32_t b) {
  return double(bvh.nodes[a].bounds.halfArea()) + double(bvh.nodes[b].bounds.halfArea());
}

// sahCost sums one double per node in refitOrder, and a swap changes that order: two trees of
// equal real SAH may differ by the rounding of n additions, at most (n - 1) x 2^-53 relative
// (recursive summation, Higham 2002, eq. 4.4). A swap whose SAH is within that of the one before does
// not raise it.
bool notRaised(double after, double before, size_t nodes) {
  return after <= before * (1.0 + double(nodes) * std::ldexp(1.0, -53));
}

// ---- refit ------------------------------------------------------------------------------------------

class RefitEveryBuilder : public ::testing::TestWithParam<std::string> {};

// A refit of a tree over triangles that did not move gives back the builder's tree: the same nodes,
// bit for bit, and the same tree hash. A builder that splits primitives (sbvh) keeps clipped leaf
// boxes a refit cannot know: its refit tree holds the build's boxes instead.
TEST_P(RefitEveryBuilder, RefitOfAnUnmovedMeshIsTheBuild) {
  const Clip clip = waveClip(40, 30, 1);
  for (uint32_t leafSize : {1u, 4u}) {
    UpdateOptions options;
    options.builder = GetParam();
    options.build.maxLeafSize = leafSize;
    const auto strategy = makeUpdateStrategy("refit", options);
    ASSERT_TRUE(strategy->update(clip.frame(0)));
    const Bvh built = strategy->tree();
    ASSERT_FALSE(strategy->update(clip.frame(0)));
    const Bvh& refit = strategy->tree();
    if (testing::splitsPrimitives(GetParam())) {
      ASSERT_EQ(refit.nodes.size(), built.nodes.size());
      for (size_t i = 0; i < built.nodes.size(); ++i)
        EXPECT_TRUE(refit.nodes[i].bounds.contains(built.nodes[i].bounds)) << "node " << i;
      checkRefitTree(refit, clip.frame(0), leafSize, true);
      continue;
    }
    EXPECT_TRUE(identical(built, refit)) << "leaf size " << leafSize;
    EXPECT_EQ(treeHash(built, clip.frame(0)), treeHash(refit, clip.frame(0))) << "leaf size " << leafSize;
  }
}

// After a refit to a moved mesh, every box is the exact union of what it holds, at every frame of a
// clip, for both the smooth and the exploding clip.
TEST_P(RefitEveryBuilder, RefitBoxesAreExactUnionsAtEveryFrame) {
  const bool splits = testing::splitsPrimitives(GetParam());
  for (const Clip& clip : {waveClip(30, 20, 6), explodeClip(24, 16, 6)}) {
    UpdateOptions options;
    options.builder = GetParam();
    const auto strategy = makeUpdateStrategy("refit", options);
    size_t nodes = 0;
    const std::vector<FrameTriangles> frames = clip.all();
    const std::vector<UpdateRecord> records =
        runClip(*strategy, frames, {}, [&](uint32_t f, const Bvh& tree, UpdateRecord& record) {
          SCOPED_TRACE("frame " + std::to_string(f));
          if (f == 0) nodes = tree.nodes.size();
          EXPECT_EQ(tree.nodes.size(), nodes) << "a refit keeps the topology";
          // Frame 0 is the builder's tree: for sbvh its leaves hold clipped boxes, not whole triangles'.
          if (f > 0 || !splits) checkRefitTree(tree, frames[f], options.build.maxLeafSize, splits);
          EXPECT_EQ(record.sahCost, sahCost(tree, options.build.cost));
        });
    ASSERT_EQ(records.size(), clip.frames());
    for (const UpdateRecord& r : records) EXPECT_EQ(r.rebuilt, r.frame == 0);
  }
}

INSTANTIATE_TEST_SUITE_P(Updates, RefitEveryBuilder, ::testing::ValuesIn(builderNames()),
                         [](const auto& info) {
                           std::string name = info.param;
                           std::replace(name.begin(), name.end(), '-', '_');
                           return name;
                         });

// ---- rotations ----------------------------------------------------------------------------------------

// Swap by swap: at each inner node, children before parents, the best swap lowers the summed half
// area of the nodes it changes, never raises the tree's SAH, and the tree keeps every invariant; the
// swaps made one by one give the tree refitRotateBvh gives, whose SAH is at most the plain refit's.
TEST(Rotations, NeverRaiseTheSahAndKeepEveryInvariant) {
  const Clip clip = explodeClip(20, 12, 4, 0.3f);  // 480 triangles
  const CostModel cost;
  for (const std::string builder : {"sah-binned", "lbvh", "ploc", "median", "sbvh"}) {
    SCOPED_TRACE(builder);
    const bool splits = testing::splitsPrimitives(builder);
    UpdateOptions options;
    options.builder = builder;
    const auto strategy = makeUpdateStrategy("refit", options);
    strategy->update(clip.frame(0));
    Bvh tree = strategy->tree();
    uint32_t rotations = 0;
    for (size_t f = 1; f < clip.frames(); ++f) {
      SCOPED_TRACE("frame " + std::to_string(f));
      Bvh byLibrary = tree;
      const uint32_t libraryRotations = refitRotateBvh(byLibrary, clip.frame(f), cost);
      const std::vector<uint32_t> order = refitOrder(tree);
      refitBvh(tree, order, clip.frame(f));
      const double refitSah = sahCost(tree, cost);
      uint32_t made = 0;
      for (const uint32_t node : order) {
        if (tree.nodes[node].isLeaf()) continue;
        const Rotation rotation = bestRotation(tree, node);
        if (rotation == Rotation::None) continue;
        const uint32_t l = tree.nodes[node].left, r = tree.nodes[node].right;
        const double areasBefore = areas(tree, l, r), sahBefore = sahCost(tree, cost);
        applyRotation(tree, node, rotation);
        ++made;
        EXPECT_LT(areas(tree, l, r), areasBefore) << rotationName(rotation) << " at node " << node;
        EXPECT_PRED3(notRaised, sahCost(tree, cost), sahBefore, tree.nodes.size())
            << rotationName(rotation) << " at node " << node;
        checkRefitTree(tree, clip.frame(f), options.build.maxLeafSize, splits);
        if (::testing::Test::HasFailure()) return;
      }
      EXPECT_EQ(made, libraryRotations);
      EXPECT_TRUE(identical(tree, byLibrary)) << "refitRotateBvh differs from the swaps made one by one";
      EXPECT_PRED3(notRaised, sahCost(tree, cost), refitSah, tree.nodes.size());
      rotations += made;
    }
    EXPECT_GT(rotations, 0u) << "no swap was ever made: the test would check nothing";
  }
}

// Each named swap relinks as documented (builders/rotate.hpp), and one that names a grandchild under a
// leaf is refused.
TEST(Rotations, ApplyRelinksTheNamedSubtrees) {
  // Root 0 with children 1 (leaves 3, 4) and 2 (leaves 5, 6); leaf boxes unit cubes along x.
  auto make = [] {
    Bvh bvh;
    bvh.nodes.resize(7);
    bvh.primIndices = {0, 1, 2, 3};
    for (uint32_t i = 3; i < 7; ++i) {
      bvh.nodes[i].first = i - 3, bvh.nodes[i].count = 1;
      bvh.nodes[i].bounds.grow(glm::vec3(float(i), 0, 0));
      bvh.nodes[i].bounds.grow(glm::vec3(float(i) + 1, 1, 1));
    }
    bvh.nodes[1].left = 3, bvh.nodes[1].right = 4, bvh.nodes[2].left = 5, bvh.nodes[2].right = 6;
    bvh.nodes[0].left = 1, bvh.nodes[0].right = 2;
    for (uint32_t i : {1u, 2u, 0u}) {
      bvh.nodes[i].bounds = bvh.nodes[bvh.nodes[i].left].bounds;
      bvh.nodes[i].bounds.grow(bvh.nodes[bvh.nodes[i].right].bounds);
    }
    return bvh;
  };
  struct Case {
    Rotation rotation;
    uint32_t rootLeft, rootRight, l1, r1, l2, r2;
  };
  for (const Case& c : {Case{Rotation::LeftWithRightLeft, 5, 2, 3, 4, 1, 6},
                        Case{Rotation::LeftWithRightRight, 6, 2, 3, 4, 5, 1},
                        Case{Rotation::RightWithLeftLeft, 1, 3, 2, 4, 5, 6},
                        Case{Rotation::RightWithLeftRight, 1, 4, 3, 2, 5, 6},
                        Case{Rotation::LeftLeftWithRightLeft, 1, 2, 5, 4, 3, 6},
                        Case{Rotation::LeftLeftWithRightRight, 1, 2, 6, 4, 5, 3}}) {
    SCOPED_TRACE(rotationName(c.rotation));
    Bvh bvh = make();
    applyRotation(bvh, 0, c.rotation);
    EXPECT_EQ(bvh.nodes[0].left, c.rootLeft);
    EXPECT_EQ(bvh.nodes[0].right, c.rootRight);
    EXPECT_EQ(bvh.nodes[1].left, c.l1);
    EXPECT_EQ(bvh.nodes[1].right, c.r1);
    EXPECT_EQ(bvh.nodes[2].left, c.l2);
    EXPECT_EQ(bvh.nodes[2].right, c.r2);
    std::vector<glm::vec3> v0, v1, v2;
    for (uint32_t i = 0; i < 4; ++i)
      v0.push_back({float(i + 3), 0, 0}), v1.push_back({float(i + 4), 1, 1}), v2.push_back({float(i + 3), 1, 0});
    checkRefitTree(bvh, {v0, v1, v2}, 1, false);
  }
  // The tree is sorted along x: no swap lowers the area. Crossed ({6, 4} and {5, 3}), some swap does.
  EXPECT_EQ(bestRotation(make(), 0), Rotation::None);
  Bvh crossed = make();
  applyRotation(crossed, 0, Rotation::LeftLeftWithRightRight);  // children {6, 4} and {5, 3}
  const Rotation fix = bestRotation(crossed, 0);
  EXPECT_NE(fix, Rotation::None);
  const double before = areas(crossed, 1, 2);
  applyRotation(crossed, 0, fix);
  EXPECT_LT(areas(crossed, 1, 2), before);
  // A leaf child has no grandchildren to swap.
  Bvh small;
  small.nodes.resize(3);
  small.primIndices = {0, 1};
  small.nodes[0].left = 1, small.nodes[0].right = 2;
  small.nodes[1].count = small.nodes[2].count = 1;
  small.nodes[2].first = 1;
  EXPECT_THROW(applyRotation(small, 0, Rotation::LeftWithRightLeft), std::invalid_argument);
  EXPECT_EQ(bestRotation(small, 0), Rotation::None);
}

// ---- rebuild policies -------------------------------------------------------------------------------

std::vector<uint32_t> rebuiltFrames(const std::vector<UpdateRecord>& records) {
  std::vector<uint32_t> out;
  for (const UpdateRecord& r : records)
    if (r.rebuilt) out.push_back(r.frame);
  return out;
}

TEST(RebuildPolicies, EveryKFramesRebuildsOnMultiplesOfK) {
  const Clip clip = waveClip(16, 16, 11);
  const std::vector<FrameTriangles> frames = clip.all();
  for (uint32_t k : {1u, 3u, 4u, 20u}) {
    const auto strategy = makeUpdateStrategy("refit+rebuild:" + std::to_string(k), {});
    const std::vector<UpdateRecord> records = runClip(*strategy, frames);
    std::vector<uint32_t> expected;
    for (uint32_t f = 0; f < frames.size(); f += k) expected.push_back(f);
    EXPECT_EQ(rebuiltFrames(records), expected) << "K = " << k;
  }
  EXPECT_EQ(rebuiltFrames(runClip(*makeUpdateStrategy("rebuild", {}), frames)).size(), frames.size());
  EXPECT_EQ(rebuiltFrames(runClip(*makeUpdateStrategy("refit", {}), frames)), std::vector<uint32_t>{0});
  EXPECT_EQ(rebuiltFrames(runClip(*makeUpdateStrategy("refit+rotate", {}), frames)), std::vector<uint32_t>{0});
}

// A clip whose frames are known to cross the threshold: frames 0-3 the same mesh, frames 4-5 the same
// triangles shuffled in space (triangle i takes the place of triangle perm[i]: a refit tree built on
// frame 0 then bounds far-apart triangles together), frames 6-7 the first mesh again. sah>R rebuilds
// at 0, at 4 (the shuffle), not at 5 (its tree fits frame 5 as it fit frame 4: ratio 1), at 6 (the tree
// of the shuffle over the first mesh), not at 7.
TEST(RebuildPolicies, SahTriggerRebuildsExactlyWhenTheRatioIsCrossed) {
  const Clip base = waveClip(20, 20, 1);
  std::vector<uint32_t> perm(base.v0[0].size());
  for (uint32_t i = 0; i < perm.size(); ++i) perm[i] = i;
  std::shuffle(perm.begin(), perm.end(), std::mt19937(11));
  std::vector<glm::vec3> s0(perm.size()), s1(perm.size()), s2(perm.size());
  for (size_t i = 0; i < perm.size(); ++i) {
    // Moved rigidly to where triangle perm[i] is: its own shape, someone else's place.
    const glm::vec3 shift = base.v0[0][perm[i]] - base.v0[0][i];
    s0[i] = base.v0[0][i] + shift, s1[i] = base.v1[0][i] + shift, s2[i] = base.v2[0][i] + shift;
  }
  Clip clip;
  for (int f = 0; f < 4; ++f) clip.add(base.v0[0], base.v1[0], base.v2[0]);
  for (int f = 0; f < 2; ++f) clip.add(s0, s1, s2);
  for (int f = 0; f < 2; ++f) clip.add(base.v0[0], base.v1[0], base.v2[0]);
  const std::vector<FrameTriangles> frames = clip.all();
  const std::vector<UpdateRecord> records = runClip(*makeUpdateStrategy("refit+rebuild:sah>1.5", {}), frames);
  EXPECT_EQ(rebuiltFrames(records), (std::vector<uint32_t>{0, 4, 6}));

  // The threshold itself, over frames 0-5: the ratio of frame 4's refit tree to frame 0's, measured
  // with a plain refit; R just above it keeps the refit tree all along, R just below it rebuilds at 4
  // (1e-9 relative: far above the rounding of the strategy's R x SAH product, 2^-53, and far below
  // the distance to any other ratio of the clip).
  const std::vector<FrameTriangles> first6(frames.begin(), frames.begin() + 6);
  const std::vector<UpdateRecord> refit = runClip(*makeUpdateStrategy("refit", {}), frames);
  const double ratio = refit[4].sahCost / refit[0].sahCost;
  ASSERT_GT(ratio, 1.5);
  char above[64], below[64];
  std::snprintf(above, sizeof above, "refit+rebuild:sah>%.17g", ratio * (1.0 + 1e-9));
  std::snprintf(below, sizeof below, "refit+rebuild:sah>%.17g", ratio * (1.0 - 1e-9));
  EXPECT_EQ(rebuiltFrames(runClip(*makeUpdateStrategy(above, {}), first6)), (std::vector<uint32_t>{0}));
  EXPECT_EQ(rebuiltFrames(runClip(*makeUpdateStrategy(below, {}), first6)), (std::vector<uint32_t>{0, 4}));
}

// On an exploding mesh a refit tree degrades many times over, while sah>R holds every frame it keeps
// without a rebuild within R x the last rebuild's SAH, by construction.
TEST(RebuildPolicies, SahTriggerBoundsTheSahOfAnExplodingMesh) {
  const Clip clip = explodeClip(40, 25, 16, 0.25f);  // 2,000 triangles
  const std::vector<FrameTriangles> frames = clip.all();
  const std::vector<UpdateRecord> refit = runClip(*makeUpdateStrategy("refit", {}), frames);
  const std::vector<UpdateRecord> rebuild = runClip(*makeUpdateStrategy("rebuild", {}), frames);
  EXPECT_GT(refit.back().sahCost, 3.0 * refit.front().sahCost) << "the clip does not explode enough to test";
  EXPECT_GT(refit.back().sahCost, 3.0 * rebuild.back().sahCost);
  for (double ratio : {1.2, 1.5, 2.0}) {
    SCOPED_TRACE("R = " + std::to_string(ratio));
    char spec[64];
    std::snprintf(spec, sizeof spec, "refit+rebuild:sah>%g", ratio);
    const std::vector<UpdateRecord> sah = runClip(*makeUpdateStrategy(spec, {}), frames);
    double lastRebuild = 0.0;
    size_t rebuilds = 0;
    for (const UpdateRecord& r : sah) {
      if (r.rebuilt) {
        lastRebuild = r.sahCost, ++rebuilds;
        EXPECT_EQ(r.sahCost, rebuild[r.frame].sahCost) << "a rebuild is the builder's tree, frame " << r.frame;
      } else {
        EXPECT_LE(r.sahCost, ratio * lastRebuild) << "frame " << r.frame;
      }
    }
    EXPECT_GT(rebuilds, 1u) << "no rebuild after frame 0: the bound was never tested";
    EXPECT_LT(rebuilds, sah.size()) << "a rebuild every frame: the bound was never tested";
  }
  // Rotations recover part of what the refit loses, never more SAH than the refit.
  const std::vector<UpdateRecord> rotate = runClip(*makeUpdateStrategy("refit+rotate", {}), frames);
  size_t rotations = 0;
  for (size_t f = 0; f < frames.size(); ++f) rotations += rotate[f].rotations;
  EXPECT_GT(rotations, 0u);
  EXPECT_LT(rotate.back().sahCost, refit.back().sahCost);
}

// ---- threads ----------------------------------------------------------------------------------------

// The builders run their top levels and subtrees on several threads (above 4,096 primitives), and EPO
// shares its nodes among threads; refit and rotations run on one. The records (all but the times; the
// tree hash filled in by the frame callback, as a caller above the layout library does) and the trees
// of every frame are the same for 1 thread and for 4.
TEST(Updates, SameResultsForAnyThreadCount) {
  const Clip clip = explodeClip(80, 40, 5, 0.1f);  // 6,400 triangles: above the builders' parallel cut
  const std::vector<FrameTriangles> frames = clip.all();
  for (const std::string spec : {"rebuild", "refit+rebuild:2", "refit+rebuild:sah>1.1", "refit+rotate"}) {
    SCOPED_TRACE(spec);
    std::vector<std::vector<UpdateRecord>> records;
    std::vector<std::vector<Bvh>> trees;
    for (unsigned threads : {1u, 4u}) {
      UpdateOptions options;
      options.build.threads = threads;
      ClipOptions clipOptions;
      clipOptions.epo = true;
      clipOptions.epoThreads = threads;
      trees.emplace_back();
      records.push_back(runClip(*makeUpdateStrategy(spec, options), frames, clipOptions,
                                [&](uint32_t f, const Bvh& tree, UpdateRecord& record) {
                                  trees.back().push_back(tree);
                                  record.treeHash = treeHash(tree, frames[f]);  // as trace/render would
                                }));
    }
    for (size_t f = 0; f < frames.size(); ++f) {
      EXPECT_TRUE(identical(trees[0][f], trees[1][f])) << "frame " << f;
      EXPECT_EQ(records[0][f].rebuilt, records[1][f].rebuilt);
      EXPECT_EQ(records[0][f].sahCost, records[1][f].sahCost);
      ASSERT_TRUE(records[0][f].epo && records[1][f].epo);
      EXPECT_EQ(*records[0][f].epo, *records[1][f].epo);
      EXPECT_EQ(records[0][f].rotations, records[1][f].rotations);
      EXPECT_EQ(records[0][f].treeHash, records[1][f].treeHash);
      EXPECT_EQ(records[0][f].treeHash.size(), 16u);
    }
  }
}

// ---- bad input ----------------------------------------------------------------------------------------

TEST(Updates, BadStrategyStringsAreRefusedNamingTheValidOnes) {
  for (const std::string bad : {"refit+rebuild:0", "refit+rebuild:sah>0.5", "bogus", "", "REFIT", "refit+rebuild:",
                                "refit+rebuild:-3", "refit+rebuild:3x", "refit+rebuild:1.5", "refit+rebuild:sah>",
                                "refit+rebuild:sah>nan", "refit+rebuild:sah>inf", "refit+rebuild:sah> 2",
                                "refit+rebuild:99999999999", "rebuild:lbvh", "refit+rotate "}) {
    SCOPED_TRACE("'" + bad + "'");
    try {
      parseUpdateSpec(bad);
      ADD_FAILURE() << "accepted";
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("'" + bad + "'"), std::string::npos) << what;
      for (const UpdateStrategyInfo& info : updateStrategies())
        EXPECT_NE(what.find(info.name), std::string::npos) << what;
    }
  }
  // The message is copied out of the exception while it is alive (e.what() dies with it).
  EXPECT_NE([]() -> std::string {
              try {
                parseUpdateSpec("refit+rebuild:0");
              } catch (const std::invalid_argument& e) {
                return e.what();
              }
              return {};
            }().find(">= 1"),
            std::string::npos);
  // And the good ones, with their numbers.
  EXPECT_EQ(parseUpdateSpec("refit+rebuild:8").every, 8u);
  EXPECT_EQ(parseUpdateSpec("refit+rebuild:8").name, "refit+rebuild:K");
  EXPECT_EQ(parseUpdateSpec("refit+rebuild:sah>1.5").sahRatio, 1.5);
  EXPECT_EQ(parseUpdateSpec("refit+rebuild:sah>1").name, "refit+rebuild:sah>R");
  for (const std::string good : {"rebuild", "refit", "refit+rotate"}) EXPECT_EQ(parseUpdateSpec(good).name, good);
  // An unknown builder is refused naming the builders.
  UpdateOptions options;
  options.builder = "nope";
  try {
    makeUpdateStrategy("refit", options);
    ADD_FAILURE() << "accepted builder 'nope'";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("sah-binned"), std::string::npos) << e.what();
  }
}

TEST(Updates, BadFramesAreRefused) {
  const Clip clip = waveClip(8, 8, 2);
  Clip fewer = waveClip(8, 7, 1);
  for (const std::string spec : {"rebuild", "refit", "refit+rotate", "refit+rebuild:2", "refit+rebuild:sah>1.5"}) {
    SCOPED_TRACE(spec);
    auto strategy = makeUpdateStrategy(spec, {});
    strategy->update(clip.frame(0));
    EXPECT_THROW(strategy->update(fewer.frame(0)), std::invalid_argument);
    std::vector<glm::vec3> v0 = clip.v0[1];
    v0[17].y = std::nanf("");
    EXPECT_THROW(strategy->update({v0, clip.v1[1], clip.v2[1]}), InputError);
  }
  const std::vector<FrameTriangles> mixed = {clip.frame(0), fewer.frame(0)};
  EXPECT_THROW(runClip(*makeUpdateStrategy("refit", {}), mixed), std::invalid_argument);
}

}  // namespace
}  // namespace bvhlab
