// hploc-gpu, phase hierarchy: H-PLOC (builders/hploc.hpp) in one dispatch, the tree's nodes, boxes and
// links. One invocation per sorted position starts at its leaf and climbs the radix tree (Apetrei's
// test: the parent spans the boundary with the smaller key XOR); at each parent the first child to
// arrive leaves its other end in waiting[] and stops, the second goes on with the parent. A workgroup
// is one group of kGroup = 32 invocations (a warp on NVIDIA, as the paper's): after each climb its
// invocations cluster, one after another and all together, the subtrees that need it (more than
// kKeep primitives, or the root): the two children's cluster lists loaded one cluster per
// invocation, ploc's passes (gpubuild_ploc_pairs.glsl, compiled ahead of this module) until kKeep
// clusters are left (the root: one), the list written back at the subtree's first position. Every
// decision the workgroup takes together (who clusters, which clusters are kept and where they go) is
// a bit mask in shared memory (atomicOr, then bitCount: the paper's ballots) that every invocation
// reads, so barrier() stays in uniform control flow. (Loops over 32 shared flags instead made the
// dispatch about twice as long on llvmpipe: bunny, 2 cores, radius 1 and 16, interleaved builds.)
// The other subtrees are the climbing invocation's alone: a run of one Morton code becomes the radix
// tree's node over its two children (one cluster each), a small subtree's list the left child's
// followed by the right's.
// Inner nodes are numbered downwards from n - 2 by an atomic counter (a pass's merges take one block of
// numbers); the root's last merge is the build's last, so the root is node 0.
layout(local_size_x = 32) in;
struct Key { uint hi, lo, id; };
layout(std430, binding = 0) readonly buffer Keys { Key keys[]; };
layout(std430, binding = 1) readonly buffer Boxes { float boxes[]; };  // min xyz, max xyz per primitive
layout(std430, binding = 2) coherent buffer NodeBoxes { float nodeBoxes[]; };
layout(std430, binding = 3) writeonly buffer Children { uint children[]; };  // left, right per inner node
layout(std430, binding = 4) writeonly buffer Parents { uint parents[]; };    // per node; the root's is set
// lists[p]: a list's cluster (a node) at position p; lists[n + L]: the count of the list of the
// subtree that starts at L (1 for a leaf).
layout(std430, binding = 5) coherent buffer Lists { uint lists[]; };
// made: inner nodes made so far; waiting[s]: the other end of the child that reached the parent over
// boundary s first (~0u: none yet).
layout(std430, binding = 6) coherent buffer Waiting { uint made; uint waiting[]; };
uniform uint u_count;
uniform uint u_radius;

const uint kGroup = 32u, kKeep = 16u, kNone = 0xffffffffu;

// In three copies used by turns (iteration t writes copy t % 3 before its barrier and reads it after;
// invocation 0 clears copy (t + 2) % 3, last read before that barrier and next written after the
// following one): the invocations that cluster their subtree now and those still climbing, one bit
// each (atomicOr), and per invocation its subtree (first position, split, last position).
shared uint s_clusterBits[3], s_climbingBits[3];
shared uvec3 s_range[3][kGroup];
shared vec3 s_lo[kGroup], s_hi[kGroup];  // the list's clusters: box
shared uint s_node[kGroup];              // and node
shared uint s_nearest[kGroup];
// The positions kept and those that merge with their neighbour (kept too), one bit each (atomicOr);
// written between a pass's first and second barrier, read before its third, cleared after it.
shared uint s_keptBits, s_mergeBits;
shared uint s_made;          // the inner nodes made before this pass's merges

// The keys at i, i + 1 differ in a lower bit than those at j, j + 1: (code, position), code first.
bool deltaLess(uint i, uint j) {
  uvec3 a = uvec3(keys[i].hi ^ keys[i + 1u].hi, keys[i].lo ^ keys[i + 1u].lo, i ^ (i + 1u));
  uvec3 b = uvec3(keys[j].hi ^ keys[j + 1u].hi, keys[j].lo ^ keys[j + 1u].lo, j ^ (j + 1u));
  if (a.x != b.x) return a.x < b.x;
  if (a.y != b.y) return a.y < b.y;
  return a.z < b.z;
}

bool sameCode(uint i, uint j) { return keys[i].hi == keys[j].hi && keys[i].lo == keys[j].lo; }

// Inner node `node` over a (left) and b: boxes, links.
void makeInner(uint node, Cluster a, Cluster b) {
  Cluster c = mergedCluster(a, b, node);
  for (uint k = 0u; k < 6u; ++k) nodeBoxes[6u * node + k] = c.box[k];
  children[2u * node] = a.node;
  children[2u * node + 1u] = b.node;
  parents[a.node] = node;
  parents[b.node] = node;
}

Cluster storedCluster(uint node) {
  Cluster c;
  for (uint k = 0u; k < 6u; ++k) c.box[k] = nodeBoxes[6u * node + k];
  c.node = node;
  return c;
}

Cluster sharedCluster(uint at) {
  Cluster c;
  c.box[0] = s_lo[at].x, c.box[1] = s_lo[at].y, c.box[2] = s_lo[at].z;
  c.box[3] = s_hi[at].x, c.box[4] = s_hi[at].y, c.box[5] = s_hi[at].z;
  c.node = s_node[at];
  return c;
}

