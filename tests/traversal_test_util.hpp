// Shared by test_traversal.cpp (the C++ mirrors against brute force and recursive definitions) and
// test_traversal_glsl.cpp (the GLSL on a GL device against the mirrors): test meshes, trees (the
// registered builders plus two test-local shapes), rays, brute force, the reference counts of a miss,
// and the per-scene check of every kernel.
#pragma once
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
#include <glm/gtc/constants.hpp>
#include <gtest/gtest.h>
#include "builders/builder.hpp"
#include "datasets/mesh_io.hpp"
#include "datasets/random_draws.hpp"
#include "layout/layout.hpp"
#include "traversal/kernels.hpp"
#include "traversal/ray_box.hpp"
#include "traversal/ray_triangle.hpp"

namespace bvhlab::traversaltest {

using glsl::Counters;
using glsl::MeshHit;
using glsl::Ray;

// ---- meshes -------------------------------------------------------------------------------------

inline Mesh sphereMesh(int stacks, int slices, float radius) {
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

inline Mesh randomSoupMesh(size_t count, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f), edge(-0.15f, 0.15f);
  Mesh m;
  m.name = "random-soup";
  for (size_t i = 0; i < count; ++i) {
    const glm::vec3 c = draw3<glm::vec3>(unit, rng);
    for (int k = 0; k < 3; ++k) m.positions.push_back(c + draw3<glm::vec3>(edge, rng));
    m.triangles.push_back({uint32_t(3 * i), uint32_t(3 * i + 1), uint32_t(3 * i + 2)});
  }
  return m;
}

// The plane y = 0 over [-1,1]^2 as n x n quads: coplanar triangles sharing edges and vertices, so
// rays through grid vertices meet several triangles at the same t (ties), and every box is flat.
inline Mesh gridMesh(int n) {
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

inline TriangleSoup soupOf(std::vector<Mesh> meshes) {
  Scene s;
  s.materials.resize(1);
  s.meshes = std::move(meshes);
  return gatherTriangles(s);
}

// ---- trees: the registered builders plus two test-local shapes ---------------------------------

inline Aabb boundsOf(const std::vector<Aabb>& boxes, const std::vector<uint32_t>& prims, size_t begin, size_t end) {
  Aabb b;
  for (size_t i = begin; i < end; ++i) b.grow(boxes[prims[i]]);
  return b;
}

// The deepest possible tree: each inner node's second child is a leaf holding the primitive with the
// smallest centroid z, its first child the chain of the rest. Depth = primitive count.
inline Bvh chainBvh(const std::vector<Aabb>& boxes) {
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
inline Bvh randomSplitBvh(const std::vector<Aabb>& boxes, uint32_t seed) {
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
inline bool boxesNest(const PackedBvh& p) {
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

inline std::vector<Tree> treesFor(const TriangleSoup& soup, bool localShapes) {
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

inline BruteHit bruteForce(const TriangleSoup& soup, const RayQuery& q) {
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

inline Aabb soupBounds(const TriangleSoup& soup) {
  Aabb b;
  for (const Aabb& box : triangleBoxes(soup)) b.grow(box);
  return b;
}

// Random rays between a point around the scene and a point in it (every third one unnormalised),
// with three kinds of interval: (0, inf), (0, random), (random, inf).
inline std::vector<RayQuery> randomRays(const Aabb& bounds, size_t count, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const glm::vec3 c = bounds.center(), e = bounds.extent();
  const float radius = glm::length(e);
  std::vector<RayQuery> rays;
  for (size_t i = 0; i < count; ++i) {
    const glm::vec3 from = c + (draw3<glm::vec3>(u, rng) - 0.5f) * 2.0f * e;
    const glm::vec3 to = bounds.min + draw3<glm::vec3>(u, rng) * e;
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
inline std::vector<RayQuery> cameraRays(const Aabb& bounds, glm::vec3 direction, int n) {
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

inline MissCounts missCounts(const PackedBvh& p, const RayQuery& q) {
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

inline KernelRun runKernel(const KernelInfo& k, const glsl::Storage& s, const RayQuery& q) {
  KernelRun r{};
  r.closestFound = k.traceClosest(s, q.ray, q.tMin, q.tMax, r.hit, r.closest);
  r.anyFound = k.traceAny(s, q.ray, q.tMin, q.tMax, r.any);
  return r;
}

inline std::string describe(const RayQuery& q) {
  std::ostringstream s;
  s.precision(9);
  s << "ray o=(" << q.ray.origin.x << ", " << q.ray.origin.y << ", " << q.ray.origin.z << ") d=(" << q.ray.dir.x << ", "
    << q.ray.dir.y << ", " << q.ray.dir.z << ") t in (" << q.tMin << ", " << q.tMax << ")";
  return s.str();
}

// Checks every kernel on every ray of one tree; returns how many rays hit something.
inline size_t checkTree(const TriangleSoup& soup, const Tree& tree, const std::vector<RayQuery>& rays,
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

inline void checkScene(const std::string& name, const TriangleSoup& soup, std::vector<RayQuery> rays, bool localShapes) {
  SCOPED_TRACE("scene " + name);
  std::vector<BruteHit> truth;
  for (const RayQuery& q : rays) truth.push_back(bruteForce(soup, q));
  size_t hits = 0;
  for (const Tree& tree : treesFor(soup, localShapes)) hits = checkTree(soup, tree, rays, truth);
  // Both outcomes must be exercised for the test to mean anything.
  EXPECT_GT(hits, rays.size() / 10) << "too few rays hit";
  EXPECT_LT(hits, rays.size()) << "no ray misses";
}

inline std::vector<RayQuery> mixedRays(const TriangleSoup& soup, size_t random, uint32_t seed) {
  const Aabb bounds = soupBounds(soup);
  std::vector<RayQuery> rays = randomRays(bounds, random, seed);
  for (glm::vec3 dir : {glm::vec3(0.3f, -0.5f, -1.0f), glm::vec3(0.0f, 0.0f, 1.0f)})
    for (const RayQuery& q : cameraRays(bounds, dir, 16)) rays.push_back(q);
  return rays;
}

}  // namespace bvhlab::traversaltest
