// PLOC (Meister & Bittner 2018, "Parallel Locally-Ordered Clustering for Bounding Volume Hierarchy
// Construction", IEEE TVCG 24(3)): bottom-up agglomerative clustering along the Morton curve.
//  1. Centroids quantised to a 2^21 grid over their bounds and interleaved into 63-bit Morton codes
//     (as lbvh does; with BuildOptions::mortonSizeBits, size bits among the upper ones:
//     builders/morton.hpp), radix-sorted. Primitives with equal codes (coincident centroids to 2^-21
//     of the extent, fewer bits with size bits, and the same size class) cannot be told apart: each
//     such run starts as one cluster, a balanced tree over the run (what lbvh does with equal codes;
//     clustering nested boxes of one centre would chain them into a list).
//  2. Repeat until one cluster is left: every cluster finds its nearest neighbour -- the one whose
//     merged box has the smallest (half) area -- among the clusters within +-radius in the current
//     order (BuildOptions::plocRadius, 1..1024); mutual nearest neighbours merge (the merged cluster
//     takes the lower position, the order is kept) and the array is compacted.
//     With BuildOptions::plocTopDown = F > 0 the passes stop once n / F clusters are left, and
//     those are split top-down instead: sah-binned over the cluster boxes (box centres as centroids),
//     leaves of one cluster, the same thread count. PLOC for the bottom of the tree, binned SAH for
//     its top, where PLOC loses most of its SAH (docs/builders.md, "The knobs").
//  3. The single-primitive-leaf tree is collapsed by SAH (builders/collapse.hpp, shared with lbvh).
// Ties in the merged area are broken by a key of the pair alone (builders/ploc_keys.hpp), so the
// smallest pair in the window is always mutual (at least one merge per pass) and equal boxes pair up
// (2k, 2k+1) instead of chaining.
// Threads: the passes work in fixed chunks of the order (never derived from the thread count) and
// every cluster's neighbour is a function of the clusters alone, so the tree is the same for any
// thread count. Quality, leaf 4, Ct = Ci = 1: 1.09x sah-binned's SAH on the bunny, elephant and
// armadillo, 1.05x on makeLargeMesh(1M), 0.91x on random soups (tests/test_ploc.cpp); Morton size bits
// change that by -0.7..+1% (docs/builders.md).
#include <algorithm>
#include <array>
#include <atomic>
#include <barrier>
#include <bit>
#include <cstring>
#include <limits>
#include <memory>
#include <new>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

// The neighbour search runs on GCC/Clang vector extensions, 4 lanes (SSE2 on x86-64), or 8 lanes on
// CPUs with AVX2 (chosen at run time). BVHLAB_NO_SIMD forces the scalar loop, BVHLAB_NO_AVX2 the 4
// lanes: every path makes the same float operations on the same pairs and the same choices, so the
// same trees (tests/test_ploc.cpp: Ploc.MatchesTheDefinition, a plain implementation, against the
// path the machine takes).
#if (defined(__GNUC__) || defined(__clang__)) && !defined(BVHLAB_NO_SIMD)
#define BVHLAB_PLOC_VECTOR 1
#if defined(__x86_64__) && !defined(BVHLAB_NO_AVX2)
#define BVHLAB_PLOC_AVX2 1
#endif
#endif

#include "builders/morton.hpp"
#include "builders/morton_sort.hpp"
#include "builders/build_util.hpp"
#include "builders/builder.hpp"
#include "builders/collapse.hpp"
#include "builders/ploc_keys.hpp"

