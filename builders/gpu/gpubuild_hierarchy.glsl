// lbvh-gpu, hierarchy phase 2: Karras 2012 ("Maximizing Parallelism in the Construction of BVHs,
// Octrees, and k-d Trees", HPG 2012): inner node i of the n - 1 finds its range (one end at i, the
// direction from its neighbours' common prefixes) and its split by binary searches over delta, the
// common prefix length of two sorted keys (code, then label: gpubuild_labels.glsl). Node ids: inner
// node k is k, leaf k (sorted position k) is n - 1 + k; the root is inner node 0.
layout(local_size_x = 256) in;
struct Key { uint hi, lo, id; };
layout(std430, binding = 0) readonly buffer Keys { Key keys[]; };
layout(std430, binding = 1) readonly buffer Labels { uint labels[]; };
layout(std430, binding = 2) writeonly buffer Children { uint children[]; };  // left, right per inner node
layout(std430, binding = 3) writeonly buffer Parents { uint parents[]; };    // per node; root: ~0
uniform uint u_count;

int delta(int i, int j) {
  if (j < 0 || j >= int(u_count)) return -1;
  uint x = keys[i].hi ^ keys[j].hi;
  if (x != 0u) return 31 - findMSB(x);
  x = keys[i].lo ^ keys[j].lo;
  if (x != 0u) return 63 - findMSB(x);
  return 95 - findMSB(labels[i] ^ labels[j]);  // equal codes: distinct labels
}

void main() {
  int n = int(u_count), i = int(gl_GlobalInvocationID.x);
  if (i >= n - 1) return;
  int d = delta(i, i + 1) > delta(i, i - 1) ? 1 : -1;  // never equal: the keys are distinct
  int dmin = delta(i, i - d);
  int lmax = 2;
  while (delta(i, i + lmax * d) > dmin) lmax *= 2;
  int l = 0;
  for (int t = lmax / 2; t >= 1; t /= 2)
    if (delta(i, i + (l + t) * d) > dmin) l += t;
  int j = i + l * d;
  int dnode = delta(i, j);
  int s = 0;
  for (int div = 2;; div *= 2) {
    int t = (l + div - 1) / div;
    if (delta(i, i + (s + t) * d) > dnode) s += t;
    if (t <= 1) break;
  }
  int gamma = i + s * d + min(d, 0);
  uint left = min(i, j) == gamma ? uint(n - 1 + gamma) : uint(gamma);
  uint right = max(i, j) == gamma + 1 ? uint(n + gamma) : uint(gamma + 1);
  children[2 * i] = left;
  children[2 * i + 1] = right;
  parents[left] = uint(i);
  parents[right] = uint(i);
}
