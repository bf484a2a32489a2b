// The texture layout (layout/layout.hpp): gatherTriangles and packBvh's invariants, checked against
// independent recursive definitions over the builder's Bvh, for every registered builder.
#include <algorithm>
#include <bit>
#include <cmath>
#include <functional>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <glm/gtc/constants.hpp>
#include <gtest/gtest.h>

#include "builders/builder.hpp"
#include "datasets/random_draws.hpp"
#include "layout/layout.hpp"

namespace bvhlab {
namespace {

// ---- generated meshes ---------------------------------------------------------------------------

Mesh sphereMesh(int stacks, int slices) {
  Mesh m;
  m.name = "sphere";
  for (int i = 0; i <= stacks; ++i)
    for (int j = 0; j <= slices; ++j) {
      const float theta = glm::pi<float>() * float(i) / float(stacks);
      const float phi = 2.0f * glm::pi<float>() * float(j) / float(slices);
      const glm::vec3 p(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi));
      m.positions.push_back(p);
      m.normals.push_back(p);
      m.uvs.push_back({float(j) / float(slices), float(i) / float(stacks)});
    }
  for (int i = 0; i < stacks; ++i)
    for (int j = 0; j < slices; ++j) {
      const uint32_t a = uint32_t(i * (slices + 1) + j), b = a + uint32_t(slices + 1);
      m.triangles.push_back({a, b, a + 1});
      m.triangles.push_back({a + 1, b, b + 1});
    }
  return m;
}

Mesh randomSoupMesh(size_t count, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f), edge(-0.1f, 0.1f);
  Mesh m;
  m.name = "random-soup";
  for (size_t i = 0; i < count; ++i) {
    const glm::vec3 c = draw3<glm::vec3>(unit, rng);
    for (int k = 0; k < 3; ++k) m.positions.push_back(c + draw3<glm::vec3>(edge, rng));
    m.triangles.push_back({uint32_t(3 * i), uint32_t(3 * i + 1), uint32_t(3 * i + 2)});
  }
  return m;
}

Scene makeScene(std::vector<Mesh> meshes) {
  Scene s;
  s.materials.resize(2);
  for (size_t i = 0; i < meshes.size(); ++i) meshes[i].material = int(i % 2);
  s.meshes = std::move(meshes);
  return s;
}

struct Built {
  TriangleSoup soup;
  Bvh bvh;
  PackedBvh packed;
};

Built buildAndPack(const Scene& scene, const std::string& builder, uint32_t leafSize) {
  Built b;
  b.soup = gatherTriangles(scene);
  const std::vector<Aabb> boxes = triangleBoxes(b.soup);
  const std::vector<glm::vec3> centroids = triangleCentroids(b.soup);
  BuildOptions options;
  options.maxLeafSize = leafSize;
  b.bvh = buildBvh(builder, BuildInput{boxes, centroids}, options);
  b.packed = packBvh(b.bvh, b.soup);
  return b;
}

// Component-wise bit casts: GLM's vector versions break strict aliasing and GCC -O2 miscompiles them.
bool sameBits(const glm::vec3& a, const glm::vec3& b) {
  for (int k = 0; k < 3; ++k)
    if (std::bit_cast<uint32_t>(a[k]) != std::bit_cast<uint32_t>(b[k])) return false;
  return true;
}
glm::vec3 floats3(const glm::uvec4& t) {
  return {std::bit_cast<float>(t.x), std::bit_cast<float>(t.y), std::bit_cast<float>(t.z)};
}
glm::vec2 floats2(uint32_t x, uint32_t y) { return {std::bit_cast<float>(x), std::bit_cast<float>(y)}; }

// ---- the invariants, from independent definitions -----------------------------------------------

// Walks the Bvh recursively (the definition of depth-first order) alongside the packed stream and
// checks every node: same box bits, same kind and count, child A adjacent, A = second child's stream
// index, escape = what follows the subtree in the walk, leaf triangles in walk order.
struct WalkCheck {
  const Bvh& bvh;
  const PackedBvh& packed;
  uint32_t nextStream = 0;    // stream index the walk expects next
  uint32_t nextTriangle = 0;  // TRIANGLE stream index the next leaf must start at
  uint32_t maxDepth = 0;

