// Sorting Morton-coded keys (builders/morton_sort.hpp): LSD radix sort, 8 bits per pass.
#include "builders/morton_sort.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <utility>
#include <vector>

#include "builders/build_util.hpp"

namespace bvhlab::detail {

namespace {

// Keys per job of a pass. Fixed (never derived from the thread count): jobs only split the work.
constexpr size_t kChunk = 8192;

void radixSortParts(ScratchVector<Keyed>& keys, unsigned threads);
void radixSortRange(Keyed* keys, Keyed* other, size_t begin, size_t end, int top);

}  // namespace

// LSD radix sort on the code, 8 bits per pass; stable, so equal codes keep their input order (and
// the order is unique: chunks and threads only split the work). Per pass, each chunk of kChunk keys
// counts its digits, the counts become offsets (digit-major, chunk-minor), and each chunk scatters
// its keys. Passes whose digit is the same for every key are skipped. One thread sorts the whole
// range with one counter array per pass. Below 16 chunks (131072 keys)
// a pass is too short for thread starts (tens of microseconds each, two per pass), so with several
// threads the keys are first split by their highest varying digit (one stable scatter), and each
// part is then sorted on the lower digits as its own job (radixSortParts): one thread start per sort.
// The result is the same either way: the stable order by code.
void sortMortonKeys(ScratchVector<Keyed>& keys, unsigned threads) {
  const size_t n = keys.size(), chunks = (n + kChunk - 1) / kChunk;
  if (threads <= 1 || n < 2) {  // one range, one counter array per pass
    ScratchVector<Keyed> other(n);
    return radixSortRange(keys.data(), other.data(), 0, n, 64);
  }
  if (chunks < 16) return radixSortParts(keys, threads);
  ScratchVector<Keyed> other(n);
  std::vector<std::array<uint32_t, 256>> count(chunks);
  for (int shift = 0; shift < 64; shift += 8) {
    auto digit = [shift](const Keyed& k) { return (k.code >> shift) & 0xff; };
    runJobs(chunks, threads, [&](size_t c) {
      count[c].fill(0);
      for (size_t i = c * kChunk, end = std::min(n, i + kChunk); i < end; ++i) ++count[c][digit(keys[i])];
    });
    size_t first = 0;  // keys with the first key's digit
    for (const auto& chunk : count) first += chunk[digit(keys[0])];
    if (first == n) continue;
    uint32_t sum = 0;
    for (size_t d = 0; d < 256; ++d)
      for (auto& chunk : count) sum += std::exchange(chunk[d], sum);
    runJobs(chunks, threads, [&](size_t c) {
      for (size_t i = c * kChunk, end = std::min(n, i + kChunk); i < end; ++i) other[count[c][digit(keys[i])]++] = keys[i];
    });
    keys.swap(other);
  }
}

namespace {

// Stable LSD passes over the digits below `top` (a multiple of 8) of keys[begin, end), with
// other[begin, end) as the second buffer; the sorted part ends in keys.
void radixSortRange(Keyed* keys, Keyed* other, size_t begin, size_t end, int top) {
  const size_t n = end - begin;
  if (n < 64) {  // a stable sort by code is the sort by (code, input index): ids rise in input order
    std::sort(keys + begin, keys + end,
              [](const Keyed& a, const Keyed& b) { return a.code < b.code || (a.code == b.code && a.id < b.id); });
    return;
  }
  Keyed *from = keys + begin, *to = other + begin;
  for (int shift = 0; shift < top; shift += 8) {
    auto digit = [shift](const Keyed& k) { return uint32_t(k.code >> shift) & 0xff; };
    std::array<uint32_t, 256> count{};
    for (size_t i = 0; i < n; ++i) ++count[digit(from[i])];
    if (count[digit(from[0])] == n) continue;
    uint32_t sum = 0;
    for (uint32_t& c : count) sum += std::exchange(c, sum);
    for (size_t i = 0; i < n; ++i) to[count[digit(from[i])]++] = from[i];
    std::swap(from, to);
  }
  if (from != keys + begin) std::copy(from, from + n, keys + begin);
}

void radixSortParts(ScratchVector<Keyed>& keys, unsigned threads) {
  const size_t n = keys.size();
  uint64_t varying = 0;
  for (size_t i = 1; i < n; ++i) varying |= keys[i].code ^ keys[0].code;
  if (varying == 0) return;  // one code: already in input order
  const int shift = (63 - std::countl_zero(varying)) / 8 * 8;  // the highest digit that varies
  auto digit = [shift](const Keyed& k) { return uint32_t(k.code >> shift) & 0xff; };
  std::array<uint32_t, 257> start{};
  for (size_t i = 0; i < n; ++i) ++start[digit(keys[i]) + 1];
  for (size_t d = 1; d <= 256; ++d) start[d] += start[d - 1];
  ScratchVector<Keyed> other(n);
  {
    std::array<uint32_t, 256> at;
    std::copy_n(start.begin(), 256, at.begin());
    for (size_t i = 0; i < n; ++i) other[at[digit(keys[i])]++] = keys[i];
  }
  keys.swap(other);  // split by the top digit; `other` is the second buffer of every part
  std::vector<uint32_t> parts, order;
  for (uint32_t d = 0; d < 256; ++d)
    if (start[d + 1] > start[d]) parts.push_back(d);
  for (uint32_t k = 0; k < parts.size(); ++k) order.push_back(k);
  std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {  // biggest first
    return start[parts[a] + 1] - start[parts[a]] > start[parts[b] + 1] - start[parts[b]];
  });
  runJobs(
      parts.size(), threads,
      [&](size_t k) { radixSortRange(keys.data(), other.data(), start[parts[k]], start[parts[k] + 1], shift); },
      order);
}

}  // namespace

}  // namespace bvhlab::detail
