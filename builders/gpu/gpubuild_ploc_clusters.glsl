// ploc-gpu, clusters phase 2: one invocation per run of equal Morton codes builds the run's balanced
// tree as builders/ploc.cpp does: neighbours paired level by level (positions 2k, 2k + 1 of a level;
// an odd last one goes up alone), inner nodes numbered downwards in that order from n - 1 - (inner
// nodes of the runs before: the run's first position minus its number). Level l's items are the
// groups of 2^l consecutive positions of the run (the last one possibly shorter); the node of the
// group starting at p is kept in slots[p]. The run's root becomes cluster (its number).
layout(local_size_x = 256) in;
struct Key { uint hi, lo, id; };
struct Cluster { float box[6]; uint node; };
layout(std430, binding = 0) readonly buffer Keys { Key keys[]; };
layout(std430, binding = 1) coherent buffer NodeBoxes { float nodeBoxes[]; };
layout(std430, binding = 2) writeonly buffer Children { uint children[]; };  // left, right per inner node
layout(std430, binding = 3) writeonly buffer Parents { uint parents[]; };
layout(std430, binding = 4) buffer Slots { uint slots[]; };
layout(std430, binding = 5) readonly buffer Sums { uint sums[]; };  // scanned run counts per block
layout(std430, binding = 6) writeonly buffer Clusters { Cluster clusters[]; };
uniform uint u_count;

shared uint s_scan[256];

bool sameCode(uint a, uint b) { return keys[a].hi == keys[b].hi && keys[a].lo == keys[b].lo; }

// Inner node `node` over children l and r, its box the union as Aabb::grow makes it (glm's min and
// max: b < a ? b : a, a < b ? b : a).
void makeInner(uint node, uint l, uint r) {
  for (uint c = 0u; c < 3u; ++c) {
    float a = nodeBoxes[6u * l + c], b = nodeBoxes[6u * r + c];
    nodeBoxes[6u * node + c] = b < a ? b : a;
    a = nodeBoxes[6u * l + 3u + c], b = nodeBoxes[6u * r + 3u + c];
    nodeBoxes[6u * node + 3u + c] = a < b ? b : a;
  }
  children[2u * node] = l;
  children[2u * node + 1u] = r;
  parents[l] = node;
  parents[r] = node;
}

void main() {
  uint t = gl_LocalInvocationID.x, k = gl_GlobalInvocationID.x, n = u_count;
  bool start = k < n && (k == 0u || !sameCode(k, k - 1u));
  // The run's number: the runs starting before it (scanned per block, then within the block).
  uint mine = start ? 1u : 0u;
  s_scan[t] = mine;
  barrier();
  for (uint step = 1u; step < 256u; step <<= 1u) {
    uint add = t >= step ? s_scan[t - step] : 0u;
    barrier();
    s_scan[t] += add;
    barrier();
  }
  if (!start) return;
  uint run = sums[gl_WorkGroupID.x] + s_scan[t] - mine;
  uint end = k + 1u;
  while (end < n && sameCode(end, k)) ++end;
  uint next = n - 1u - (k - run);  // one past the index of the next inner node
  for (uint p = k; p < end; ++p) slots[p] = n - 1u + p;
  for (uint width = 1u; width < end - k; width *= 2u)
    for (uint p = k; p + width < end; p += 2u * width) {
      --next;
      makeInner(next, slots[p], slots[p + width]);
      slots[p] = next;
    }
  uint root = slots[k];
  for (uint c = 0u; c < 6u; ++c) clusters[run].box[c] = nodeBoxes[6u * root + c];
  clusters[run].node = root;
}
