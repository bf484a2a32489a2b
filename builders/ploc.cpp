// PLOC (Meister & Bittner 2018, "Parallel Locally-Ordered Clustering for Bounding Volume Hierarchy
// Construction", IEEE TVCG 24(3)): bottom-up agglomerative clustering along the Morton curve.
//  1. Centroids quantised to a 2^21 grid over their bounds and interleaved into 63-bit Morton codes
//     (as lbvh does), radix-sorted. Primitives with equal codes (coincident centroids to 2^-21 of the
//     extent) cannot be told apart by position: each such run starts as one cluster, a balanced tree
//     over the run (what lbvh does with equal codes; clustering nested boxes of one centre would
//     chain them into a list).
//  2. Repeat until one cluster is left: every cluster finds its nearest neighbour -- the one whose
//     merged box has the smallest area -- among the clusters within +-radius in the current order;
//     mutual nearest neighbours merge (the merged cluster takes the lower position, the order is kept)
//     and the array is compacted.
//  3. The single-primitive-leaf tree is collapsed by SAH (builders/collapse.hpp, shared with lbvh).
// Ties in the merged area are broken by a key of the pair alone (distance in the order, then the
// lower position's parity, then the lower position), so the smallest pair in the window is always
// mutual (at least one merge per iteration) and equal boxes pair up (2k, 2k+1) instead of chaining.
// The search runs in fixed chunks of the order on threads; every cluster's neighbour is a function
// of the clusters alone, so the tree is the same for any thread count.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

// BVHLAB_NO_SIMD forces the portable path (same float operations in the same order: same trees).
#if defined(__SSE2__) && !defined(BVHLAB_NO_SIMD)
#define BVHLAB_PLOC_SSE 1
#include <emmintrin.h>
#endif

#include "builders/build_util.hpp"
#include "builders/collapse.hpp"

