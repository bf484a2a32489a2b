// One side of ab_revisions.sh's comparison: compiled once per side with -Dbvhlab=bvhlabA (or B) and
// -DAB_SIDE=abBuildA (or B), next to that side's copy of builders/*.cpp compiled the same way, so
// that two versions of the builders live in one process under different namespaces. Builds with the
// named builder and returns the time of the build alone (thread CPU time, or wall time with `wall`)
// and, if asked, a hash of the tree (boxes, children, leaf ranges, primitive order).
#include <cstdint>
#include <cstring>
#include <ctime>

#include "builders/builder.hpp"

extern "C" double AB_SIDE(const char* builder, const void* input, const void* options, bool wall, uint64_t* hash) {
  const bvhlab::BuilderInfo& info = bvhlab::findBuilder(builder);
  const clockid_t clock = wall ? CLOCK_MONOTONIC : CLOCK_THREAD_CPUTIME_ID;
  timespec start, stop;
  clock_gettime(clock, &start);
  const bvhlab::Bvh bvh = info.build(*static_cast<const bvhlab::BuildInput*>(input),
                                     *static_cast<const bvhlab::BuildOptions*>(options));
  clock_gettime(clock, &stop);
  if (hash) {  // FNV-1a over the fields a tree is (not the padding)
    uint64_t h = 1469598103934665603ull;
    auto mix = [&h](const void* p, size_t bytes) {
      for (size_t k = 0; k < bytes; ++k) h = (h ^ static_cast<const unsigned char*>(p)[k]) * 1099511628211ull;
    };
    for (const bvhlab::BvhNode& node : bvh.nodes) {
      mix(&node.bounds, sizeof node.bounds);
      mix(&node.left, sizeof node.left), mix(&node.right, sizeof node.right);
      mix(&node.first, sizeof node.first), mix(&node.count, sizeof node.count);
    }
    mix(bvh.primIndices.data(), bvh.primIndices.size() * sizeof(uint32_t));
    *hash = h;
  }
  return double(stop.tv_sec - start.tv_sec) * 1e3 + double(stop.tv_nsec - start.tv_nsec) * 1e-6;
}
