// The traversal kernels (traversal/kernel_*.glsl through their C++ mirrors): every builder x every
// kernel against brute force over all triangles, the counters against independent recursive
// definitions, the stack bounds, the ray-box / ray-triangle tests, and the GLSL through glslang.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <glad/gl.h>
#include <glm/gtc/constants.hpp>
#include <gtest/gtest.h>
#include <unistd.h>

#include "gl_compute.hpp"
#include "builders/builder.hpp"
#include "datasets/mesh_io.hpp"
#include "layout/layout.hpp"
#include "render/gl_context.hpp"
#include "shaders/assemble.hpp"
#include "traversal/kernels.hpp"
#include "traversal/ray_box.hpp"
#include "traversal/ray_triangle.hpp"

namespace bvhlab {
namespace {

using glsl::Counters;
using test::compileCompute;
using glsl::MeshHit;
using glsl::Ray;

// ---- meshes -------------------------------------------------------------------------------------

Mesh sphereMesh(int stacks, int slices, float radius) {
  Mesh m;
  m.name = "sphere";
  for (int i = 0; i <= stacks; ++i)
    for (int j = 0; j <= slices; ++j) {
      const float theta = glm::pi<float>() * float(i) / float(stacks);
      const float phi = 2.0f * glm::pi<float>() * float(j) / float(slices);
      m.positions.push_back(radius *
                            glm::vec3(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi)));
    }
  for (int i = 0; i < stacks; ++i)
    for (int j = 0; j < slices; ++j) {
      const uint32_t a = uint32_t(i * (slices + 1) + j), b = a + uint32_t(slices + 1);
      if (i > 0) m.triangles.push_back({a, b, a + 1});               // no zero-area pole triangles
      if (i < stacks - 1) m.triangles.push_back({a + 1, b, b + 1});
    }
  return m;
}

Mesh randomSoupMesh(size_t count, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f), edge(-0.15f, 0.15f);
  Mesh m;
  m.name = "random-soup";
  for (size_t i = 0; i < count; ++i) {
    const glm::vec3 c(unit(rng), unit(rng), unit(rng));
    for (int k = 0; k < 3; ++k) m.positions.push_back(c + glm::vec3(edge(rng), edge(rng), edge(rng)));
    m.triangles.push_back({uint32_t(3 * i), uint32_t(3 * i + 1), uint32_t(3 * i + 2)});
  }
  return m;
}

// The plane y = 0 over [-1,1]^2 as n x n quads: coplanar triangles sharing edges and vertices, so
// rays through grid vertices meet several triangles at the same t (ties), and every box is flat.
Mesh gridMesh(int n) {
  Mesh m;
  m.name = "grid";
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) m.positions.push_back({-1.0f + 2.0f * float(j) / float(n), 0.0f, -1.0f + 2.0f * float(i) / float(n)});
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const uint32_t a = uint32_t(i * (n + 1) + j), b = a + uint32_t(n + 1);
      m.triangles.push_back({a, b, a + 1});
      m.triangles.push_back({a + 1, b, b + 1});
    }
  return m;
}

TriangleSoup soupOf(std::vector<Mesh> meshes) {
  Scene s;
  s.materials.resize(1);
  s.meshes = std::move(meshes);
  return gatherTriangles(s);
}

// ---- trees: the registered builders plus two test-local shapes ---------------------------------

Aabb boundsOf(const std::vector<Aabb>& boxes, const std::vector<uint32_t>& prims, size_t begin, size_t end) {
  Aabb b;
  for (size_t i = begin; i < end; ++i) b.grow(boxes[prims[i]]);
  return b;
}

// The deepest possible tree: each inner node's second child is a leaf holding the primitive with the
// smallest centroid z, its first child the chain of the rest. Depth = primitive count.
Bvh chainBvh(const std::vector<Aabb>& boxes) {
  Bvh bvh;
  const size_t n = boxes.size();
  bvh.primIndices.resize(n);
  for (uint32_t i = 0; i < n; ++i) bvh.primIndices[i] = i;
  std::stable_sort(bvh.primIndices.begin(), bvh.primIndices.end(),
                   [&](uint32_t a, uint32_t b) { return boxes[a].center().z < boxes[b].center().z; });
  // Chain node k covers primIndices[k, n); its leaf child holds primIndices[k].
  for (size_t k = 0; k + 1 < n; ++k) {
    BvhNode inner;
    inner.bounds = boundsOf(boxes, bvh.primIndices, k, n);
    const uint32_t self = uint32_t(bvh.nodes.size());
    inner.right = self + 1;
    inner.left = self + 2;  // the next chain node, or the final leaf
    bvh.nodes.push_back(inner);
    BvhNode leaf;
    leaf.bounds = boxes[bvh.primIndices[k]];
    leaf.first = uint32_t(k);
    leaf.count = 1;
    bvh.nodes.push_back(leaf);
  }
  BvhNode last;
  last.bounds = boxes[bvh.primIndices[n - 1]];
  last.first = uint32_t(n - 1);
  last.count = 1;
  bvh.nodes.push_back(last);
  return bvh;
}

// Random partitions of a shuffled primitive list, random leaf sizes 1..8: boxes overlap everywhere,
// the opposite of what a real builder makes, and a good way to catch ordering assumptions.
Bvh randomSplitBvh(const std::vector<Aabb>& boxes, uint32_t seed) {
  std::mt19937 rng(seed);
  Bvh bvh;
  bvh.primIndices.resize(boxes.size());
  for (uint32_t i = 0; i < boxes.size(); ++i) bvh.primIndices[i] = i;
  std::shuffle(bvh.primIndices.begin(), bvh.primIndices.end(), rng);
  std::function<uint32_t(size_t, size_t)> build = [&](size_t begin, size_t end) -> uint32_t {
    const uint32_t self = uint32_t(bvh.nodes.size());
    bvh.nodes.emplace_back();
    bvh.nodes[self].bounds = boundsOf(boxes, bvh.primIndices, begin, end);
    const size_t count = end - begin;
    if (count <= std::uniform_int_distribution<size_t>(1, 8)(rng)) {
      bvh.nodes[self].first = uint32_t(begin);
      bvh.nodes[self].count = uint32_t(count);
      return self;
    }
    const size_t mid = begin + std::uniform_int_distribution<size_t>(1, count - 1)(rng);
    const uint32_t left = build(begin, mid), right = build(mid, end);
    bvh.nodes[self].left = left;
    bvh.nodes[self].right = right;
    return self;
  };
  build(0, boxes.size());
  return bvh;
}