namespace bvhlab {

namespace {

constexpr int kBitsPerAxis = 21;  // 3 * 21 = 63 bits in a 64-bit code
// The CLI's range too (app/, render/, experiments/): the search costs O(radius) per cluster and pass.
constexpr uint32_t kMaxRadius = 1024;
// Clusters per search job. Fixed (never derived from the thread count); chunks only split the work,
// each cluster's result does not depend on them. Each job rescans the radius clusters before it.
constexpr uint32_t kChunk = 8192;
constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();

// Spreads the low 21 bits of v so that bit i lands at bit 3i (lbvh.cpp's code layout).
uint64_t spreadBits(uint64_t v) {
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffULL;
  v = (v | v << 16) & 0x1f0000ff0000ffULL;
  v = (v | v << 8) & 0x100f00f00f00f00fULL;
  v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
  v = (v | v << 2) & 0x1249249249249249ULL;
  return v;
}

struct Keyed {
  uint64_t code;
  uint32_t id;
};

// LSD radix sort on the code, 8 bits per pass; stable, so equal codes keep their input order.
// Passes whose digit is the same for every key are skipped.
void radixSort(std::vector<Keyed>& keys) {
  std::vector<Keyed> other(keys.size());
  for (int shift = 0; shift < 64; shift += 8) {
    std::array<size_t, 256> count{};
    for (const Keyed& k : keys) ++count[(k.code >> shift) & 0xff];
    if (count[(keys[0].code >> shift) & 0xff] == keys.size()) continue;
    size_t sum = 0;
    for (size_t& c : count) sum += std::exchange(c, sum);
    for (const Keyed& k : keys) other[count[(k.code >> shift) & 0xff]++] = k;
    keys.swap(other);
  }
}

// The current clusters in order, structure of arrays (the search reads four neighbours at a time):
// box[0..2] min x/y/z, box[3..5] max x/y/z, node = the cluster's node in the full tree. Padded by 4
// so a 4-wide load past the last cluster stays inside the arrays (those lanes are masked).
struct Clusters {
  std::vector<float> box[6];
  std::vector<uint32_t> node;
  void resize(size_t m) {
    for (auto& b : box) b.assign(m + 4, 0.0f);
    node.resize(m + 4);
  }
  Aabb bounds(uint32_t i) const {
    return {{box[0][i], box[1][i], box[2][i]}, {box[3][i], box[4][i], box[5][i]}};
  }
  void set(uint32_t i, const Aabb& b, uint32_t n) {
    for (int a = 0; a < 3; ++a) box[a][i] = b.min[a], box[3 + a][i] = b.max[a];
    node[i] = n;
  }
};

// Orders the candidates of cluster x that tie on merged area by a key of the pair {x, j} alone
// (distance, parity of the lower position, the lower position), so both ends of a pair rank it alike.
uint64_t tieKey(uint32_t x, uint32_t j) {
  const uint64_t d = x > j ? x - j : j - x, lower = std::min(x, j);
  return 4 * d + 2 * (lower & 1) + (j > x ? 1 : 0);
}

// Scratch for one search job: the best candidate so far of each cluster in [base, base + size),
// from clusters before it (the "backward" half of its window).
struct Scratch {
  std::vector<float> area;
  std::vector<uint32_t> index;
};

// Cluster i against its forward window (i, i + count]: returns i's best forward candidate (smallest
// area, ties to the nearest), and offers i to each of those clusters' backward best (ties to the
// nearest: candidates arrive in increasing i, so equal areas replace). Merged half areas are
// computed as Aabb::halfArea does, (ex*ey + ey*ez) + ez*ex; inputs are finite and validated to a
// finite scene area, so every area here is finite and no NaN reaches a comparison.
void scanForward(const Clusters& c, uint32_t i, uint32_t count, uint32_t base, Scratch& s, float& bestArea,
                 uint32_t& bestIndex) {
  float* backArea = s.area.data() - base;
  uint32_t* backIndex = s.index.data() - base;
#if defined(BVHLAB_PLOC_SSE)
  const __m128 lx = _mm_set1_ps(c.box[0][i]), ly = _mm_set1_ps(c.box[1][i]), lz = _mm_set1_ps(c.box[2][i]);
  const __m128 hx = _mm_set1_ps(c.box[3][i]), hy = _mm_set1_ps(c.box[4][i]), hz = _mm_set1_ps(c.box[5][i]);
  const __m128i self = _mm_set1_epi32(int32_t(i)), limit = _mm_set1_epi32(int32_t(count)), four = _mm_set1_epi32(4);
  __m128i k = _mm_setr_epi32(0, 1, 2, 3);  // offset - 1 of each lane: j = i + 1 + k (count <= kMaxRadius)
  __m128i lane = _mm_setr_epi32(int32_t(i + 1), int32_t(i + 2), int32_t(i + 3), int32_t(i + 4));
  __m128 vArea = _mm_set1_ps(kInf);
  __m128i vIndex = _mm_set1_epi32(-1);
  auto select = [](__m128 mask, __m128 a, __m128 b) { return _mm_or_ps(_mm_and_ps(mask, a), _mm_andnot_ps(mask, b)); };
  for (uint32_t j = i + 1, end = i + 1 + count; j < end; j += 4) {
    const __m128 ex = _mm_sub_ps(_mm_max_ps(hx, _mm_loadu_ps(&c.box[3][j])), _mm_min_ps(lx, _mm_loadu_ps(&c.box[0][j])));
    const __m128 ey = _mm_sub_ps(_mm_max_ps(hy, _mm_loadu_ps(&c.box[4][j])), _mm_min_ps(ly, _mm_loadu_ps(&c.box[1][j])));
    const __m128 ez = _mm_sub_ps(_mm_max_ps(hz, _mm_loadu_ps(&c.box[5][j])), _mm_min_ps(lz, _mm_loadu_ps(&c.box[2][j])));
    const __m128 area = _mm_add_ps(_mm_add_ps(_mm_mul_ps(ex, ey), _mm_mul_ps(ey, ez)), _mm_mul_ps(ez, ex));
    const __m128 valid = _mm_castsi128_ps(_mm_cmplt_epi32(k, limit));
    const __m128 better = _mm_and_ps(valid, _mm_cmplt_ps(area, vArea));
    vArea = select(better, area, vArea);
    vIndex = _mm_castps_si128(select(better, _mm_castsi128_ps(lane), _mm_castsi128_ps(vIndex)));
    const __m128 back = _mm_loadu_ps(&backArea[j]);
    const __m128i backI = _mm_loadu_si128(reinterpret_cast<const __m128i*>(&backIndex[j]));
    const __m128 replace = _mm_and_ps(valid, _mm_cmple_ps(area, back));
    _mm_storeu_ps(&backArea[j], select(replace, area, back));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(&backIndex[j]),
                     _mm_castps_si128(select(replace, _mm_castsi128_ps(self), _mm_castsi128_ps(backI))));
    k = _mm_add_epi32(k, four);
    lane = _mm_add_epi32(lane, four);
  }
  alignas(16) float areas[4];
  alignas(16) uint32_t indices[4];
  _mm_store_ps(areas, vArea);
  _mm_store_si128(reinterpret_cast<__m128i*>(indices), vIndex);
  bestArea = kInf, bestIndex = kNone;
  for (int l = 0; l < 4; ++l)  // each lane kept its nearest among equals: the nearest overall wins
    if (areas[l] < bestArea || (areas[l] == bestArea && indices[l] < bestIndex)) bestArea = areas[l], bestIndex = indices[l];
#else
  bestArea = kInf, bestIndex = kNone;
  for (uint32_t j = i + 1, end = i + 1 + count; j < end; ++j) {
    const float ex = std::max(c.box[3][i], c.box[3][j]) - std::min(c.box[0][i], c.box[0][j]);
    const float ey = std::max(c.box[4][i], c.box[4][j]) - std::min(c.box[1][i], c.box[1][j]);
    const float ez = std::max(c.box[5][i], c.box[5][j]) - std::min(c.box[2][i], c.box[2][j]);
    const float area = (ex * ey + ey * ez) + ez * ex;
    if (area < bestArea) bestArea = area, bestIndex = j;
    if (area <= backArea[j]) backArea[j] = area, backIndex[j] = i;
  }
#endif
}

// Nearest neighbour of each cluster in [a, b) among the m clusters, into nn[a, b).
void nearestNeighbours(const Clusters& c, uint32_t m, uint32_t radius, uint32_t a, uint32_t b, uint32_t* nn,
                       Scratch& s) {
  const uint32_t base = a - std::min(a, radius);
  // Backward bests of [base, b + radius), padded for the 4-wide stores past it.
  const size_t size = size_t(b - base) + radius + 4;
  s.area.assign(size, kInf);
  s.index.assign(size, kNone);
  for (uint32_t i = base; i < b; ++i) {
    float forwardArea;
    uint32_t forward;
    scanForward(c, i, std::min(radius, m - 1 - i), base, s, forwardArea, forward);
    if (i < a) continue;  // scanned only to offer itself to [a, b)
    const float backArea = s.area[i - base];
    const uint32_t back = s.index[i - base];
    // m >= 2, so one side is finite; equal areas are then both finite.
    nn[i] = forwardArea < backArea || (forwardArea == backArea && tieKey(i, forward) < tieKey(i, back)) ? forward
                                                                                                      : back;
  }
}

}  // namespace

