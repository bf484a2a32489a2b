// Bytes fetched per ray, counted by the kernels' C++ mirrors (glsl::Counters::nodeBytes,
// triangleBytes, stackBytes; each traversal/kernel_*.hpp states how it counts): a hand-made tree
// whose counts are worked out here from the layouts' texel sizes, the byte counts against the
// other counters for every kernel, and cwbvh's bytes beside v1's on the bunny's diffuse rays.
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "datasets/procedural.hpp"
#include "datasets/scene_io.hpp"
#include "layout/layout_wide.hpp"
#include "layout/layouts.hpp"
#include "layout/triangle_formats.hpp"
#include "render/prepared_scene.hpp"
#include "render/trace_run.hpp"
#include "render/workloads.hpp"
#include "traversal/embree_tracer.hpp"
#include "traversal/kernels.hpp"
#include "traversal/layout_wide.hpp"
#include "layout_test_util.hpp"
#include "require.hpp"

namespace bvhlab {
namespace {

using glsl::Counters;
using glsl::kTexelBytes;
using glsl::MeshHit;
using glsl::Ray;

// Two triangles over the unit square's lower-left half, one behind the other along +z (each tilted
// so its box has depth), and a tree made by hand: an inner root, a leaf per triangle.
TriangleSoup twoTriangles() {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0.1f}, {0, 1, 0.1f}, {0, 0, 1}, {1, 0, 1.1f}, {0, 1, 1.1f}};
  m.triangles = {{0, 1, 2}, {3, 4, 5}};
  MeshSceneOptions mo;
  mo.groundPlane = false;
  return gatherTriangles(makeMeshScene(std::move(m), mo));
}

Bvh handTree(const TriangleSoup& soup) {
  const std::vector<Aabb> boxes = triangleBoxes(soup);
  Bvh bvh;
  BvhNode root, a, b;
  root.bounds.grow(boxes[0]);
  root.bounds.grow(boxes[1]);
  root.left = 1;
  root.right = 2;
  a.bounds = boxes[0];
  a.first = 0;
  a.count = 1;
  b.bounds = boxes[1];
  b.first = 1;
  b.count = 1;
  bvh.nodes = {root, a, b};
  bvh.primIndices = {0, 1};
  return bvh;
}

// Down +z through both boxes: the near triangle is hit at t ~ 1, the far box is entered at t ~ 2.
const Ray kRay{glm::vec3(0.25f, 0.25f, -1.0f), glm::vec3(0.0f, 0.0f, 1.0f)};

Counters traceOne(const PackedBvh& packed, const std::string& kernel, MeshHit& hit) {
  Counters c;
  EXPECT_TRUE(findKernel(packed.layout, kernel).traceClosest(packed, kRay, 0.0f, 1e30f, hit, c));
  EXPECT_EQ(hit.tri, 0) << "the nearer triangle (leaf order = triangle order here)";
  return c;
}

// v1, stack-ordered: the root, then both children (two texels each: layout.glsl) are read; both
// boxes are met, the farther child is pushed (int + float), the near leaf tests its one triangle
// (raw: three texels), and the pushed entry is dropped (entered beyond the hit).
TEST(BytesFetched, HandTreeV1StackOrdered) {
  const TriangleSoup soup = twoTriangles();
  const PackedBvh packed = findLayout("v1").pack(handTree(soup), soup);
  MeshHit hit;
  const Counters c = traceOne(packed, "stack-ordered", hit);
  const uint64_t node = 3 * (2 * kTexelBytes), tri = 1 * (3 * kTexelBytes), stack = 2 * (sizeof(int) + sizeof(float));
  EXPECT_EQ(c.nodeBytes, node);
  EXPECT_EQ(c.triangleBytes, tri);
  EXPECT_EQ(c.stackBytes, stack);
}

// The same tree in the indexed triangle format: a triangle test reads its index texel and then its
// three VERTEX texels.
TEST(BytesFetched, HandTreeV1Indexed) {
  const TriangleSoup soup = twoTriangles();
  PackedBvh packed = findLayout("v1").pack(handTree(soup), soup);
  packTriangles(packed, soup, "indexed");
  MeshHit hit;
  const Counters c = traceOne(packed, "stack-ordered", hit);
  EXPECT_EQ(c.triangleBytes, uint64_t(1 + 3) * kTexelBytes);
  EXPECT_EQ(c.nodeBytes, uint64_t(3 * 2 * kTexelBytes));
}