  void visit(uint32_t original, uint32_t escape, uint32_t depth) {
    const uint32_t i = nextStream++;
    maxDepth = std::max(maxDepth, depth);
    const BvhNode& node = bvh.nodes[original];
    const NodeRecord r = unpackNode(packed, i);
    ASSERT_TRUE(sameBits(r.bmin, node.bounds.min) && sameBits(r.bmax, node.bounds.max)) << "node " << i;
    ASSERT_EQ(r.count, node.count) << "node " << i;
    ASSERT_EQ(r.escape, escape) << "node " << i;
    if (node.isLeaf()) {
      ASSERT_EQ(r.a, nextTriangle) << "leaf " << i << " must continue the triangle stream";
      for (uint32_t k = 0; k < node.count; ++k)
        ASSERT_EQ(packed.triangles[kTriangleTexels * (r.a + k)].w, bvh.primIndices[node.first + k]);
      nextTriangle += node.count;
      return;
    }
    // The second child follows the whole first subtree, so its index is only known after the walk
    // of the first child; the first child is always i + 1.
    const uint32_t secondChildIndex = r.a;
    ASSERT_EQ(nextStream, i + 1);
    visit(node.left, secondChildIndex, depth + 1);
    ASSERT_EQ(nextStream, secondChildIndex) << "node " << i << ": A must name the node after the first subtree";
    visit(node.right, escape, depth + 1);
  }
};

void checkPacking(const Built& b) {
  const PackedBvh& p = b.packed;
  ASSERT_EQ(p.nodes.size() % kNodeTexels, 0u);
  const uint32_t nodeCount = uint32_t(p.nodes.size() / kNodeTexels);
  WalkCheck walk{b.bvh, p};
  walk.visit(0, kEscapeEnd, 1);
  ASSERT_EQ(walk.nextStream, nodeCount) << "every stream node is reached by the walk";
  EXPECT_EQ(p.depth, walk.maxDepth);
  EXPECT_EQ(p.depth, computeStats(b.bvh, CostModel{}).depth);

  // One triangle record per leaf reference: every triangle exactly once, or at least once for a
  // builder that splits primitives (sbvh references a straddling triangle from several leaves).
  const size_t n = b.soup.size();
  size_t references = 0;
  for (const BvhNode& node : b.bvh.nodes) references += node.count;
  ASSERT_EQ(p.triangles.size(), kTriangleTexels * references);
  ASSERT_EQ(p.attributes.size(), kAttributeTexels * references);
  std::vector<int> seen(n, 0);
  for (size_t j = 0; j < references; ++j) {
    const uint32_t id = p.triangles[kTriangleTexels * j].w;
    ASSERT_LT(id, n);
    ++seen[id];
    // Vertex bits unmodified, material and mesh carried, attributes in the same order.
    const glm::uvec4 t0 = p.triangles[3 * j], t1 = p.triangles[3 * j + 1], t2 = p.triangles[3 * j + 2];
    EXPECT_TRUE(sameBits(floats3(t0), b.soup.v0[id]));
    EXPECT_TRUE(sameBits(floats3(t1), b.soup.v1[id]));
    EXPECT_TRUE(sameBits(floats3(t2), b.soup.v2[id]));
    EXPECT_EQ(t1.w, b.soup.material[id]);
    EXPECT_EQ(t2.w, b.soup.mesh[id]);
    const glm::uvec4 a0 = p.attributes[4 * j], a1 = p.attributes[4 * j + 1], a2 = p.attributes[4 * j + 2],
                     a3 = p.attributes[4 * j + 3];
    EXPECT_TRUE(sameBits(floats3(a0), b.soup.n0[id]));
    EXPECT_TRUE(sameBits(floats3(a1), b.soup.n1[id]));
    EXPECT_TRUE(sameBits(floats3(a2), b.soup.n2[id]));
    EXPECT_EQ(floats2(a0.w, a1.w), b.soup.uv0[id]);
    EXPECT_EQ(floats2(a2.w, a3.x), b.soup.uv1[id]);
    EXPECT_EQ(floats2(a3.y, a3.z), b.soup.uv2[id]);
  }
  const bool splits = references != n;
  EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [splits](int c) { return splits ? c >= 1 : c == 1; }));
}

