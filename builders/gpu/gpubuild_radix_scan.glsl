// Stable LSD radix sort, step 2 of 3 per digit: one workgroup per digit turns that digit's counts
// (counts[digit * blocks + block], contiguous per digit, as gpubuild_radix_hist.glsl writes them)
// into exclusive offsets within the digit, 256 blocks at a time (gpubuild_workgroup_scan.glsl plus
// the running total of the earlier chunks), and writes the digit's total after the 256 x blocks counts.
// The scatter adds the digits' own exclusive scan of those 256 totals. The 256 workgroups run at
// once, each reading its row in order; one workgroup over all 256 x blocks counts would leave each
// invocation a strided segment of `blocks` reads to walk alone (2,442 per pass for 10M keys).
layout(local_size_x = 256) in;
layout(std430, binding = 1) buffer Counts { uint counts[]; };  // 256 x blocks counts, then 256 totals
uniform uint u_blocks;

void main() {
  uint t = gl_LocalInvocationID.x, digit = gl_WorkGroupID.x;
  uint row = digit * u_blocks;
  uint carry = 0u;  // the digit's keys in the blocks of the earlier chunks
  for (uint chunk = 0u; chunk < u_blocks; chunk += 256u) {
    uint i = chunk + t;
    uint chunkTotal;
    uint before = workgroupExclusiveSum(t, i < u_blocks ? counts[row + i] : 0u, chunkTotal);
    if (i < u_blocks) counts[row + i] = carry + before;
    carry += chunkTotal;
  }
  if (t == 0u) counts[256u * u_blocks + digit] = carry;
}
