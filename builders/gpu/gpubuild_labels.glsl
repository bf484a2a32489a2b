// lbvh-gpu, hierarchy phase 1: a label per sorted key that makes Karras's radix tree split a run of
// equal codes where the CPU lbvh splits it: in the middle (builders/lbvh.cpp; left half floor(m/2)).
// The label of position k in a run of m equal codes is its path in that middle-split tree (1 = right),
// ceil(log2 m) bits, padded with zeros below a leaf that is less deep: labels rise along the run and
// the highest bit in which two of them differ is the level where the middle splits part them, so the
// radix tree over (code, label) splits every equal-code range as the CPU does. A key alone in its run
// gets label 0 (it is never compared with an equal code).
layout(local_size_x = 256) in;
struct Key { uint hi, lo, id; };
layout(std430, binding = 0) readonly buffer Keys { Key keys[]; };
layout(std430, binding = 1) writeonly buffer Labels { uint labels[]; };
uniform uint u_count;

bool less(uvec2 a, uvec2 b) { return a.x < b.x || (a.x == b.x && a.y < b.y); }
uvec2 codeAt(uint i) { return uvec2(keys[i].hi, keys[i].lo); }

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= u_count) return;
  uvec2 c = codeAt(i);
  bool alone = (i == 0u || codeAt(i - 1u) != c) && (i + 1u == u_count || codeAt(i + 1u) != c);
  if (alone) { labels[i] = 0u; return; }
  uint lo = 0u, hi = i;  // the run's first position: the first code not below c
  while (lo < hi) {
    uint mid = lo + (hi - lo) / 2u;
    if (less(codeAt(mid), c)) lo = mid + 1u; else hi = mid;
  }
  uint first = lo;
  lo = i + 1u, hi = u_count;  // one past the run: the first code above c
  while (lo < hi) {
    uint mid = lo + (hi - lo) / 2u;
    if (less(c, codeAt(mid))) hi = mid; else lo = mid + 1u;
  }
  uint m = lo - first, k = i - first;
  uint levels = uint(findMSB(m - 1u)) + 1u;  // ceil(log2 m), m >= 2
  uint label = 0u, b = 0u, e = m;
  for (uint level = 0u; level < levels; ++level) {
    label <<= 1u;
    if (e - b > 1u) {
      uint mid = b + (e - b) / 2u;
      if (k >= mid) { label |= 1u; b = mid; } else e = mid;
    }
  }
  labels[i] = label;
}