// A stackless walk over the escape links, where `hits(node)` decides each box test, visits the
// same nodes in the same order as a recursive depth-first walk that descends only into hit nodes.
void checkEscapeWalk(const Built& b, uint32_t seed) {
  const uint32_t nodeCount = uint32_t(b.packed.nodes.size() / kNodeTexels);
  auto hits = [seed](uint32_t stream) { return ((stream * 2654435761u) ^ seed) % 5u != 0u; };

  std::vector<uint32_t> recursive;
  std::function<void(uint32_t)> walk = [&](uint32_t i) {
    recursive.push_back(i);
    const NodeRecord r = unpackNode(b.packed, i);
    if (!hits(i) || r.isLeaf()) return;
    walk(i + 1);
    walk(r.a);
  };
  walk(0);

  std::vector<uint32_t> stackless;
  for (uint32_t i = 0; i != kEscapeEnd;) {
    ASSERT_LT(i, nodeCount);
    stackless.push_back(i);
    const NodeRecord r = unpackNode(b.packed, i);
    i = (hits(i) && !r.isLeaf()) ? i + 1 : r.escape;
  }
  EXPECT_EQ(stackless, recursive);
}

// ---- tests --------------------------------------------------------------------------------------

TEST(Layout, HandMadeTreeIsReorderedDepthFirst) {
  // Original numbering deliberately not depth-first: root 0 -> (3, 1); 3 -> (2, 4); leaves 1, 2, 4.
  Scene scene = makeScene({randomSoupMesh(4, 7)});
  const TriangleSoup soup = gatherTriangles(scene);
  const std::vector<Aabb> boxes = triangleBoxes(soup);
  Bvh bvh;
  bvh.primIndices = {3, 0, 2, 1};
  bvh.nodes.resize(5);
  auto leaf = [&](uint32_t n, uint32_t first, uint32_t count) {
    bvh.nodes[n].first = first;
    bvh.nodes[n].count = count;
    for (uint32_t k = first; k < first + count; ++k) bvh.nodes[n].bounds.grow(boxes[bvh.primIndices[k]]);
  };
  leaf(1, 2, 2);
  leaf(2, 0, 1);
  leaf(4, 1, 1);
  bvh.nodes[3].left = 2, bvh.nodes[3].right = 4;
  bvh.nodes[3].bounds.grow(bvh.nodes[2].bounds), bvh.nodes[3].bounds.grow(bvh.nodes[4].bounds);
  bvh.nodes[0].left = 3, bvh.nodes[0].right = 1;
  bvh.nodes[0].bounds.grow(bvh.nodes[3].bounds), bvh.nodes[0].bounds.grow(bvh.nodes[1].bounds);

  const PackedBvh p = packBvh(bvh, soup);
  // Walk order 0, 3, 2, 4, 1 -> stream 0..4.
  ASSERT_EQ(p.nodes.size(), 10u);
  EXPECT_EQ(p.depth, 3u);
  const NodeRecord r0 = unpackNode(p, 0), r1 = unpackNode(p, 1), r2 = unpackNode(p, 2), r3 = unpackNode(p, 3),
                   r4 = unpackNode(p, 4);
  EXPECT_EQ(r0.count, 0u);
  EXPECT_EQ(r0.a, 4u);
  EXPECT_EQ(r0.escape, kEscapeEnd);
  EXPECT_EQ(r1.count, 0u);
  EXPECT_EQ(r1.a, 3u);
  EXPECT_EQ(r1.escape, 4u);
  EXPECT_EQ(r2.count, 1u);
  EXPECT_EQ(r2.a, 0u);
  EXPECT_EQ(r2.escape, 3u);
  EXPECT_EQ(r3.count, 1u);
  EXPECT_EQ(r3.a, 1u);
  EXPECT_EQ(r3.escape, 4u);
  EXPECT_EQ(r4.count, 2u);
  EXPECT_EQ(r4.a, 2u);
  EXPECT_EQ(r4.escape, kEscapeEnd);
  // Triangles in leaf order: leaf 2 (prim 3), leaf 4 (prim 0), leaf 1 (prims 2, 1).
  ASSERT_EQ(p.triangles.size(), 12u);
  EXPECT_EQ(p.triangles[0].w, 3u);
  EXPECT_EQ(p.triangles[3].w, 0u);
  EXPECT_EQ(p.triangles[6].w, 2u);
  EXPECT_EQ(p.triangles[9].w, 1u);
  EXPECT_TRUE(sameBits(r1.bmin, bvh.nodes[3].bounds.min));
  EXPECT_TRUE(sameBits(r4.bmax, bvh.nodes[1].bounds.max));
}