void main() {
  uint lane = gl_LocalInvocationID.x, k = gl_GlobalInvocationID.x, n = u_count;
  bool climbing = k < n;
  uint l = k, r = k, split = 0u;
  if (climbing) {
    uint leaf = n - 1u + k, prim = keys[k].id;
    for (uint a = 0u; a < 6u; ++a) nodeBoxes[6u * leaf + a] = boxes[6u * prim + a];
    lists[k] = leaf;
    lists[n + k] = 1u;
  }
  if (lane == 0u) {
    s_clusterBits[0] = s_clusterBits[1] = 0u;
    s_climbingBits[0] = s_climbingBits[1] = 0u;
    s_keptBits = s_mergeBits = 0u;
  }
  barrier();
  for (uint turn = 0u;; turn = turn == 2u ? 0u : turn + 1u) {
    // One level up: the parent over boundary `split`.
    bool clusterNow = false;
    if (climbing) {
      memoryBarrierBuffer();  // this subtree's list and nodes before the exchange that hands them on
      bool leftChild = l == 0u || (r != n - 1u && deltaLess(r, l - 1u));
      split = leftChild ? r : l - 1u;
      uint other = atomicExchange(waiting[split], leftChild ? l : r);
      if (other == kNone) {
        climbing = false;  // the sibling is not done: it goes on
      } else {
        memoryBarrierBuffer();
        if (leftChild) r = other; else l = other;
        bool root = l == 0u && r == n - 1u;
        uint left = lists[n + l], right = lists[n + split + 1u];
        if (sameCode(l, r)) {  // a run of one code: the radix tree's node over the two clusters
          uint node = n - 2u - atomicAdd(made, 1u);
          makeInner(node, storedCluster(lists[l]), storedCluster(lists[split + 1u]));
          lists[l] = node;
          if (root) climbing = false;
        } else if (r - l + 1u > kKeep || root) {
          clusterNow = true;
        } else {  // the left list, then the right one
          for (uint j = 0u; j < right; ++j) lists[l + left + j] = lists[split + 1u + j];
          lists[n + l] = left + right;
        }
      }
    }
    if (clusterNow) atomicOr(s_clusterBits[turn], 1u << lane);
    if (climbing) atomicOr(s_climbingBits[turn], 1u << lane);
    s_range[turn][lane] = uvec3(l, split, r);
    barrier();
    uint mask = s_clusterBits[turn];
    bool any = s_climbingBits[turn] != 0u;
    if (lane == 0u) {
      uint next2 = turn == 0u ? 2u : turn - 1u;  // (turn + 2) % 3
      s_clusterBits[next2] = 0u;
      s_climbingBits[next2] = 0u;
    }
    if (!any) break;
    while (mask != 0u) {
      uint owner = uint(findLSB(mask));
      mask &= mask - 1u;
      uvec3 task = s_range[turn][owner];
      bool root = task.x == 0u && task.z == n - 1u;
      uint left = lists[n + task.x], right = lists[n + task.y + 1u];
      uint m = left + right;
      if (lane < m) {
        uint node = lane < left ? lists[task.x + lane] : lists[task.y + 1u + lane - left];
        s_lo[lane] = vec3(nodeBoxes[6u * node], nodeBoxes[6u * node + 1u], nodeBoxes[6u * node + 2u]);
        s_hi[lane] = vec3(nodeBoxes[6u * node + 3u], nodeBoxes[6u * node + 4u], nodeBoxes[6u * node + 5u]);
        s_node[lane] = node;
      }
      barrier();
      while (m > (root ? 1u : kKeep)) {
        // A ploc pass over the m clusters, positions 0 .. m - 1 of the list.
        if (lane < m) {
          vec3 xlo = s_lo[lane], xhi = s_hi[lane];
          uvec2 best = uvec2(0xffffffffu);
          uint found = lane;
          uint from = lane - min(lane, u_radius), to = min(m - 1u, lane + u_radius);
          for (uint j = from; j <= to; ++j) {
            if (j == lane) continue;
            uvec2 key = candidateKey(lane, j, xlo, xhi, s_lo[j], s_hi[j]);
            if (less(key, best)) { best = key; found = j; }
          }
          s_nearest[lane] = found;
        }
        barrier();
        // The pass's merges take one block of node numbers (one atomic per pass, not per merge), in
        // the order of their positions.
        bool kept = false, merging = false;
        Cluster mine, other;
        if (lane < m) {
          uint y = s_nearest[lane];
          bool mutual = s_nearest[y] == lane;
          kept = !mutual || lane < y;
          merging = mutual && lane < y;  // merged here: left child the lower position
          mine = sharedCluster(lane);
          if (merging) other = sharedCluster(y);
        }
        if (kept) atomicOr(s_keptBits, 1u << lane);
        if (merging) atomicOr(s_mergeBits, 1u << lane);
        barrier();
        uint keptBits = s_keptBits, mergeBits = s_mergeBits, below = (1u << lane) - 1u;
        uint at = uint(bitCount(keptBits & below)), total = uint(bitCount(keptBits));
        uint rank = uint(bitCount(mergeBits & below)), merges = uint(bitCount(mergeBits));
        if (merging && rank == 0u) s_made = atomicAdd(made, merges);
        barrier();  // every invocation has read its clusters and the bits; the block of numbers is known
        if (lane == 0u) s_keptBits = s_mergeBits = 0u;
        if (merging) {
          uint node = n - 2u - (s_made + rank);
          makeInner(node, mine, other);
          mine = mergedCluster(mine, other, node);
        }
        if (kept) {
          s_lo[at] = vec3(mine.box[0], mine.box[1], mine.box[2]);
          s_hi[at] = vec3(mine.box[3], mine.box[4], mine.box[5]);
          s_node[at] = mine.node;
        }
        barrier();
        m = total;
      }
      if (lane < m) lists[task.x + lane] = s_node[lane];
      if (lane == 0u) lists[n + task.x] = m;
      memoryBarrierBuffer();
      barrier();  // the list written before its owner climbs on (and before the shared list is reused)
      if (lane == owner && root) climbing = false;
    }
  }
}
