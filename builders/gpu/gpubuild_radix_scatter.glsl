// Stable LSD radix sort, step 3 of 3 per digit: each workgroup moves its block's keys to their slots,
// in input order. The block goes in chunks of 256 keys, one per invocation; an invocation's rank
// among the chunk's keys of its digit is the number of lower invocations with that digit, counted
// from a bit mask per digit (one bit per invocation, popcounts). Earlier chunks' keys of each digit
// are counted in s_base, which starts at the digit's first slot (the exclusive scan of the 256 digit
// totals, gpubuild_workgroup_scan.glsl) plus the block's offset within the digit (gpubuild_radix_scan.glsl).
layout(local_size_x = 256) in;
struct Key { uint hi, lo, id; };
layout(std430, binding = 0) readonly buffer Keys { Key keys[]; };
// Per digit, its blocks' exclusive offsets within the digit; then the 256 digits' totals.
layout(std430, binding = 1) readonly buffer Offsets { uint offsets[]; };
layout(std430, binding = 2) writeonly buffer Sorted { Key sorted[]; };
uniform uint u_count;
uniform uint u_shift;

const uint kBlock = 4096u;
shared uint s_mask[256 * 8];
shared uint s_base[256];

uint digitOf(Key k) { return (u_shift < 32u ? k.lo >> u_shift : k.hi >> (u_shift - 32u)) & 0xffu; }

void main() {
  uint t = gl_LocalInvocationID.x, block = gl_WorkGroupID.x, blocks = gl_NumWorkGroups.x;
  uint allKeys;
  s_base[t] = workgroupExclusiveSum(t, offsets[256u * blocks + t], allKeys) + offsets[t * blocks + block];
  uint word = t >> 5u, below = (1u << (t & 31u)) - 1u;
  for (uint chunk = 0u; chunk < kBlock; chunk += 256u) {
    for (uint w = 0u; w < 8u; ++w) s_mask[t * 8u + w] = 0u;
    barrier();
    uint i = block * kBlock + chunk + t;
    bool live = i < u_count;
    Key k;
    uint d = 0u;
    if (live) {
      k = keys[i];
      d = digitOf(k);
      atomicOr(s_mask[d * 8u + word], 1u << (t & 31u));
    }
    barrier();
    uint rank = 0u, total = 0u;
    if (live) {
      for (uint w = 0u; w < 8u; ++w) {
        uint m = s_mask[d * 8u + w];
        total += bitCount(m);
        if (w < word) rank += bitCount(m);
      }
      rank += bitCount(s_mask[d * 8u + word] & below);
      sorted[s_base[d] + rank] = k;
    }
    barrier();
    if (live && rank + 1u == total) s_base[d] += total;  // the digit's last key in the chunk
    barrier();
  }
}