TEST(Layout, CountIsSplitOverBothNibbles) {
  // A leaf of 255 = 0xFF triangles needs both nibbles; 16 = 0x10 only the high one.
  for (uint32_t count : {1u, 15u, 16u, 17u, 200u, 255u}) {
    Scene scene = makeScene({randomSoupMesh(count, count)});
    const TriangleSoup soup = gatherTriangles(scene);
    Bvh bvh;
    bvh.nodes.resize(1);
    bvh.nodes[0].count = count;
    for (uint32_t i = 0; i < count; ++i) bvh.primIndices.push_back(i);
    for (const Aabb& box : triangleBoxes(soup)) bvh.nodes[0].bounds.grow(box);
    const PackedBvh p = packBvh(bvh, soup);
    const NodeRecord r = unpackNode(p, 0);
    EXPECT_EQ(r.count, count);
    EXPECT_EQ(r.a, 0u);
    EXPECT_EQ(r.escape, kEscapeEnd);
    EXPECT_EQ(p.depth, 1u);
  }
}

TEST(Layout, EveryBuilderPacksToTheLayout) {
  ASSERT_FALSE(builders().empty());
  const std::vector<Scene> scenes = {makeScene({sphereMesh(12, 24)}),
                                     makeScene({randomSoupMesh(700, 3), sphereMesh(5, 9)})};
  for (const BuilderInfo& builder : builders())
    for (uint32_t leafSize : {1u, 4u, 16u})
      for (size_t s = 0; s < scenes.size(); ++s) {
        SCOPED_TRACE(builder.name + " leaf " + std::to_string(leafSize) + " scene " + std::to_string(s));
        const Built b = buildAndPack(scenes[s], builder.name, leafSize);
        checkPacking(b);
        checkEscapeWalk(b, 1);
        checkEscapeWalk(b, 12345);
      }
}

TEST(Layout, PackingIsDeterministic) {
  const Scene scene = makeScene({randomSoupMesh(500, 9)});
  const Built a = buildAndPack(scene, builders().front().name, 4);
  const Bvh copy = a.bvh;
  const PackedBvh b = packBvh(copy, a.soup);
  EXPECT_EQ(a.packed.nodes, b.nodes);
  EXPECT_EQ(a.packed.triangles, b.triangles);
  EXPECT_EQ(a.packed.attributes, b.attributes);
  EXPECT_EQ(a.packed.depth, b.depth);
  EXPECT_EQ(a.packed.bytes(), 16 * (b.nodes.size() + b.triangles.size() + b.attributes.size()));
}