struct Tree {
  std::string name;
  PackedBvh packed;
};

// Parent boxes contain their children's in every tree here; the exact counter identities below rely
// on it (a child box inside its parent is never hit when the parent is missed).
bool boxesNest(const PackedBvh& p) {
  for (uint32_t i = 0; i < p.nodes.size() / kNodeTexels; ++i) {
    const NodeRecord r = unpackNode(p, i);
    if (r.isLeaf()) continue;
    const Aabb parent{r.bmin, r.bmax};
    for (uint32_t c : {i + 1, r.a}) {
      const NodeRecord child = unpackNode(p, c);
      if (!parent.contains(Aabb{child.bmin, child.bmax})) return false;
    }
  }
  return true;
}

std::vector<Tree> treesFor(const TriangleSoup& soup, bool localShapes) {
  const std::vector<Aabb> boxes = triangleBoxes(soup);
  const std::vector<glm::vec3> centroids = triangleCentroids(soup);
  std::vector<Tree> trees;
  for (const BuilderInfo& b : builders()) {
    BuildOptions options;
    options.maxLeafSize = 4;
    // With the vertices, so a builder that splits primitives (sbvh) clips the triangles: its leaves
    // then reference a triangle more than once, with boxes that hold only the clipped parts.
    const BuildInput input{boxes, centroids, soup.v0, soup.v1, soup.v2};
    trees.push_back({b.name, packBvh(buildBvh(b.name, input, options), soup)});
  }
  if (localShapes) {
    trees.push_back({"test-chain", packBvh(chainBvh(boxes), soup)});
    trees.push_back({"test-random-split", packBvh(randomSplitBvh(boxes, 17), soup)});
  }
  return trees;
}

// ---- rays and brute force -----------------------------------------------------------------------

struct RayQuery {
  Ray ray;
  float tMin, tMax;
};

struct BruteHit {
  bool found = false;
  float t = 0.0f;
  std::vector<uint32_t> ties;  // input triangle ids hit at exactly t
};

BruteHit bruteForce(const TriangleSoup& soup, const RayQuery& q) {
  BruteHit best;
  for (uint32_t i = 0; i < soup.size(); ++i) {
    float t;
    glm::vec2 bary;
    if (!glsl::intersectTriangle(q.ray, soup.v0[i], soup.v1[i], soup.v2[i], q.tMin, q.tMax, t, bary)) continue;
    if (!best.found || t < best.t) {
      best.found = true;
      best.t = t;
      best.ties.clear();
    }
    if (t == best.t) best.ties.push_back(i);
  }
  return best;
}

Aabb soupBounds(const TriangleSoup& soup) {
  Aabb b;
  for (const Aabb& box : triangleBoxes(soup)) b.grow(box);
  return b;
}

// Random rays between a point around the scene and a point in it (every third one unnormalised),
// with three kinds of interval: (0, inf), (0, random), (random, inf).
std::vector<RayQuery> randomRays(const Aabb& bounds, size_t count, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const glm::vec3 c = bounds.center(), e = bounds.extent();
  const float radius = glm::length(e);
  std::vector<RayQuery> rays;
  for (size_t i = 0; i < count; ++i) {
    const glm::vec3 from = c + (glm::vec3(u(rng), u(rng), u(rng)) - 0.5f) * 2.0f * e;
    const glm::vec3 to = bounds.min + glm::vec3(u(rng), u(rng), u(rng)) * e;
    glm::vec3 dir = to - from;
    if (i % 3 != 0) dir = glm::normalize(dir);
    const float scale = radius / glm::length(dir);  // world distance -> t
    RayQuery q{{from, dir}, 0.0f, glsl::INF};
    if (i % 3 == 1) q.tMax = u(rng) * 2.0f * scale;
    if (i % 3 == 2) q.tMin = u(rng) * scale;
    rays.push_back(q);
  }
  return rays;
}

// A pinhole camera's primary rays, n x n over a 50 degree field of view.
std::vector<RayQuery> cameraRays(const Aabb& bounds, glm::vec3 direction, int n) {
  const glm::vec3 c = bounds.center();
  const float radius = 0.5f * glm::length(bounds.extent());
  const glm::vec3 forward = glm::normalize(direction);
  const glm::vec3 eye = c - 2.5f * radius * forward;
  const glm::vec3 right = glm::normalize(glm::cross(forward, std::abs(forward.y) > 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0)));
  const glm::vec3 up = glm::cross(right, forward);
  const float h = std::tan(glm::radians(25.0f));
  std::vector<RayQuery> rays;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const float px = (2.0f * (float(x) + 0.5f) / float(n) - 1.0f) * h, py = (2.0f * (float(y) + 0.5f) / float(n) - 1.0f) * h;
      rays.push_back({{eye, glm::normalize(forward + px * right + py * up)}, 0.0f, glsl::INF});
    }
  return rays;
}

// ---- the reference counts for a ray that hits nothing ------------------------------------------

// With no hit the closest-hit distance never shrinks, so each kernel's counters follow from which
// boxes the ray meets alone. Each count below restates a kernel's documented counter definition as
// a recursion over the tree, with no stack and no ordering.
struct MissCounts {
  uint32_t reachedNodes = 0;   // stackless: one visit per node reached
  uint32_t orderedVisits = 0;  // root + 2 per hit inner node + 1 per push (each push is popped)
  uint32_t unorderedVisits = 0;  // 1 per pop + 1 per child box tested
  uint32_t triTests = 0;       // triangles of leaves whose box and all ancestors' boxes are hit
  uint32_t unorderedTriTests = 0;  // the same, except the root is popped without a box test
};