namespace bvhlab {

namespace {

// Clusters per job. Fixed (never derived from the thread count); chunks only split the work, no
// cluster's neighbour depends on them. A job also searches for the radius clusters on either side
// (to see which of its own are mutual) and needs the merged areas of the radius before those:
// about 3 * 16 / 8192 = 0.6% more work at the default radius.
constexpr uint32_t kChunk = 8192;
// Clusters per job of a clustering pass: 512 per unit of radius, within 2048..8192. Small chunks
// spread the few jobs of a pass near the end (PLOC's top-down variant stops at n / F clusters) evenly
// over the threads; each job also searches 2 * radius clusters around its own, which this keeps at
// 0.4% or less (2048 at radius 4: 0.988x with two threads on the bunny, same trees; at radius 16 it
// stays 8192, where 2048 cost one thread 1.1%). Chunks never change the tree.
uint32_t passChunk(uint32_t radius) { return std::clamp(std::bit_ceil(512 * radius), 2048u, 8192u); }
constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();

using detail::Keyed;

// The current clusters in order, structure of arrays: box[0..2] min x/y/z, box[3..5] max x/y/z,
// node = the cluster's node in the full tree. The box arrays have `pad` (>= radius + 8, a multiple
// of 4) entries before cluster 0 and after the last cluster holding an "everywhere" box, so the
// search reads whole vectors around any cluster without bounds checks: such a box's union
// with any box spans FLT_MAX - -FLT_MAX, which overflows to +inf on every axis, so its merged area
// is +inf (inf * inf and inf + inf, never inf - inf or 0 * inf: no NaN) and never beats a finite
// one. Entries between are left uninitialised: every pass writes what it reads. All arrays of one
// Clusters live in one block (a ScratchArray: whole advised huge pages from 1 MiB on, builders/scratch.hpp,
// so that a build's fresh block does not take a page fault per 4 KiB: measured in docs/builders.md).
struct Clusters {
  static constexpr float kHuge = std::numeric_limits<float>::max();
  static_assert(alignof(detail::CollapseInfo) <= 16 && sizeof(detail::CollapseInfo) % 4 == 0);
  size_t boxStride;  // floats per box array, pads included, a multiple of 4
  std::unique_ptr<detail::ScratchArray<float>> storage;  // (a pointer, so Clusters swap)
  float* box[6];
  uint32_t* node;
  detail::CollapseInfo* info;  // the node's (read here rather than from the tree)
  uint32_t pad;
  Clusters(uint32_t capacity, uint32_t padding)
      : boxStride((capacity + 2 * size_t(padding) + 3) & ~size_t(3)),
        storage(std::make_unique<detail::ScratchArray<float>>(6 * boxStride + (capacity + 3) / 4 * 4 +
                                                              capacity * (sizeof(detail::CollapseInfo) / 4))),
        pad(padding) {
    for (int a = 0; a < 6; ++a) {
      box[a] = storage->data() + a * boxStride + pad;  // 16-byte aligned: the block is, pad is a multiple of 4
      std::fill_n(box[a] - pad, pad, a < 3 ? -kHuge : kHuge);
    }
    node = reinterpret_cast<uint32_t*>(storage->data() + 6 * boxStride);
    info = reinterpret_cast<detail::CollapseInfo*>(storage->data() + 6 * boxStride + (capacity + 3) / 4 * 4);
  }
  void padAfter(uint32_t m) {
    for (int a = 0; a < 6; ++a) std::fill_n(box[a] + m, pad, a < 3 ? -kHuge : kHuge);
  }
  Aabb bounds(uint32_t i) const {
    return {{box[0][i], box[1][i], box[2][i]}, {box[3][i], box[4][i], box[5][i]}};
  }
  void set(uint32_t i, const Aabb& b, uint32_t n, const detail::CollapseInfo& nodeInfo) {
    for (int a = 0; a < 3; ++a) box[a][i] = b.min[a], box[3 + a][i] = b.max[a];
    node[i] = n;
    info[i] = nodeInfo;
  }
};

using detail::ploc::candidateKey;  // builders/ploc_keys.hpp

// A node of the full tree and its collapse entry, in one 64-byte cache line: the emission walks the
// tree depth-first, far from the order the nodes were made in, and reads both (one miss, not two).
struct alignas(64) FullNode {
  BvhNode node;
  detail::CollapseInfo info;
};
// Frees what detail::allocateScratch allocated (FullNode is trivially destructible: nothing to destroy).
static_assert(std::is_trivially_destructible_v<FullNode>);
struct FreeStorage {
  void operator()(FullNode* p) const { detail::freeScratch(p); }
};

// Scratch for one search job: the ring of recent forward areas (vector path), the nearest neighbours.
struct Scratch {
  std::vector<float> forward;
  std::vector<uint32_t> nn;
};

// Merged half area of clusters x and j, as Aabb::halfArea computes it: (ex*ey + ey*ez) + ez*ex.
// Inputs are finite and validated to a finite scene area, so it is finite for real clusters.
[[maybe_unused]] float mergedArea(const Clusters& c, int64_t x, int64_t j) {
  const float ex = std::max(c.box[3][x], c.box[3][j]) - std::min(c.box[0][x], c.box[0][j]);
  const float ey = std::max(c.box[4][x], c.box[4][j]) - std::min(c.box[1][x], c.box[1][j]);
  const float ez = std::max(c.box[5][x], c.box[5][j]) - std::min(c.box[2][x], c.box[2][j]);
  return (ex * ey + ey * ez) + ez * ex;
}

// The definition: the smallest candidateKey among the clusters within radius on either side.
[[maybe_unused]] void nearestNeighboursScalar(const Clusters& c, uint32_t m, uint32_t radius, uint32_t lo,
                                              uint32_t hi, Scratch& s) {
  for (uint32_t x = lo; x < hi; ++x) {
    uint64_t best = ~uint64_t(0);
    uint32_t nearest = kNone;
    for (uint32_t d = 1; d <= radius; ++d) {
      if (x >= d) {
        const uint64_t key = candidateKey(mergedArea(c, x, x - d), x, x - d);
        if (key < best) best = key, nearest = x - d;
      }
      if (x + d < m) {
        const uint64_t key = candidateKey(mergedArea(c, x, x + d), x, x + d);
        if (key < best) best = key, nearest = x + d;
      }
    }
    s.nn[x - lo] = nearest;
  }
}

#if defined(BVHLAB_PLOC_VECTOR)
// W consecutive clusters x0..x0+W-1 (x0 a multiple of W) per vector. For d = 1..radius: the merged
// areas with x + d (forward), kept in a ring of the last `ring` columns per d, from which the merged
// areas with x - d (backward) are read back, so each pair is computed once. Ties on area go to the
// smaller d on each side (strict <, d ascending); the sides then meet by candidateKey. The blocks
// start up to W - 1 clusters early; the lanes before lo may read ring columns this job has not
// written (zeros or older areas, never NaN), and their results are dropped.
// min/max as a < b ? a : b: inputs are never NaN; for -0 vs +0 the choice can differ from the
// scalar loop's, which only changes the sign of a zero area, and candidateKey ignores that.
typedef float Float4 __attribute__((vector_size(16)));
typedef int32_t Int4 __attribute__((vector_size(16)));
typedef float Float8 __attribute__((vector_size(32)));
typedef int32_t Int8 __attribute__((vector_size(32)));
template <int W>
struct Vectors;
template <>
struct Vectors<4> {
  using F = Float4;
  using I = Int4;
};
template <>
struct Vectors<8> {
  using F = Float8;
  using I = Int8;
};

template <int W>
[[gnu::always_inline]] inline void nearestNeighboursVector(const Clusters& c, uint32_t radius, uint32_t lo,
                                                           uint32_t hi, Scratch& s) {
  using F = typename Vectors<W>::F;
  using I = typename Vectors<W>::I;
  F inf;
  for (int l = 0; l < W; ++l) inf[l] = kInf;
  const uint32_t ring = std::bit_ceil(radius + W);  // >= the radius + W columns in use at once
  const size_t stride = ring + W;                    // + a copy of columns 0..W-1: no load wraps
  s.forward.resize(radius * stride);
  float* const ringBase = s.forward.data();
  const int64_t first = (int64_t(lo) - radius) & ~int64_t(W - 1);  // >= -pad: padding before 0
  for (int64_t x0 = first; x0 < int64_t(hi); x0 += W) {
    F box[6];
    for (int a = 0; a < 6; ++a) std::memcpy(&box[a], c.box[a] + x0, sizeof(F));
    const uint32_t column = uint32_t(x0) & (ring - 1);
    F forwardArea = inf, backwardArea = inf;
    I forwardD = {}, backwardD = {};
    float* row = ringBase;
    for (uint32_t d = 1; d <= radius; ++d, row += stride) {
      F e[3];
      for (int a = 0; a < 3; ++a) {
        F low, high;
        std::memcpy(&low, c.box[a] + x0 + d, sizeof(F));
        std::memcpy(&high, c.box[3 + a] + x0 + d, sizeof(F));
        e[a] = (box[3 + a] > high ? box[3 + a] : high) - (box[a] < low ? box[a] : low);
      }
      const F area = (e[0] * e[1] + e[1] * e[2]) + e[2] * e[0];
      std::memcpy(row + column, &area, sizeof(F));
      if (column == 0) std::memcpy(row + ring, &area, sizeof(F));
      const I better = area < forwardArea;
      forwardArea = better ? area : forwardArea;
      forwardD = better ? int32_t(d) : forwardD;
    }
    if (x0 + W <= int64_t(lo)) continue;  // only its forward areas were needed
    row = ringBase;
    for (uint32_t d = 1; d <= radius; ++d, row += stride) {
      F area;  // written d columns ago
      std::memcpy(&area, row + (uint32_t(x0 - d) & (ring - 1)), sizeof(F));
      const I better = area < backwardArea;
      backwardArea = better ? area : backwardArea;
      backwardD = better ? int32_t(d) : backwardD;
    }
    for (int l = 0; l < W; ++l) {
      const int64_t x = x0 + l;
      if (x < int64_t(lo) || x >= int64_t(hi)) continue;
      // m >= 2, so one side has a real (finite) candidate; a side without one has area +inf.
      const uint32_t xi = uint32_t(x), forward = xi + uint32_t(forwardD[l]), backward = xi - uint32_t(backwardD[l]);
      s.nn[xi - lo] =
          candidateKey(forwardArea[l], xi, forward) < candidateKey(backwardArea[l], xi, backward) ? forward : backward;
    }
  }
}

void nearestNeighbours4(const Clusters& c, uint32_t radius, uint32_t lo, uint32_t hi, Scratch& s) {
  nearestNeighboursVector<4>(c, radius, lo, hi, s);
}
#if defined(BVHLAB_PLOC_AVX2)
[[gnu::target("avx2")]] void nearestNeighbours8(const Clusters& c, uint32_t radius, uint32_t lo, uint32_t hi,
                                                Scratch& s) {
  nearestNeighboursVector<8>(c, radius, lo, hi, s);
}
#endif
#endif

// Nearest neighbour of each cluster in [lo, hi) among the m clusters, into s.nn[0, hi - lo).
void nearestNeighbours(const Clusters& c, [[maybe_unused]] uint32_t m, uint32_t radius, uint32_t lo, uint32_t hi,
                       Scratch& s) {
  s.nn.resize(hi - lo);
#if defined(BVHLAB_PLOC_AVX2)
  static const bool avx2 = __builtin_cpu_supports("avx2");
  if (avx2) return nearestNeighbours8(c, radius, lo, hi, s);
#endif
#if defined(BVHLAB_PLOC_VECTOR)
  nearestNeighbours4(c, radius, lo, hi, s);
#else
  nearestNeighboursScalar(c, m, radius, lo, hi, s);
#endif
}

}  // namespace

Bvh buildPloc(const BuildInput& input, const BuildOptions& options) {
  const uint32_t radius = options.plocRadius;
  if (radius < 1 || radius > kMaxPlocRadius)
    throw std::invalid_argument("ploc: plocRadius " + std::to_string(radius) + " is outside 1.." +
                                std::to_string(kMaxPlocRadius));
  if (options.plocTopDown > kMaxPlocTopDown)
    throw std::invalid_argument("ploc: plocTopDown " + std::to_string(options.plocTopDown) + " is outside 0.." +
                                std::to_string(kMaxPlocTopDown));
  const uint32_t n = uint32_t(input.boxes.size());
  const unsigned threads = detail::resolveThreads(options.threads);
  const uint32_t jobs = (n + kChunk - 1) / kChunk;

  // 1. Morton order.
  const detail::MortonEncoder encoder(input, options.mortonSizeBits, options.mortonGrid);
  detail::ScratchVector<Keyed> keys(n);
  detail::runJobs(jobs, threads, [&](size_t job) {
    for (uint32_t i = uint32_t(job) * kChunk, end = std::min(n, i + kChunk); i < end; ++i) keys[i] = {encoder.code(i), i};
  });
  detail::sortMortonKeys(keys, threads);

  // The full tree: leaves at n - 1 + (Morton position), inner nodes numbered downwards from n - 2 as
  // they are made, so a parent (made after its children) has a smaller index and the root ends at 0.
  // Each node's collapse cost is computed as it is made (builders/collapse.hpp).
  // Storage only: each node is constructed once, when it is made (and first touched by the thread
  // that makes it), instead of being initialised first and then overwritten.
  const size_t nodes = 2 * size_t(n) - 1;
  std::unique_ptr<FullNode[], FreeStorage> full(
      static_cast<FullNode*>(detail::allocateScratch(nodes * sizeof(FullNode), alignof(FullNode))));
  auto makeInner = [&](uint32_t index, uint32_t left, uint32_t right, const Aabb& box, const detail::CollapseInfo& l,
                       const detail::CollapseInfo& r) -> const detail::CollapseInfo& {
    const BvhNode& node = *new (&full[index].node) BvhNode{box, left, right, 0, 0};
    return full[index].info = detail::collapseInnerInfo(node, l, r, options);
  };
  auto chunkOf = [&](size_t job, uint32_t size) {
    const uint32_t a = uint32_t(job) * kChunk;
    return std::pair{a, std::min(size, a + kChunk)};
  };
  const uint32_t kPassChunk = passChunk(radius);
  auto passChunkOf = [&](size_t job, uint32_t size) {
    const uint32_t a = uint32_t(job) * kPassChunk;
    return std::pair{a, std::min(size, a + kPassChunk)};
  };

  // Initial clusters: single primitives, and one balanced tree per run of equal codes. Per chunk of
  // the order: the leaves, and the runs that start in it (clusters) with their inner nodes; then the
  // runs' trees, at offsets from those counts (the numbering of a sequential pass).
  auto runStart = [&](uint32_t k) { return k == 0 || keys[k].code != keys[k - 1].code; };
  auto runEnd = [&](uint32_t k) {
    while (++k < n && keys[k].code == keys[k - 1].code) {}
    return k;
  };
  std::vector<uint32_t> outputs(jobs), merges(jobs), outputAt(jobs), nodeAt(jobs);
  detail::runJobs(jobs, threads, [&](size_t job) {
    const auto [a, b] = chunkOf(job, n);
    uint32_t runs = 0, inner = 0;
    for (uint32_t k = a; k < b; ++k) {
      const BvhNode& leaf = *new (&full[n - 1 + k].node) BvhNode{input.boxes[keys[k].id], 0, 0, keys[k].id, 1};
      full[n - 1 + k].info = detail::collapseLeafInfo(leaf, options);
      if (runStart(k)) ++runs, inner += runEnd(k) - k - 1;
    }
    outputs[job] = runs, merges[job] = inner;
  });
  uint32_t nextInner = n - 1;  // one past the next inner node's index
  auto offsets = [&](uint32_t chunks) {
    uint32_t total = 0;
    for (uint32_t job = 0; job < chunks; ++job) {
      outputAt[job] = total, nodeAt[job] = nextInner;
      total += outputs[job], nextInner -= merges[job];
    }
    return total;
  };
  const uint32_t pad = (radius + 11) & ~3u;  // >= radius + 8 (the widest vector), a multiple of 4
  Clusters clusters(n, pad), next(n, pad);
  uint32_t m = offsets(jobs);
  clusters.padAfter(m);
  detail::runJobs(jobs, threads, [&](size_t job) {
    const auto [a, b] = chunkOf(job, n);
    uint32_t out = outputAt[job], node = nodeAt[job];
    std::vector<uint32_t> level;
    for (uint32_t k = a; k < b; ++k) {
      if (!runStart(k)) continue;
      level.clear();
      for (uint32_t p = k, end = runEnd(k); p < end; ++p) level.push_back(n - 1 + p);
      while (level.size() > 1) {  // pair neighbours level by level: depth ceil(log2 run)
        size_t w = 0;
        for (size_t p = 0; p + 1 < level.size(); p += 2) {
          Aabb box = full[level[p]].node.bounds;
          box.grow(full[level[p + 1]].node.bounds);
          makeInner(--node, level[p], level[p + 1], box, full[level[p]].info, full[level[p + 1]].info);
          level[w++] = node;
        }
        if (level.size() % 2) level[w++] = level.back();
        level.resize(w);
      }
      clusters.set(out++, full[level[0]].node.bounds, level[0], full[level[0]].info);
    }
  });

  // 2. Cluster. Each pass: (a) per chunk of the order, every cluster's nearest neighbour (the chunk
  // also computes those of the radius clusters on either side, to see which of its own are mutual)
  // and the chunk's counts; (b) the offsets from the counts; (c) per chunk, the merged and kept
  // clusters written at those offsets. Merges are numbered in order, so the tree is that of a
  // sequential pass, whichever thread does which chunk.
  const uint32_t stopAt = options.plocTopDown ? std::max(1u, n / options.plocTopDown) : 1u;
  detail::ScratchVector<uint32_t> partner(n);  // the nearest neighbour when mutual, else kNone
  const size_t passJobs = (size_t(n) + kPassChunk - 1) / kPassChunk;
  if (outputs.size() < passJobs)
    for (auto* v : {&outputs, &merges, &outputAt, &nodeAt}) v->resize(passJobs);
  uint32_t chunks = (m + kPassChunk - 1) / kPassChunk, total = 0;
  const unsigned team = std::min<unsigned>(threads, chunks);
  std::vector<Scratch> scratch(std::max(team, 1u));  // one per thread
  for (Scratch& s : scratch) {  // the most a search asks for: no allocation (nor exception) inside
    s.nn.reserve(kPassChunk + 2 * size_t(radius));
    s.forward.reserve(radius * (std::bit_ceil(radius + 8) + 8));
  }
  auto search = [&](uint32_t job, Scratch& s) {
    const auto [a, b] = passChunkOf(job, m);
    const uint32_t lo = a - std::min(a, radius), hi = std::min(m, b + radius);
    nearestNeighbours(clusters, m, radius, lo, hi, s);
    uint32_t merged = 0, dropped = 0;
    for (uint32_t x = a; x < b; ++x) {  // branch-free: "mutual" is a coin flip to a predictor
      const uint32_t y = s.nn[x - lo];    // within radius of x, so inside [lo, hi)
      const uint32_t mutual = s.nn[y - lo] == x;
      partner[x] = y | (mutual - 1);  // kNone unless mutual
      merged += mutual & (x < y);
      dropped += mutual & (x > y);
    }
    outputs[job] = (b - a) - dropped;
    merges[job] = merged;
  };
  auto write = [&](uint32_t job) {
    const auto [a, b] = passChunkOf(job, m);
    uint32_t out = outputAt[job], node = nodeAt[job];
    for (uint32_t x = a; x < b; ++x) {
      const uint32_t y = partner[x];
      if (y == kNone) {  // no merge this pass: kept
        for (int k = 0; k < 6; ++k) next.box[k][out] = clusters.box[k][x];
        next.node[out] = clusters.node[x];
        next.info[out++] = clusters.info[x];
      } else if (x < y) {  // merged at the lower position
        Aabb box = clusters.bounds(x);
        box.grow(clusters.bounds(y));
        --node;
        next.set(out++, box, node,
                 makeInner(node, clusters.node[x], clusters.node[y], box, clusters.info[x], clusters.info[y]));
      }
    }
  };
  auto finishPass = [&] {
    std::swap(clusters, next);
    m = total;
    clusters.padAfter(m);
    chunks = (m + kPassChunk - 1) / kPassChunk;
  };
  // While a pass has several chunks: one team of threads for all those passes, in step at a barrier
  // after each phase (a thread start costs tens of microseconds, a pass can take less). The barrier's
  // completion step runs alone: the offsets, then the swap to the next pass.
  if (m > stopAt && team > 1) {
    std::atomic<uint32_t> claimSearch{0}, claimWrite{0};
    bool afterSearch = true;
    auto step = [&]() noexcept {
      if (afterSearch) {
        total = offsets(chunks);
        claimWrite = 0;
      } else {
        finishPass();
        claimSearch = 0;
      }
      afterSearch = !afterSearch;
    };
    std::barrier sync(team, step);
    detail::runJobs(team, team, [&](size_t member) {  // team jobs on team threads: all run at once
      while (m > stopAt && chunks > 1) {
        for (uint32_t job; (job = claimSearch++) < chunks;) search(job, scratch[member]);
        sync.arrive_and_wait();
        for (uint32_t job; (job = claimWrite++) < chunks;) write(job);
        sync.arrive_and_wait();
      }
    });
  }
  while (m > stopAt) {  // the rest (or everything, on one thread), sequentially
    for (uint32_t job = 0; job < chunks; ++job) search(job, scratch[0]);
    total = offsets(chunks);
    for (uint32_t job = 0; job < chunks; ++job) write(job);
    finishPass();
  }

  // The top, when the passes stopped early: sah-binned over the clusters, whose inner nodes become the
  // full tree's, made children first (each node's collapse entry needs its children's) and numbered
  // downwards from the m - 1 indices still free (m - 2 .. 0: the root last, at 0).
  if (m > 1) {
    detail::ScratchVector<Aabb> boxes(m);
    detail::ScratchVector<glm::vec3> centres(m);
    for (uint32_t i = 0; i < m; ++i) boxes[i] = clusters.bounds(i), centres[i] = boxes[i].center();
    BuildOptions topOptions;
    topOptions.maxLeafSize = 1;
    topOptions.cost = options.cost;
    topOptions.threads = options.threads;
    const Bvh top = buildBvh("sah-binned", BuildInput{boxes, centres}, topOptions);
    // Top's node -> the full tree's, its box and its collapse entry: kept by top index, so that making
    // a node reads its children's from here (near, in top's depth-first order) rather than from the
    // full tree, where they lie anywhere (a cache miss each: 2-3% of a bunny build with F = 4). The box
    // is the union of the children's, as the full tree's other inner nodes have it: sah-binned's own
    // box of the node has the same value, but min and max of -0 and +0 depend on the order of the
    // operands, so its zeros may carry other signs (makeLargeMesh's tree changed bits that way).
    detail::ScratchVector<uint32_t> made(top.nodes.size());
    detail::ScratchVector<Aabb> madeBox(top.nodes.size());
    detail::ScratchVector<detail::CollapseInfo> madeInfo(top.nodes.size());
    // Depth-first, children made first; `next` is one past the index the next made node takes.
    auto walk = [&](uint32_t from, uint32_t next) {
      std::vector<std::pair<uint32_t, bool>> stack{{from, false}};  // (node, children made)
      while (!stack.empty()) {
        const auto [i, childrenMade] = stack.back();
        stack.pop_back();
        const BvhNode& t = top.nodes[i];
        if (t.isLeaf()) {
          const uint32_t c = top.primIndices[t.first];
          made[i] = clusters.node[c];
          madeBox[i] = clusters.bounds(c);
          madeInfo[i] = clusters.info[c];
        } else if (!childrenMade) {
          stack.push_back({i, true});
          stack.push_back({t.right, false});
          stack.push_back({t.left, false});
        } else {
          Aabb box = madeBox[t.left];
          box.grow(madeBox[t.right]);
          made[i] = --next;
          madeBox[i] = box;
          madeInfo[i] = makeInner(made[i], made[t.left], made[t.right], box, madeInfo[t.left], madeInfo[t.right]);
        }
      }
    };
    // The same walk in parts, with the same numbering: the subtrees of at most m / 16 clusters met
    // first from the root (the parts) are walked as jobs, each starting from the index the whole walk
    // would give it, then the nodes above them, children first. A subtree of k clusters (one per
    // leaf: leaf size 1) makes k - 1 inner nodes. Parts depend on m only: the same tree for any
    // thread count. (Children follow their parent in top.nodes, so one backward pass counts.)
    detail::ScratchVector<uint32_t> clustersBelow(top.nodes.size());
    for (size_t i = top.nodes.size(); i-- > 0;) {
      const BvhNode& t = top.nodes[i];
      clustersBelow[i] = t.isLeaf() ? t.count : clustersBelow[t.left] + clustersBelow[t.right];
    }
    const uint32_t partMax = std::max(1u, m / 16);
    std::vector<uint32_t> parts, partNext, above;  // `above`: the other inner nodes, children first
    {
      uint32_t next = m - 1;
      std::vector<std::pair<uint32_t, bool>> stack{{0u, false}};
      while (!stack.empty()) {
        const auto [i, childrenMade] = stack.back();
        stack.pop_back();
        const BvhNode& t = top.nodes[i];
        if (t.isLeaf() || clustersBelow[i] <= partMax) {
          parts.push_back(i), partNext.push_back(next);
          next -= clustersBelow[i] - 1;
        } else if (!childrenMade) {
          stack.push_back({i, true});
          stack.push_back({t.right, false});
          stack.push_back({t.left, false});
        } else {
          made[i] = --next;
          above.push_back(i);
        }
      }
    }
    std::vector<uint32_t> order(parts.size());
    for (uint32_t k = 0; k < order.size(); ++k) order[k] = k;
    std::stable_sort(order.begin(), order.end(),
                     [&](uint32_t a, uint32_t b) { return clustersBelow[parts[a]] > clustersBelow[parts[b]]; });
    detail::runJobs(parts.size(), threads, [&](size_t k) { walk(parts[k], partNext[k]); }, order);
    for (const uint32_t i : above) {
      const BvhNode& t = top.nodes[i];
      Aabb box = madeBox[t.left];
      box.grow(madeBox[t.right]);
      madeBox[i] = box;
      madeInfo[i] = makeInner(made[i], made[t.left], made[t.right], box, madeInfo[t.left], madeInfo[t.right]);
    }
  }

  // 3. Leaves.
  return detail::emitCollapsed([&](uint32_t i) -> const BvhNode& { return full[i].node; },
                               [&](uint32_t i) -> detail::CollapseInfo& { return full[i].info; });
}

}  // namespace bvhlab