// Expects a std::runtime_error whose message contains `needle`.
template <class F>
void expectError(F&& f, const std::string& needle) {
  try {
    f();
    ADD_FAILURE() << "no error; expected one mentioning '" << needle << "'";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

TEST(Layout, LimitsAndMalformedTreesAreClearErrors) {
  const Scene scene = makeScene({randomSoupMesh(300, 5)});
  const TriangleSoup soup = gatherTriangles(scene);
  Bvh leaf;
  leaf.nodes.resize(1);
  leaf.nodes[0].count = 256;
  for (uint32_t i = 0; i < 256; ++i) leaf.primIndices.push_back(i);
  expectError([&] { packBvh(leaf, soup); }, "node stream");

  leaf.nodes[0].count = 4;
  leaf.primIndices = {0, 1, 2, 300};
  expectError([&] { packBvh(leaf, soup); }, "primitive 300");

  Bvh cycle;
  cycle.nodes.resize(2);
  cycle.nodes[0].left = 1, cycle.nodes[0].right = 0;
  cycle.nodes[1].count = 1;
  cycle.primIndices = {0};
  expectError([&] { packBvh(cycle, soup); }, "reached twice");

  Bvh dangling = cycle;
  dangling.nodes[0].right = 7;
  expectError([&] { packBvh(dangling, soup); }, "child 7");

  expectError([&] { packBvh(Bvh{}, soup); }, "no nodes");

  const Built b = buildAndPack(scene, builders().front().name, 4);
  checkStreamLimits(b.packed, "tbo", b.packed.attributes.size());  // exactly at the limit: fine
  expectError([&] { checkStreamLimits(b.packed, "tex2d", b.packed.triangles.size()); }, "attribute stream");
  expectError([&] { checkStreamLimits(b.packed, "tex2d", b.packed.nodes.size() - 1); }, "node stream");
  EXPECT_THROW(unpackNode(b.packed, uint32_t(b.packed.nodes.size() / 2)), std::out_of_range);
}

TEST(Soup, GathersMeshesWithAttributesAndDefaults) {
  Mesh withAttributes;
  withAttributes.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  withAttributes.normals = {{0, 0, 2}, {0, 0, 0}, {0, 3, 4}, {0, 0, 1}};  // unnormalised, one zero
  withAttributes.uvs = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
  withAttributes.triangles = {{0, 1, 2}, {1, 3, 2}};
  withAttributes.material = 1;
  Mesh bare;
  bare.positions = {{0, 0, 5}, {0, 2, 5}, {2, 0, 5}};  // clockwise seen from +Z: normal -Z
  bare.triangles = {{0, 1, 2}};
  Scene scene;
  scene.materials.resize(2);
  scene.meshes = {withAttributes, bare};

  const TriangleSoup soup = gatherTriangles(scene);
  ASSERT_EQ(soup.size(), 3u);
  EXPECT_EQ(soup.n0[0], glm::vec3(0, 0, 1));
  EXPECT_EQ(soup.n1[0], glm::vec3(0, 0, 1));  // zero normal -> geometric normal
  EXPECT_NEAR(glm::length(soup.n2[0] - glm::vec3(0, 0.6f, 0.8f)), 0.0f, 1e-6f);
  EXPECT_EQ(soup.uv1[1], glm::vec2(1, 1));
  EXPECT_EQ(soup.material[0], 1u);
  EXPECT_EQ(soup.mesh[2], 1u);
  EXPECT_EQ(soup.v1[2], glm::vec3(0, 2, 5));
  for (const glm::vec3& n : {soup.n0[2], soup.n1[2], soup.n2[2]}) EXPECT_EQ(n, glm::vec3(0, 0, -1));
  EXPECT_EQ(soup.uv2[2], glm::vec2(0, 0));

  const std::vector<Aabb> boxes = triangleBoxes(soup);
  const std::vector<glm::vec3> centroids = triangleCentroids(soup);
  EXPECT_EQ(boxes[2].min, glm::vec3(0, 0, 5));
  EXPECT_EQ(boxes[2].max, glm::vec3(2, 2, 5));
  for (size_t i = 0; i < soup.size(); ++i) EXPECT_TRUE(boxes[i].contains(Aabb{centroids[i], centroids[i]}));
}

TEST(Soup, BadMeshesAreInputErrors) {
  auto gather = [](Mesh m) {
    Scene s;
    s.materials.resize(1);
    s.meshes = {std::move(m)};
    return gatherTriangles(s);
  };
  Mesh good;
  good.name = "tri.off";
  good.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  good.triangles = {{0, 1, 2}};
  EXPECT_EQ(gather(good).size(), 1u);

  Mesh badIndex = good;
  badIndex.triangles = {{0, 1, 3}};
  EXPECT_THROW(gather(badIndex), InputError);
  Mesh badNormals = good;
  badNormals.normals = {{0, 0, 1}};
  EXPECT_THROW(gather(badNormals), InputError);
  Mesh badUvs = good;
  badUvs.uvs = {{0, 0}, {1, 1}};
  EXPECT_THROW(gather(badUvs), InputError);
  Mesh nan = good;
  nan.positions[1].y = std::nanf("");
  EXPECT_THROW(gather(nan), InputError);
  Mesh badMaterial = good;
  badMaterial.material = 3;
  try {
    gather(badMaterial);
    ADD_FAILURE() << "no error for material 3";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("tri.off"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace bvhlab