MissCounts missCounts(const PackedBvh& p, const RayQuery& q) {
  const glm::vec3 invDir = glsl::rayInverseDirection(q.ray.dir);
  auto hits = [&](uint32_t n) {
    const NodeRecord r = unpackNode(p, n);
    float tEnter;
    return glsl::intersectAabb(q.ray.origin, invDir, r.bmin, r.bmax, q.tMin, q.tMax, tEnter);
  };
  MissCounts m;
  m.orderedVisits = 1;
  std::function<void(uint32_t)> reach = [&](uint32_t n) {
    ++m.reachedNodes;
    if (!hits(n)) return;
    const NodeRecord r = unpackNode(p, n);
    if (r.isLeaf()) {
      m.triTests += r.count;
      return;
    }
    m.orderedVisits += 2 + ((hits(n + 1) && hits(r.a)) ? 1 : 0);
    reach(n + 1);
    reach(r.a);
  };
  std::function<void(uint32_t)> pop = [&](uint32_t n) {
    ++m.unorderedVisits;
    const NodeRecord r = unpackNode(p, n);
    if (r.isLeaf()) {
      m.unorderedTriTests += r.count;
      return;
    }
    for (uint32_t child : {n + 1, r.a}) {
      ++m.unorderedVisits;
      if (hits(child)) pop(child);
    }
  };
  reach(0);
  pop(0);
  return m;
}

// ---- the check ----------------------------------------------------------------------------------

struct KernelRun {
  bool closestFound, anyFound;
  MeshHit hit;
  Counters closest, any;
};

KernelRun runKernel(const KernelInfo& k, const glsl::Storage& s, const RayQuery& q) {
  KernelRun r{};
  r.closestFound = k.traceClosest(s, q.ray, q.tMin, q.tMax, r.hit, r.closest);
  r.anyFound = k.traceAny(s, q.ray, q.tMin, q.tMax, r.any);
  return r;
}

std::string describe(const RayQuery& q) {
  std::ostringstream s;
  s.precision(9);
  s << "ray o=(" << q.ray.origin.x << ", " << q.ray.origin.y << ", " << q.ray.origin.z << ") d=(" << q.ray.dir.x << ", "
    << q.ray.dir.y << ", " << q.ray.dir.z << ") t in (" << q.tMin << ", " << q.tMax << ")";
  return s.str();
}

// Checks every kernel on every ray of one tree; returns how many rays hit something.
size_t checkTree(const TriangleSoup& soup, const Tree& tree, const std::vector<RayQuery>& rays,
                 const std::vector<BruteHit>& truth) {
  SCOPED_TRACE("tree " + tree.name);
  EXPECT_TRUE(boxesNest(tree.packed)) << "a parent box does not contain its child's";
  const glsl::Storage storage(tree.packed);
  size_t hits = 0, failures = 0;
  auto fail = [&](const std::string& what, const RayQuery& q) {
    if (++failures <= 5) ADD_FAILURE() << what << "; " << describe(q);
  };
  for (size_t i = 0; i < rays.size(); ++i) {
    const RayQuery& q = rays[i];
    const BruteHit& b = truth[i];
    hits += b.found;
    std::map<std::string, KernelRun> runs;
    for (const KernelInfo& k : kernels()) {
      const KernelRun r = runKernel(k, storage, q);
      runs[k.name] = r;
      if (r.closest.stackOverflow || r.any.stackOverflow) fail(k.name + ": stack overflow at stackSizeFor(depth)", q);
      if (r.closestFound != b.found || r.anyFound != b.found) {
        fail(k.name + ": closest " + std::to_string(r.closestFound) + " any " + std::to_string(r.anyFound) +
                 ", brute force " + std::to_string(b.found),
             q);
        continue;
      }
      // traceAny walks like traceClosest and stops at the first hit: never more work.
      if (r.any.nodeVisits > r.closest.nodeVisits || r.any.triTests > r.closest.triTests)
        fail(k.name + ": any-hit did more work than closest-hit", q);
      if (!b.found) {
        if (r.hit.tri != -1 || r.hit.t != q.tMax) fail(k.name + ": a miss must leave hit = (tMax, -1)", q);
        if (r.any.nodeVisits != r.closest.nodeVisits || r.any.triTests != r.closest.triTests)
          fail(k.name + ": on a miss, any-hit and closest-hit walk the same nodes", q);
        continue;
      }
      const uint32_t id = tree.packed.triangles.at(size_t(kTriangleTexels) * uint32_t(r.hit.tri)).w;
      float t;
      glm::vec2 bary;
      glsl::intersectTriangle(q.ray, soup.v0[id], soup.v1[id], soup.v2[id], q.tMin, q.tMax, t, bary);
      if (std::bit_cast<uint32_t>(r.hit.t) != std::bit_cast<uint32_t>(b.t) ||
          std::find(b.ties.begin(), b.ties.end(), id) == b.ties.end() || r.hit.bary != bary)
        fail(k.name + ": closest hit t=" + std::to_string(r.hit.t) + " id " + std::to_string(id) + ", brute force t=" +
                 std::to_string(b.t) + " id " + std::to_string(b.ties.front()),
             q);
    }
    if (runs.count("stackless") && runs.count("stack-unordered") && b.found &&
        runs["stackless"].hit.tri != runs["stack-unordered"].hit.tri)
      fail("stackless and stack-unordered reach leaves in the same order, so they break ties alike", q);
    if (!b.found) {
      const MissCounts m = missCounts(tree.packed, q);
      for (const auto& [name, r] : runs) {
        const uint32_t expected = name == "stack-unordered" ? m.unorderedTriTests : m.triTests;
        if (r.closest.triTests != expected)
          fail(name + ": " + std::to_string(r.closest.triTests) + " triangle tests on a miss, expected " +
                   std::to_string(expected),
               q);
      }
      const std::map<std::string, uint32_t> visits = {
          {"stackless", m.reachedNodes}, {"stack-ordered", m.orderedVisits}, {"stack-unordered", m.unorderedVisits}};
      for (const auto& [name, expected] : visits)
        if (runs.count(name) && runs[name].closest.nodeVisits != expected)
          fail(name + ": " + std::to_string(runs[name].closest.nodeVisits) + " node visits on a miss, expected " +
                   std::to_string(expected),
               q);
    }
  }
  EXPECT_EQ(failures, 0u) << "rays failing (first 5 shown above)";
  return hits;
}