// bvh4: the root's slot (two texels: layout_wide.glsl), then the root node's two child slots; the
// farther child is pushed (uint + uint + float) and dropped after the near leaf's triangle test.
TEST(BytesFetched, HandTreeBvh4) {
  const TriangleSoup soup = twoTriangles();
  const PackedBvh packed = findLayout("bvh4").pack(handTree(soup), soup);
  MeshHit hit;
  const Counters c = traceOne(packed, "", hit);
  EXPECT_EQ(c.nodeBytes, uint64_t((1 + 2) * 2 * kTexelBytes));
  EXPECT_EQ(c.triangleBytes, uint64_t(3 * kTexelBytes));
  EXPECT_EQ(c.stackBytes, uint64_t(2 * (2 * sizeof(uint32_t) + sizeof(float))));
}

// bvh4 with three leaves one behind the other along +z, under one wide node whose slots hold them near
// to far (checked below from the packed slots): the first met child is walked next, the second is
// pushed, the third is pushed below it, which shifts the second up (read and written). So: the root's
// slot and three child slots, one triangle test, and 2 pushes + 1 shift (2 entries) + 2 drops.
TEST(BytesFetched, HandTreeBvh4InsertionShift) {
  Mesh m;
  for (int k = 0; k < 3; ++k) {
    const float z = float(k);
    m.positions.insert(m.positions.end(), {{0, 0, z}, {1, 0, z + 0.1f}, {0, 1, z + 0.1f}});
    m.triangles.push_back({uint32_t(3 * k), uint32_t(3 * k + 1), uint32_t(3 * k + 2)});
  }
  MeshSceneOptions mo;
  mo.groundPlane = false;
  const TriangleSoup soup = gatherTriangles(makeMeshScene(std::move(m), mo));
  const std::vector<Aabb> boxes = triangleBoxes(soup);
  Bvh bvh;
  BvhNode root, a, bc, b, c;
  for (const Aabb& box : boxes) root.bounds.grow(box);
  root.left = 1;
  root.right = 2;
  a.bounds = boxes[0];
  a.first = 0;
  a.count = 1;
  bc.bounds = boxes[1];
  bc.bounds.grow(boxes[2]);
  bc.left = 3;
  bc.right = 4;
  b.bounds = boxes[1];
  b.first = 1;
  b.count = 1;
  c.bounds = boxes[2];
  c.first = 2;
  c.count = 1;
  bvh.nodes = {root, a, bc, b, c};
  bvh.primIndices = {0, 1, 2};
  const PackedBvh packed = findLayout("bvh4").pack(bvh, soup);
  // The precondition: one wide node of three leaf slots, near to far along +z.
  const glsl::Storage st(packed);
  glm::vec3 lo, hi;
  uint32_t link, count;
  glsl::loadSlot(st, 0u, lo, hi, link, count);
  ASSERT_EQ(count, kWideInner + 3u);
  float lastZ = -1.0f;
  for (uint32_t i = 0; i < 3; ++i) {
    uint32_t childLink, childCount;
    glsl::loadSlot(st, link + 2u * i, lo, hi, childLink, childCount);
    ASSERT_LT(childCount, kWideInner) << "slot " << i << " is a leaf";
    ASSERT_GT(lo.z, lastZ) << "slots near to far";
    lastZ = lo.z;
  }
  MeshHit hit;
  const Counters k = traceOne(packed, "", hit);
  const uint64_t entry = 2 * sizeof(uint32_t) + sizeof(float);
  EXPECT_EQ(k.nodeBytes, uint64_t((1 + 3) * 2 * kTexelBytes));
  EXPECT_EQ(k.triangleBytes, uint64_t(3 * kTexelBytes));
  EXPECT_EQ(k.stackBytes, 2 * entry + 2 * entry + 2 * entry);
}