Bvh buildPloc(const BuildInput& input, const BuildOptions& options) {
  const uint32_t radius = options.plocRadius;
  if (radius < 1 || radius > kMaxRadius)
    throw std::invalid_argument("ploc: plocRadius " + std::to_string(radius) + " is outside 1.." +
                                std::to_string(kMaxRadius));
  const uint32_t n = uint32_t(input.boxes.size());
  const unsigned threads = detail::resolveThreads(options.threads);
  const uint32_t jobs = (n + kChunk - 1) / kChunk;

  // 1. Morton order.
  Aabb centroidBounds;
  for (const glm::vec3& c : input.centroids) centroidBounds.grow(c);
  // Grid scale per axis; a zero (or denormal, 2^21 / extent overflowing) extent maps to cell 0.
  // Inputs are finite and c >= min, so every product below is finite and >= 0.
  const float cells = float(1 << kBitsPerAxis);
  glm::vec3 scale(0.0f);
  for (int a = 0; a < 3; ++a) {
    const float extent = centroidBounds.max[a] - centroidBounds.min[a];
    const float s = cells / extent;
    if (extent > 0.0f && std::isfinite(s)) scale[a] = s;
  }
  std::vector<Keyed> keys(n);
  detail::runJobs(jobs, threads, [&](size_t job) {
    for (uint32_t i = uint32_t(job) * kChunk, end = std::min(n, i + kChunk); i < end; ++i) {
      const glm::vec3 q = glm::min((input.centroids[i] - centroidBounds.min) * scale, glm::vec3(cells - 1.0f));
      keys[i] = {spreadBits(uint64_t(q.x)) << 2 | spreadBits(uint64_t(q.y)) << 1 | spreadBits(uint64_t(q.z)), i};
    }
  });
  radixSort(keys);

  // The full tree: leaves at n - 1 + (Morton position), inner nodes numbered downwards from n - 2 as
  // they are made, so a parent (made after its children) has a smaller index and the root ends at 0.
  std::vector<BvhNode> full(2 * size_t(n) - 1);
  for (uint32_t k = 0; k < n; ++k) {
    BvhNode& leaf = full[n - 1 + k];
    leaf.bounds = input.boxes[keys[k].id];
    leaf.first = keys[k].id;
    leaf.count = 1;
  }
  uint32_t nextInner = n - 1;  // one past the next inner node's index
  auto makeInner = [&](uint32_t left, uint32_t right) {
    const uint32_t index = --nextInner;
    BvhNode& node = full[index];
    node.bounds = full[left].bounds;
    node.bounds.grow(full[right].bounds);
    node.left = left;
    node.right = right;
    return index;
  };

  // Initial clusters: single primitives, and one balanced tree per run of equal codes.
  Clusters clusters, next;
  clusters.resize(n);
  next.resize(n);
  uint32_t m = 0;
  std::vector<uint32_t> level;
  for (uint32_t k = 0; k < n;) {
    uint32_t end = k + 1;
    while (end < n && keys[end].code == keys[k].code) ++end;
    level.clear();
    for (uint32_t p = k; p < end; ++p) level.push_back(n - 1 + p);
    while (level.size() > 1) {  // pair neighbours level by level: depth ceil(log2 run)
      size_t w = 0;
      for (size_t p = 0; p + 1 < level.size(); p += 2) level[w++] = makeInner(level[p], level[p + 1]);
      if (level.size() % 2) level[w++] = level.back();
      level.resize(w);
    }
    clusters.set(m++, full[level[0]].bounds, level[0]);
    k = end;
  }

  // 2. Cluster.
  std::vector<uint32_t> nn(n);
  std::vector<Scratch> scratch(jobs);
  while (m > 1) {
    const uint32_t chunks = (m + kChunk - 1) / kChunk;
    detail::runJobs(chunks, threads, [&](size_t job) {
      const uint32_t a = uint32_t(job) * kChunk, b = std::min(m, a + kChunk);
      nearestNeighbours(clusters, m, radius, a, b, nn.data(), scratch[job]);
    });
    uint32_t w = 0;
    for (uint32_t i = 0; i < m; ++i) {
      const uint32_t j = nn[i];
      if (nn[j] != i) {  // no merge this pass: keep it
        for (int a = 0; a < 6; ++a) next.box[a][w] = clusters.box[a][i];
        next.node[w++] = clusters.node[i];
      } else if (i < j) {  // mutual: merged at the lower position
        const uint32_t node = makeInner(clusters.node[i], clusters.node[j]);
        next.set(w++, full[node].bounds, node);
      }
    }
    std::swap(clusters, next);
    m = w;
  }

  // 3. Leaves.
  return detail::collapseLeavesBySah(full, options);
}

}  // namespace bvhlab