void checkScene(const std::string& name, const TriangleSoup& soup, std::vector<RayQuery> rays, bool localShapes) {
  SCOPED_TRACE("scene " + name);
  std::vector<BruteHit> truth;
  for (const RayQuery& q : rays) truth.push_back(bruteForce(soup, q));
  size_t hits = 0;
  for (const Tree& tree : treesFor(soup, localShapes)) hits = checkTree(soup, tree, rays, truth);
  // Both outcomes must be exercised for the test to mean anything.
  EXPECT_GT(hits, rays.size() / 10) << "too few rays hit";
  EXPECT_LT(hits, rays.size()) << "no ray misses";
}

std::vector<RayQuery> mixedRays(const TriangleSoup& soup, size_t random, uint32_t seed) {
  const Aabb bounds = soupBounds(soup);
  std::vector<RayQuery> rays = randomRays(bounds, random, seed);
  for (glm::vec3 dir : {glm::vec3(0.3f, -0.5f, -1.0f), glm::vec3(0.0f, 0.0f, 1.0f)})
    for (const RayQuery& q : cameraRays(bounds, dir, 16)) rays.push_back(q);
  return rays;
}

// ---- tests --------------------------------------------------------------------------------------

TEST(Traversal, RegistryAndStackSize) {
  ASSERT_GE(kernels().size(), 3u);
  for (const KernelInfo& k : kernels()) {
    EXPECT_EQ(&findKernel(k.name), &k);
    EXPECT_NO_THROW(glslModule(k.glslFile)) << k.name << " names a GLSL file that is not embedded";
    EXPECT_NE(k.traceClosest, nullptr);
    EXPECT_NE(k.traceAny, nullptr);
  }
  try {
    findKernel("no-such-kernel");
    ADD_FAILURE() << "no error for an unknown kernel";
  } catch (const std::invalid_argument& e) {
    for (const KernelInfo& k : kernels()) EXPECT_NE(std::string(e.what()).find(k.name), std::string::npos) << e.what();
  }
  EXPECT_EQ(stackSizeFor(0), 1);
  EXPECT_EQ(stackSizeFor(1), 1);
  EXPECT_EQ(stackSizeFor(37), 37);
}

TEST(Traversal, SphereFromOutsideAndInside) {
  const TriangleSoup soup = soupOf({sphereMesh(16, 32, 1.0f)});
  std::vector<RayQuery> rays = mixedRays(soup, 300, 1);
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int i = 0; i < 100; ++i)  // from inside a closed surface every ray hits
    rays.push_back({{glm::vec3(u(rng), u(rng), u(rng)) * 0.3f, glm::vec3(u(rng), u(rng), u(rng))}, 0.0f, glsl::INF});
  checkScene("sphere", soup, rays, true);
}

TEST(Traversal, RandomSoup) {
  const TriangleSoup soup = soupOf({randomSoupMesh(600, 4)});
  checkScene("random soup", soup, mixedRays(soup, 400, 5), true);
}

TEST(Traversal, FlatGridWithTiesAndAxisAlignedRays) {
  const TriangleSoup soup = soupOf({gridMesh(12)});
  std::vector<RayQuery> rays = mixedRays(soup, 200, 6);
  // Straight down through grid vertices and edge midpoints: direction components exactly 0, origins
  // exactly on slab planes, up to six triangles hit at the same t.
  for (int i = 0; i <= 12; ++i)
    for (int j = 0; j <= 24; j += 3) {
      const glm::vec3 o(-1.0f + 2.0f * float(i) / 12.0f, 1.0f, -1.0f + 2.0f * float(j) / 24.0f);
      rays.push_back({{o, glm::vec3(0.0f, -1.0f, 0.0f)}, 0.0f, glsl::INF});
      rays.push_back({{o, glm::vec3(0.0f, -1.0f, 0.0f)}, 0.0f, 1.0f});  // ends exactly on the plane: a miss
    }
  // In the plane, parallel to it: the flat boxes are entered but no triangle can be hit (det = 0).
  rays.push_back({{glm::vec3(-2.0f, 0.0f, 0.1f), glm::vec3(1.0f, 0.0f, 0.0f)}, 0.0f, glsl::INF});
  checkScene("grid", soup, rays, true);
}

TEST(Traversal, Bunny) {
  const std::filesystem::path path = std::filesystem::path(BVHLAB_SOURCE_DIR) / "datasets/cache/meshes/bunny00.off";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " not found: run datasets/fetch.sh to test on the bunny";
  const TriangleSoup soup = soupOf({loadMesh(path)});
  checkScene("bunny", soup, mixedRays(soup, 150, 7), false);
}