// cwbvh: the root's grid box (its first texel), then the root node whole (five texels:
// layout_cwbvh.glsl); stack and triangles as bvh4's.
TEST(BytesFetched, HandTreeCwbvh) {
  const TriangleSoup soup = twoTriangles();
  const PackedBvh packed = findLayout("cwbvh").pack(handTree(soup), soup);
  MeshHit hit;
  const Counters c = traceOne(packed, "", hit);
  EXPECT_EQ(c.nodeBytes, uint64_t((1 + 5) * kTexelBytes));
  EXPECT_EQ(c.triangleBytes, uint64_t(3 * kTexelBytes));
  EXPECT_EQ(c.stackBytes, uint64_t(2 * (2 * sizeof(uint32_t) + sizeof(float))));
}

// cwbvh-groups on the same tree: the root's grid box, the root node whole; both leaves are met and form
// the node's triangle group, taken nearest first (by octant: the +z ray takes the near leaf's slot
// first); the near triangle's hit then culls the far leaf, entered beyond it. Nothing is pushed: the
// root's group holds one child, taken from registers.
TEST(BytesFetched, HandTreeCwbvhGroups) {
  const TriangleSoup soup = twoTriangles();
  const PackedBvh packed = findLayout("cwbvh").pack(handTree(soup), soup);
  MeshHit hit;
  const Counters c = traceOne(packed, "cwbvh-groups", hit);
  EXPECT_EQ(c.nodeBytes, uint64_t((1 + 5) * kTexelBytes));
  EXPECT_EQ(c.triangleBytes, uint64_t(3 * kTexelBytes));
  EXPECT_EQ(c.stackBytes, 0u);
  EXPECT_EQ(c.nodeVisits, 1u);
  EXPECT_EQ(c.boxTests, 3u);
}

// Per kernel, on a sphere and a soup with random rays: node bytes follow the visits (or, for the
// wide kernels that fetch one slot per box test, the box tests); triangle bytes are triangle tests
// times the record size of the format; a closest-hit walk pops every entry it pushed, so its stack
// bytes are whole push + pop pairs of the kernel's entry (the wide kernels' shifts are too).
TEST(BytesFetched, ConsistentWithTheOtherCounters) {
  struct Sizes {
    uint64_t perVisit, perBox, root, stackEntry;
  };
  const auto sizesOf = [](const std::string& kernel) -> Sizes {
    if (kernel == "stack-unordered") return {2 * kTexelBytes, 0, 0, 4};
    if (kernel == "stack-ordered") return {2 * kTexelBytes, 0, 0, 8};
    if (kernel == "stackless") return {2 * kTexelBytes, 0, 0, 0};
    if (kernel == "bvh2cb-stack-ordered" || kernel == "bvh2cb-aila-laine") return {4 * kTexelBytes, 0, 0, 12};
    if (kernel == "bvh4-stack-ordered" || kernel == "bvh8-stack-ordered" || kernel == "bvh4-fetch-whole" ||
        kernel == "bvh8-fetch-whole")
      return {0, 2 * kTexelBytes, 0, 12};
    if (kernel == "cwbvh-stack-ordered") return {5 * kTexelBytes, 0, kTexelBytes, 12};
    if (kernel == "cwbvh-groups" || kernel == "cwbvh-groups-shared") return {5 * kTexelBytes, 0, kTexelBytes, 8};
    ADD_FAILURE() << "no byte sizes stated here for kernel " << kernel;
    return {0, 0, 0, 0};
  };
  const std::vector<std::pair<std::string, uint64_t>> formats = {
      {"raw", 3 * kTexelBytes}, {"precomputed", 4 * kTexelBytes}, {"indexed", 4 * kTexelBytes}};
  size_t kernelsChecked = 0;
  for (const layouttest::TestMesh& m : layouttest::testMeshes()) {
    if (m.name == "cube-grid") continue;
    const std::vector<BatchRay> rays = layouttest::testRays(m.soup, 200, 11);
    const Bvh bvh = layouttest::build("sah-binned", m.soup);
    for (const LayoutInfo& l : layouts())
      for (const auto& [format, recordBytes] : formats) {
        PackedBvh packed = l.pack(bvh, m.soup);
        packTriangles(packed, m.soup, format);
        for (const KernelInfo& k : kernelsFor(l.name)) {
          SCOPED_TRACE(m.name + " / " + l.name + " / " + format + " / " + k.name);
          const Sizes z = sizesOf(k.name);
          uint64_t stackTotal = 0;
          for (const BatchRay& r : rays) {
            Counters c;
            MeshHit hit;
            k.traceClosest(packed, Ray{r.origin, r.dir}, r.tMin, r.tMax, hit, c);
            ASSERT_FALSE(c.stackOverflow);
            ASSERT_EQ(c.nodeBytes, z.root + z.perVisit * c.nodeVisits + z.perBox * c.boxTests);
            ASSERT_EQ(c.triangleBytes, recordBytes * c.triTests);
            if (z.stackEntry == 0)
              ASSERT_EQ(c.stackBytes, 0u);
            else
              ASSERT_EQ(c.stackBytes % (2 * z.stackEntry), 0u);
            stackTotal += c.stackBytes;
          }
          if (z.stackEntry > 0) {
            EXPECT_GT(stackTotal, 0u) << "no ray pushed anything: the stack count is untested";
          }
          ++kernelsChecked;
        }
      }
  }
  EXPECT_EQ(kernelsChecked, 2 * 3 * allKernels().size());
}

