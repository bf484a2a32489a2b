// Stable LSD radix sort of (63-bit code, index) keys, 8-bit digits, step 1 of 3 per digit: each
// workgroup counts the digits of its block of 4096 keys; the counts go digit-major, block-minor
// (counts[digit * blocks + block]), so their exclusive prefix sum is every block's first slot per digit.
layout(local_size_x = 256) in;
struct Key { uint hi, lo, id; };
layout(std430, binding = 0) readonly buffer Keys { Key keys[]; };
layout(std430, binding = 1) writeonly buffer Counts { uint counts[]; };
uniform uint u_count;
uniform uint u_shift;  // 0, 8, .., 56: the digit's lowest bit in the 64-bit code

const uint kBlock = 4096u;
shared uint s_count[256];

uint digitOf(Key k) { return (u_shift < 32u ? k.lo >> u_shift : k.hi >> (u_shift - 32u)) & 0xffu; }

void main() {
  uint t = gl_LocalInvocationID.x, block = gl_WorkGroupID.x, blocks = gl_NumWorkGroups.x;
  s_count[t] = 0u;
  barrier();
  for (uint j = t; j < kBlock; j += 256u) {
    uint i = block * kBlock + j;
    if (i < u_count) atomicAdd(s_count[digitOf(keys[i])], 1u);
  }
  barrier();
  counts[t * blocks + block] = s_count[t];
}