// Triangles stacked along z over the same square, in a chain tree: every box is hit by a ray down
// the z axis, which is what makes the documented stack bounds tight.
TEST(Traversal, StackBoundsAreExactAndOverflowIsReported) {
  const int n = 40;
  Mesh m;
  for (int k = 0; k < n; ++k) {
    const float z = float(k);
    const uint32_t base = uint32_t(m.positions.size());
    m.positions.insert(m.positions.end(), {{-1.0f, -1.0f, z}, {1.0f, -1.0f, z}, {-1.0f, 1.0f, z}});
    m.triangles.push_back({base, base + 1, base + 2});
  }
  const TriangleSoup soup = soupOf({m});
  const PackedBvh packed = packBvh(chainBvh(triangleBoxes(soup)), soup);
  ASSERT_EQ(packed.depth, uint32_t(n));
  const int depth = int(packed.depth);
  const Ray ray{glm::vec3(-0.5f, -0.25f, float(n) + 5.0f), glm::vec3(0.0f, 0.0f, -1.0f)};
  const float expectedT = 6.0f;  // the top triangle, z = n - 1

  // kernel -> the smallest stack that never overflows, from the bound documented in its GLSL file
  const std::map<std::string, int> bounds = {{"stack-unordered", depth}, {"stack-ordered", depth - 1}};
  for (const auto& [name, bound] : bounds) {
    SCOPED_TRACE(name);
    const KernelInfo& k = findKernel(name);
    ASSERT_LE(bound, stackSizeFor(packed.depth));
    Counters enough, tooSmall;
    MeshHit hit;
    EXPECT_TRUE(k.traceClosest(glsl::Storage(packed, bound), ray, 0.0f, glsl::INF, hit, enough));
    EXPECT_FALSE(enough.stackOverflow);
    EXPECT_EQ(hit.t, expectedT);
    k.traceClosest(glsl::Storage(packed, bound - 1), ray, 0.0f, glsl::INF, hit, tooSmall);
    EXPECT_TRUE(tooSmall.stackOverflow) << "a stack of " << bound - 1 << " must overflow on this chain";
    Counters anyCounters;
    k.traceAny(glsl::Storage(packed, bound - 1), ray, 0.0f, glsl::INF, anyCounters);
    EXPECT_TRUE(anyCounters.stackOverflow);
  }
  // The stackless kernel needs no stack at all.
  Counters c;
  MeshHit hit;
  EXPECT_TRUE(findKernel("stackless").traceClosest(glsl::Storage(packed, 1), ray, 0.0f, glsl::INF, hit, c));
  EXPECT_EQ(hit.t, expectedT);
  EXPECT_THROW(glsl::Storage(packed, 0), std::invalid_argument);
}

TEST(RayBox, InverseDirectionIsFiniteAndSlabsNeverSeeNan) {
  for (float d : {0.0f, -0.0f, 1e-40f, -1e-40f, 1e-31f}) {
    const glm::vec3 inv = glsl::rayInverseDirection(glm::vec3(d, 1.0f, -2.0f));
    EXPECT_TRUE(std::isfinite(inv.x)) << d;
    if (d != 0.0f) {
      EXPECT_EQ(std::signbit(inv.x), std::signbit(d)) << d;  // a zero may become either sign
    }
    EXPECT_EQ(inv.y, 1.0f);
    EXPECT_EQ(inv.z, -0.5f);
  }
  // Parallel to x = 0 and lying in it: the box [0,1]^3 spans the plane, so the ray meets it;
  // with the origin just outside the slab it does not.
  const glm::vec3 dir(0.0f, 1.0f, 0.0f), inv = glsl::rayInverseDirection(dir);
  float tEnter = -1.0f;
  EXPECT_TRUE(glsl::intersectAabb(glm::vec3(0.5f, -1.0f, 0.5f), inv, glm::vec3(0), glm::vec3(1), 0.0f, glsl::INF, tEnter));
  EXPECT_EQ(tEnter, 1.0f);
  EXPECT_FALSE(glsl::intersectAabb(glm::vec3(1.5f, -1.0f, 0.5f), inv, glm::vec3(0), glm::vec3(1), 0.0f, glsl::INF, tEnter));
  EXPECT_FALSE(std::isnan(tEnter));
  // On either bounding plane of the slab: inside (the box is closed), whatever the sign of the zero.
  for (float x : {0.0f, 1.0f})
    for (float zero : {0.0f, -0.0f}) {
      const glm::vec3 invZero = glsl::rayInverseDirection(glm::vec3(zero, 1.0f, 0.0f));
      EXPECT_TRUE(glsl::intersectAabb(glm::vec3(x, -1.0f, 0.5f), invZero, glm::vec3(0), glm::vec3(1), 0.0f, glsl::INF, tEnter))
          << "origin x = " << x << ", dir x = " << zero;
      EXPECT_EQ(tEnter, 1.0f);
    }
  // A flat box (min = max on an axis), as every node over a plane has, with the ray in its plane.
  EXPECT_TRUE(glsl::intersectAabb(glm::vec3(0.5f, -1.0f, 0.5f), inv, glm::vec3(0, 0, 0.5f), glm::vec3(1, 1, 0.5f), 0.0f,
                                  glsl::INF, tEnter));
  // The interval clips: a box wholly behind tMax's end or before tMin's start is missed.
  const glm::vec3 along = glsl::rayInverseDirection(glm::vec3(1, 0, 0));
  EXPECT_FALSE(glsl::intersectAabb(glm::vec3(-5, 0.5f, 0.5f), along, glm::vec3(0), glm::vec3(1), 0.0f, 4.0f, tEnter));
  EXPECT_TRUE(glsl::intersectAabb(glm::vec3(-5, 0.5f, 0.5f), along, glm::vec3(0), glm::vec3(1), 0.0f, 5.0f, tEnter));
  EXPECT_FALSE(glsl::intersectAabb(glm::vec3(-5, 0.5f, 0.5f), along, glm::vec3(0), glm::vec3(1), 6.5f, 9.0f, tEnter));
  EXPECT_TRUE(glsl::intersectAabb(glm::vec3(-5, 0.5f, 0.5f), along, glm::vec3(0), glm::vec3(1), 5.5f, 9.0f, tEnter));
  EXPECT_EQ(tEnter, 5.5f);
}