// cwbvh's kernels against v1's default (stack-ordered) on the bunny's diffuse rays, the same rays for
// all, every ray through the mirror: the ratios of total bytes per ray are printed; cwbvh-groups' is
// held to the target of at most half v1's (the mirror's counts are exact: no noise band to leave).
TEST(BytesFetched, CwbvhAgainstV1OnTheBunnysDiffuseRays) {
  const std::filesystem::path bunny = std::filesystem::path(BVHLAB_SOURCE_DIR) / "datasets/cache/meshes/bunny00.off";
  if (!std::filesystem::exists(bunny)) BVHLAB_SKIP_OR_FAIL(bunny << " is missing: run `bash datasets/fetch.sh`");
  const auto v1 = prepareScene(loadMeshScene(bunny), "sah-binned", BuildOptions{}, "v1");
  const auto cw = prepareScene(loadMeshScene(bunny), "sah-binned", BuildOptions{}, "cwbvh");
  EmbreeTracer embree(v1->soup, 1);
  WorkloadRequest r;
  r.workload = Workload::Diffuse;
  r.count = 50000;
  r.seed = 1;
  r.width = v1->scene.settings.width;
  r.height = v1->scene.settings.height;
  const RayWorkload w = generateWorkload(r, v1->scene, v1->soup, [&embree](const std::vector<BatchRay>& rays) {
    std::vector<BatchHit> hits;
    embree.closest(rays, hits);
    return hits;
  });
  ASSERT_GT(w.rays.size(), 1000u);
  const BytesFetched a = mirrorBytesFetched(v1->packed, "", Robustness::Watertight, false, w.rays, 0);
  ASSERT_EQ(a.rays, w.rays.size());
  const double n = double(w.rays.size());
  const double totalA = (a.sum[0] + a.sum[1] + a.sum[2]) / n;
  ASSERT_GT(totalA, 0.0);
  std::printf("bunny diffuse, %zu rays, bytes per ray (node + triangle + stack):\n", w.rays.size());
  std::printf("  v1 stack-ordered:    %.1f + %.1f + %.1f = %.1f\n", a.sum[0] / n, a.sum[1] / n, a.sum[2] / n, totalA);
  for (const KernelInfo& k : kernelsFor("cwbvh")) {
    const BytesFetched b = mirrorBytesFetched(cw->packed, k.name, Robustness::Watertight, false, w.rays, 0);
    ASSERT_EQ(b.rays, w.rays.size());
    const double totalB = (b.sum[0] + b.sum[1] + b.sum[2]) / n;
    ASSERT_GT(totalB, 0.0);
    std::printf("  %s: %.1f + %.1f + %.1f = %.1f\n", k.name.c_str(), b.sum[0] / n, b.sum[1] / n, b.sum[2] / n, totalB);
    std::printf("  %s / v1 total: %.3f (node %.3f, triangle %.3f, stack %.3f)\n", k.name.c_str(), totalB / totalA,
                b.sum[0] / a.sum[0], b.sum[1] / a.sum[1], b.sum[2] / a.sum[2]);
    RecordProperty(k.name + "_over_v1_bytes", std::to_string(totalB / totalA));
    if (k.name == "cwbvh-groups") {
      EXPECT_LE(totalB, 0.5 * totalA) << "the target: at most half v1's bytes per diffuse ray";
    }
  }
}

}  // namespace
}  // namespace bvhlab