TEST(RayTriangle, OpenIntervalEdgesAndDegenerates) {
  const glm::vec3 v0(0, 0, 0), v1(1, 0, 0), v2(0, 1, 0);
  const Ray down{glm::vec3(0.25f, 0.25f, 2.0f), glm::vec3(0, 0, -1)};
  float t;
  glm::vec2 bary;
  EXPECT_TRUE(glsl::intersectTriangle(down, v0, v1, v2, 0.0f, glsl::INF, t, bary));
  EXPECT_EQ(t, 2.0f);
  EXPECT_EQ(bary, glm::vec2(0.25f, 0.25f));
  EXPECT_FALSE(glsl::intersectTriangle(down, v0, v1, v2, 0.0f, 2.0f, t, bary)) << "t == tMax is outside";
  EXPECT_FALSE(glsl::intersectTriangle(down, v0, v1, v2, 2.0f, glsl::INF, t, bary)) << "t == tMin is outside";
  EXPECT_TRUE(glsl::intersectTriangle(down, v0, v1, v2, 1.9f, 2.1f, t, bary));
  // Edges and vertices belong to the triangle.
  EXPECT_TRUE(glsl::intersectTriangle({glm::vec3(0.5f, 0.0f, 1.0f), glm::vec3(0, 0, -1)}, v0, v1, v2, 0.0f, glsl::INF, t, bary));
  EXPECT_TRUE(glsl::intersectTriangle({glm::vec3(0.0f, 1.0f, 1.0f), glm::vec3(0, 0, -1)}, v0, v1, v2, 0.0f, glsl::INF, t, bary));
  EXPECT_FALSE(glsl::intersectTriangle({glm::vec3(0.6f, 0.6f, 1.0f), glm::vec3(0, 0, -1)}, v0, v1, v2, 0.0f, glsl::INF, t, bary));
  // Parallel ray in the plane, a zero-area triangle, a denormal determinant: misses, no NaN.
  EXPECT_FALSE(glsl::intersectTriangle({glm::vec3(-1, 0.2f, 0), glm::vec3(1, 0, 0)}, v0, v1, v2, 0.0f, glsl::INF, t, bary));
  EXPECT_FALSE(glsl::intersectTriangle(down, v0, v1, glm::vec3(2, 0, 0), 0.0f, glsl::INF, t, bary));
  EXPECT_FALSE(std::isnan(t));
  const float tiny = 1e-20f;  // det ~ 1e-40: below the smallest normal float
  EXPECT_FALSE(glsl::intersectTriangle({glm::vec3(0.25f * tiny, 0.25f * tiny, 1.0f), glm::vec3(0, 0, -1)}, v0,
                                       glm::vec3(tiny, 0, 0), glm::vec3(0, tiny, 0), 0.0f, glsl::INF, t, bary));
  EXPECT_FALSE(std::isnan(t));
  // Backfaces hit too (no culling): the kernels serve refraction rays leaving a surface.
  EXPECT_TRUE(glsl::intersectTriangle({glm::vec3(0.25f, 0.25f, -2.0f), glm::vec3(0, 0, 1)}, v0, v1, v2, 0.0f, glsl::INF, t, bary));
}

TEST(TraversalLayout, AttributesInterpolateLikeTheGlsl) {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.normals = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.uvs = {{0, 0}, {1, 0}, {0, 1}};
  m.triangles = {{0, 1, 2}};
  const TriangleSoup soup = soupOf({m});
  Bvh bvh;
  bvh.nodes.resize(1);
  bvh.nodes[0].count = 1;
  bvh.nodes[0].bounds = triangleBoxes(soup)[0];
  bvh.primIndices = {0};
  const PackedBvh packed = packBvh(bvh, soup);
  glm::vec3 n;
  glm::vec2 uv;
  glsl::loadAttributes(packed, 0, glm::vec2(0.25f, 0.5f), n, uv);
  EXPECT_EQ(n, glm::vec3(0.25f, 0.25f, 0.5f));  // weights (1 - u - v, u, v), not normalised
  EXPECT_EQ(uv, glm::vec2(0.25f, 0.5f));
  uint32_t primitive, material, mesh;
  glsl::loadTriangleIds(packed, 0, primitive, material, mesh);
  EXPECT_EQ(primitive, 0u);
  EXPECT_EQ(material, 0u);
  EXPECT_EQ(mesh, 0u);
}

// The GLSL itself: every kernel with both storage kinds, concatenated in assembly order under a stub
// main, must compile with the reference front end.
TEST(TraversalGlsl, EveryKernelCompilesWithGlslang) {
  if (std::system("command -v glslangValidator > /dev/null 2>&1") != 0)
    GTEST_SKIP() << "glslangValidator not found (Debian package glslang-tools)";
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("bvhlab_test_traversal_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string stubMain = R"(
layout(location = 0) out uvec4 o_result;
void main() {
  Ray ray = Ray(vec3(gl_FragCoord.xy, -1.0), vec3(0.0, 0.0, 1.0));
  MeshHit hit;
  bool closest = traceClosest(ray, 0.0, INF, hit);
  bool any = traceAny(ray, 0.0, INF);
  vec3 normal;
  vec2 uv;
  if (closest) loadAttributes(hit.tri, hit.bary, normal, uv);
  o_result = uvec4(floatBitsToUint(hit.t), uint(hit.tri), g_nodeVisits + g_triTests,
                   uint(any) + (g_stackOverflow ? 2u : 0u) + floatBitsToUint(normal.x + uv.y));
}
)";
  for (const char* storage : {"storage_tbo.glsl", "storage_tex2d.glsl"})
    for (const KernelInfo& k : kernels()) {
      std::string source = "#version 450 core\n#define BVH_STACK_SIZE 7\n";
      for (const std::string& module : {std::string("common.glsl"), std::string(storage), std::string("layout.glsl"),
                                        std::string("ray_box.glsl"), std::string("ray_triangle.glsl"),
                                        std::string("triangles_raw.glsl"), k.glslFile})
        source += glslModule(module);
      source += stubMain;
      const std::filesystem::path file = dir / (k.name + "_" + storage + ".frag");
      const std::filesystem::path log = dir / (k.name + "_" + storage + ".log");
      std::ofstream(file) << source;
      const std::string cmd = "glslangValidator -S frag '" + file.string() + "' > '" + log.string() + "' 2>&1";
      const int rc = std::system(cmd.c_str());
      std::stringstream text;
      text << std::ifstream(log).rdbuf();
      EXPECT_EQ(rc, 0) << k.name << " with " << storage << ":\n" << text.str();
    }
  std::filesystem::remove_all(dir);
}


// ---- the GLSL on a GL device, against the mirror ------------------------------------------------

// One compute invocation per ray: closest hit, then any hit, with the counters of each.
// in: 2 vec4 per ray (origin, tMin), (dir, tMax); out: 3 uvec4 per ray.
const char* const kCrossCheckMain = R"(
layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer RayBuffer { vec4 rays[]; };
layout(std430, binding = 1) writeonly buffer ResultBuffer { uvec4 results[]; };
uniform int u_count;
void main() {
  int i = int(gl_GlobalInvocationID.x);
  if (i >= u_count) return;
  Ray ray = Ray(rays[2 * i].xyz, rays[2 * i + 1].xyz);
  float tMin = rays[2 * i].w, tMax = rays[2 * i + 1].w;
  MeshHit hit;
  bool closest = traceClosest(ray, tMin, tMax, hit);
  uvec4 closestCounts = uvec4(g_nodeVisits, g_triTests, g_stackOverflow ? 1u : 0u, 0u);
  g_nodeVisits = 0u;
  g_triTests = 0u;
  g_stackOverflow = false;
  bool any = traceAny(ray, tMin, tMax);
  results[3 * i + 0] = uvec4(closest ? 1u : 0u, uint(hit.tri), floatBitsToUint(hit.t), any ? 1u : 0u);
  results[3 * i + 1] = closestCounts;
  results[3 * i + 2] = uvec4(g_nodeVisits, g_triTests, g_stackOverflow ? 1u : 0u, 0u);
}
)";


// The three streams as GL textures of one storage kind, bound to units 0..2.
struct GlStreams {
  std::vector<GLuint> buffers, textures;

  GlStreams(const PackedBvh& p, bool tex2d) {
    const std::vector<glm::uvec4>* streams[3] = {&p.nodes, &p.triangles, &p.attributes};
    for (GLuint unit = 0; unit < 3; ++unit) {
      const std::vector<glm::uvec4>& texels = *streams[unit];
      GLuint tex = 0;
      if (tex2d) {
        const GLsizei w = GLsizei(kTex2DWidth), h = GLsizei((texels.size() + kTex2DWidth - 1) / kTex2DWidth);
        std::vector<glm::uvec4> padded(size_t(w) * size_t(h), glm::uvec4(0));
        std::copy(texels.begin(), texels.end(), padded.begin());
        glCreateTextures(GL_TEXTURE_2D, 1, &tex);
        glTextureStorage2D(tex, 1, GL_RGBA32UI, w, h);
        glTextureSubImage2D(tex, 0, 0, 0, w, h, GL_RGBA_INTEGER, GL_UNSIGNED_INT, padded.data());
        glTextureParameteri(tex, GL_TEXTURE_MIN_FILTER, GL_NEAREST);  // integer textures: no filtering
        glTextureParameteri(tex, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
      } else {
        GLuint buf = 0;
        glCreateBuffers(1, &buf);
        glNamedBufferData(buf, GLsizeiptr(texels.size() * sizeof(glm::uvec4)), texels.data(), GL_STATIC_DRAW);
        glCreateTextures(GL_TEXTURE_BUFFER, 1, &tex);
        glTextureBuffer(tex, GL_RGBA32UI, buf);
        buffers.push_back(buf);
      }
      glBindTextureUnit(unit, tex);
      textures.push_back(tex);
    }
    checkGl("uploading the BVH streams");
  }
  ~GlStreams() {
    glDeleteTextures(GLsizei(textures.size()), textures.data());
    glDeleteBuffers(GLsizei(buffers.size()), buffers.data());
  }
};

struct GpuRun {
  bool closestFound, anyFound;
  int tri;
  float t;
  Counters closest, any;
};

// The kernel over one storage kind, compiled once per (kernel, storage, stack size): llvmpipe
// compiles a kernel in ~0.5 s without its disk cache.
GLuint crossCheckProgram(const KernelInfo& kernel, bool tex2d, int stackSize) {
  static std::map<std::string, GLuint> programs;
  const std::string key = kernel.name + (tex2d ? "/tex2d/" : "/tbo/") + std::to_string(stackSize);
  if (auto it = programs.find(key); it != programs.end()) return it->second;
  std::string source = "#version 450 core\n#define BVH_STACK_SIZE " + std::to_string(stackSize) + "\n";
  for (const std::string& module : {std::string("common.glsl"), std::string(tex2d ? "storage_tex2d.glsl" : "storage_tbo.glsl"),
                                    std::string("layout.glsl"), std::string("ray_box.glsl"),
                                    std::string("ray_triangle.glsl"), std::string("triangles_raw.glsl"),
                                    kernel.glslFile})
    source += glslModule(module);
  return programs[key] = compileCompute(source + kCrossCheckMain);
}

std::vector<GpuRun> traceOnGl(const KernelInfo& kernel, bool tex2d, const PackedBvh& packed, int stackSize,
                              const std::vector<RayQuery>& rays) {
  const GLuint program = crossCheckProgram(kernel, tex2d, stackSize);
  const GlStreams streams(packed, tex2d);
  std::vector<glm::vec4> in;
  for (const RayQuery& q : rays) {
    in.emplace_back(q.ray.origin, q.tMin);
    in.emplace_back(q.ray.dir, q.tMax);
  }
  GLuint io[2];
  glCreateBuffers(2, io);
  glNamedBufferData(io[0], GLsizeiptr(in.size() * sizeof(glm::vec4)), in.data(), GL_STATIC_DRAW);
  glNamedBufferData(io[1], GLsizeiptr(rays.size() * 3 * sizeof(glm::uvec4)), nullptr, GL_STATIC_READ);
  glUseProgram(program);
  glUniform1i(glGetUniformLocation(program, "u_count"), GLint(rays.size()));
  const char* names[3] = {"u_nodes", "u_triangles", "u_attributes"};
  for (int unit = 0; unit < 3; ++unit) glUniform1i(glGetUniformLocation(program, names[unit]), unit);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, io[0]);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, io[1]);
  glDispatchCompute(GLuint((rays.size() + 63) / 64), 1, 1);
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  std::vector<glm::uvec4> out(rays.size() * 3);
  glGetNamedBufferSubData(io[1], 0, GLsizeiptr(out.size() * sizeof(glm::uvec4)), out.data());
  checkGl("traversal cross-check dispatch");
  glDeleteBuffers(2, io);
  std::vector<GpuRun> runs(rays.size());
  for (size_t i = 0; i < rays.size(); ++i) {
    const glm::uvec4 a = out[3 * i], b = out[3 * i + 1], c = out[3 * i + 2];
    runs[i].closestFound = a.x != 0;
    runs[i].tri = int(a.y);
    runs[i].t = std::bit_cast<float>(a.z);
    runs[i].anyFound = a.w != 0;
    runs[i].closest = Counters{b.x, b.y, 0, b.z != 0};
    runs[i].any = Counters{c.x, c.y, 0, c.z != 0};
  }
  return runs;
}

// The GLSL kernels, compiled by the driver and run on its device, give the mirror's hits and
// counters. OSMesa (llvmpipe) by default; BVHLAB_GL_BACKEND=egl runs them through EGL (the NVIDIA
// driver on a GPU machine), where fused multiply-adds may move a few grazing hits.
TEST(TraversalGlsl, GpuAgreesWithTheMirror) {
  std::unique_ptr<GlContext> context;
  try {
    const char* backend = std::getenv("BVHLAB_GL_BACKEND");
    context = createContext(backend && *backend ? parseBackend(backend) : Backend::OSMesa);
  } catch (const std::exception& e) {
    GTEST_SKIP() << "no OpenGL 4.5 context (" << e.what() << "): GLSL not run";
  }
  struct SceneRays {
    std::string name;
    TriangleSoup soup;
    std::vector<RayQuery> rays;
  };
  std::vector<SceneRays> scenes;
  {
    SceneRays sphere{"sphere", soupOf({sphereMesh(16, 32, 1.0f)}), {}};
    sphere.rays = mixedRays(sphere.soup, 500, 11);
    scenes.push_back(std::move(sphere));
    SceneRays grid{"grid", soupOf({gridMesh(12)}), {}};
    grid.rays = mixedRays(grid.soup, 300, 12);
    for (int i = 0; i <= 12; ++i)
      for (int j = 0; j <= 12; ++j)
        grid.rays.push_back({{glm::vec3(-1.0f + float(i) / 6.0f, 1.0f, -1.0f + float(j) / 6.0f), glm::vec3(0, -1, 0)}, 0.0f, glsl::INF});
    scenes.push_back(std::move(grid));
  }
  // One stack size for every tree (the deepest one's), so each kernel compiles once per storage.
  std::vector<std::vector<Tree>> trees;
  uint32_t maxDepth = 1;
  for (const SceneRays& scene : scenes) {
    const std::vector<Aabb> boxes = triangleBoxes(scene.soup);
    const std::vector<glm::vec3> centroids = triangleCentroids(scene.soup);
    trees.push_back({{"sah-binned", packBvh(buildBvh("sah-binned", BuildInput{boxes, centroids}, BuildOptions{}), scene.soup)},
                     {"test-chain", packBvh(chainBvh(boxes), scene.soup)}});
    for (const Tree& tree : trees.back()) maxDepth = std::max(maxDepth, tree.packed.depth);
  }
  const int stackSize = stackSizeFor(maxDepth);
  size_t compared = 0, identical = 0, diffT = 0;
  double maxRelativeT = 0.0;
  for (size_t s = 0; s < scenes.size(); ++s) {
    const SceneRays& scene = scenes[s];
    for (const Tree& tree : trees[s])
      for (const KernelInfo& k : kernels())
        for (bool tex2d : {false, true}) {
          SCOPED_TRACE(scene.name + " / " + tree.name + " / " + k.name + (tex2d ? " / tex2d" : " / tbo"));
          const std::vector<GpuRun> gpu = traceOnGl(k, tex2d, tree.packed, stackSize, scene.rays);
          int failures = 0;
          for (size_t i = 0; i < scene.rays.size(); ++i) {
            const KernelRun cpu = runKernel(k, glsl::Storage(tree.packed, stackSize), scene.rays[i]);
            const GpuRun& g = gpu[i];
            ++compared;
            // Hits, triangles and counters must be identical. t may differ in its last bits: the driver
            // evaluates dot and cross in its own order (llvmpipe: up to 3 ulp on ~6% of hits here).
            const double relativeT = g.t == cpu.hit.t ? 0.0  // also both tMax = inf on a miss
                                     : std::abs(double(g.t) - double(cpu.hit.t)) / std::abs(double(cpu.hit.t));
            const bool same = g.closestFound == cpu.closestFound && g.anyFound == cpu.anyFound && g.tri == cpu.hit.tri &&
                              relativeT <= 1e-6 && g.closest.nodeVisits == cpu.closest.nodeVisits &&
                              g.closest.triTests == cpu.closest.triTests && g.any.nodeVisits == cpu.any.nodeVisits &&
                              g.any.triTests == cpu.any.triTests && !g.closest.stackOverflow && !g.any.stackOverflow;
            identical += same;
            diffT += g.t != cpu.hit.t;
            maxRelativeT = std::max(maxRelativeT, relativeT);
            if (!same && ++failures <= 3)
              ADD_FAILURE() << "GLSL: found " << g.closestFound << "/" << g.anyFound << " tri " << g.tri << " t " << g.t
                            << " visits " << g.closest.nodeVisits << "/" << g.any.nodeVisits << " tests " << g.closest.triTests
                            << "/" << g.any.triTests << "; mirror: found " << cpu.closestFound << "/" << cpu.anyFound << " tri "
                            << cpu.hit.tri << " t " << cpu.hit.t << " visits " << cpu.closest.nodeVisits << "/"
                            << cpu.any.nodeVisits << " tests " << cpu.closest.triTests << "/" << cpu.any.triTests << "; "
                            << describe(scene.rays[i]);
          }
        }
  }
  std::printf("GLSL vs mirror on %s: %zu of %zu ray queries agree; t differs in %zu (max relative %.2g)\n",
              context->renderer().c_str(), identical, compared, diffT, maxRelativeT);
  EXPECT_EQ(identical, compared);
}

}  // namespace
}  // namespace bvhlab
