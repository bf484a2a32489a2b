// plocpp-gpu: one clustering pass of ploc-gpu in one dispatch, as PLOC++ fuses it (Benthin et al.,
// "PLOC++: Parallel Locally-Ordered Clustering for Bounding Volume Hierarchy Construction Revisited",
// HPG 2022): nearest neighbours, the mutual-pair test, merging and compaction in one kernel, the
// compaction's global offsets by a single-pass scan with decoupled look-back (Merrill & Garland, 2016).
// The same choices and numbering as gpubuild_ploc_nn/count/merge/next.glsl (the keys and merges of
// gpubuild_ploc_pairs.glsl, compiled ahead of this module as for them), so the same tree.
//
// A workgroup owns 256 positions of the current order. The mutual test of a position x needs the
// nearest neighbour of x's neighbour y, which lies within +-r of x, so the workgroup finds the nearest
// neighbours of its positions and of r more on either side (the window; the boxes read span 2r on
// either side: copied to shared memory up to kTiledRadius, read from the storage buffer beyond).
//
// Look-back: each workgroup takes a ticket (its logical block) from an atomic counter when it starts,
// so every lower block has started before a block waits on it: a wait always ends. It publishes its
// kept and merged counts (flag 1), adds its predecessors' published values going back until one holds
// an inclusive prefix (flag 2), then publishes its own inclusive prefix. A status word is
// value | flag << 29 | parity << 31, the parity being the pass's (passes & 1): a block that exists in
// this pass existed in the one before, so a status word not yet written in this pass carries the other
// parity and reads as not ready. The last workgroup to finish (an atomic counter) writes the next
// pass's state as gpubuild_ploc_next.glsl does and resets both counters.
layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer Clusters { Cluster clusters[]; };
layout(std430, binding = 1) writeonly buffer Next { Cluster next[]; };
layout(std430, binding = 2) writeonly buffer NodeBoxes { float nodeBoxes[]; };
layout(std430, binding = 3) writeonly buffer Children { uint children[]; };
layout(std430, binding = 4) writeonly buffer Parents { uint parents[]; };
layout(std430, binding = 5) coherent buffer Status { uint status[]; };  // kept, merged per block
layout(std430, binding = 7) coherent buffer PassState {
  uvec3 dispatchGroups; uint passClusters; uint passes; uint stuck; uint ticket; uint done;
};
uniform uint u_radius;
// Tests only (GpuPloc::giveUpInPass): in the pass that starts after this many passes, block 1's
// look-back gives up at once, so the host's fallback runs; ~0u: never.
uniform uint u_giveUpPass;

const uint kMaxRadius = 1024u;  // kMaxPlocRadius (builders/bvh.hpp)
const uint kTiledRadius = 64u;  // boxes of 256 + 4r positions in shared memory: 12 KiB at r = 64
const uint kSpins = 1u << 30u;  // reads of the look-back's wait at most
const uint kGaveUp = 2u;        // PassState::stuck's bit for a block that gave up (gpu_ploc.cpp)
const uint kValueBits = 0x1fffffffu, kAggregate = 1u << 29u, kInclusive = 2u << 29u, kFlags = 3u << 29u;
shared vec3 s_lo[256u + 4u * kTiledRadius], s_hi[256u + 4u * kTiledRadius];
shared uint s_nn[256u + 2u * kMaxRadius];
shared uvec2 s_scan[256];  // kept, merged
shared uint s_block, s_clusters, s_parity, s_keptBefore, s_mergedBefore, s_ok;

vec3 lowOf(uint i) { return vec3(clusters[i].box[0], clusters[i].box[1], clusters[i].box[2]); }
vec3 highOf(uint i) { return vec3(clusters[i].box[3], clusters[i].box[4], clusters[i].box[5]); }

// Position x's nearest neighbour among the m clusters; shared slot s holds position boxFirst + s.
uint nearestOf(uint x, uint m, bool tiled, uint boxFirst) {
  vec3 xlo = tiled ? s_lo[x - boxFirst] : lowOf(x), xhi = tiled ? s_hi[x - boxFirst] : highOf(x);
  uvec2 best = uvec2(0xffffffffu);
  uint found = x;
  uint from = x - min(x, u_radius), to = min(m - 1u, x + u_radius);
  for (uint j = from; j <= to; ++j) {
    if (j == x) continue;
    vec3 jlo = tiled ? s_lo[j - boxFirst] : lowOf(j), jhi = tiled ? s_hi[j - boxFirst] : highOf(j);
    uvec2 key = candidateKey(x, j, xlo, xhi, jlo, jhi);
    if (less(key, best)) { best = key; found = j; }
  }
  return found;
}

// The block's exclusive prefix of one count (which: 0 kept, 1 merged) into `before`, publishing its
// own on the way. Returns false, and publishes "gave up" (both flag bits), when the wait ended before
// a prefix was found or a predecessor had given up. The wait is bounded (kSpins reads, so that a bug
// cannot hang a GPU), and llvmpipe ends it sooner: it stops every loop of an invocation after 65535
// iterations in all (its guard against shaders that hang), which a wait for a predecessor the OS has
// not scheduled yet can pass. A block that gave up writes nothing; the host then runs the pass again
// with the split kernels (gpu_ploc.cpp).
bool lookBack(uint block, uint own, uint which, uint parity, out uint before) {
  uint word = 2u * block + which, mark = parity << 31u;
  before = 0u;
  if (block == 0u) {
    atomicExchange(status[word], mark | kInclusive | own);
    return true;
  }
  atomicExchange(status[word], mark | kAggregate | own);
  uint j = block - 1u;
  bool found = false, gaveUp = block == 1u && passes == u_giveUpPass;
  for (uint spin = 0u; !found && !gaveUp && spin < kSpins; ++spin) {
    uint s = atomicOr(status[2u * j + which], 0u);  // an atomic read: never a stale copy
    if ((s & (1u << 31u)) == mark && (s & kFlags) != 0u) {  // written in this pass
      if ((s & kFlags) == kFlags) {
        gaveUp = true;
        found = true;
      } else {
        before += s & kValueBits;
        if ((s & kFlags) == kInclusive)
          found = true;
        else
          j -= 1u;
      }
    }
  }
  bool ok = found && !gaveUp;
  atomicExchange(status[word], mark | (ok ? kInclusive | (before + own) : kFlags));
  return ok;
}

void main() {
  uint t = gl_LocalInvocationID.x;
  if (t == 0u) {
    s_block = atomicAdd(ticket, 1u);
    s_clusters = passClusters;
    s_parity = passes & 1u;
  }
  barrier();
  uint block = s_block, m = s_clusters, r = u_radius, base = block * 256u;
  uint windowFirst = base - min(base, r), windowEnd = min(m, base + 256u + r);
  uint boxFirst = base - min(base, 2u * r), boxEnd = min(m, base + 256u + 2u * r);
  bool tiled = r <= kTiledRadius;  // the same for the whole dispatch: barrier() stays in uniform flow
  if (tiled) {
    for (uint s = t; s < boxEnd - boxFirst; s += 256u) {
      s_lo[s] = lowOf(boxFirst + s);
      s_hi[s] = highOf(boxFirst + s);
    }
  }
  barrier();
  for (uint p = windowFirst + t; p < windowEnd; p += 256u) s_nn[p - windowFirst] = nearestOf(p, m, tiled, boxFirst);
  barrier();

  uint x = base + t, y = x;
  bool kept = false, merged = false;
  if (x < m) {
    y = s_nn[x - windowFirst];
    bool mutual = s_nn[y - windowFirst] == x;
    kept = !mutual || x < y;
    merged = mutual && x < y;
  }
  uvec2 mine = uvec2(kept ? 1u : 0u, merged ? 1u : 0u);
  s_scan[t] = mine;
  barrier();
  for (uint step = 1u; step < 256u; step <<= 1u) {
    uvec2 add = t >= step ? s_scan[t - step] : uvec2(0u);
    barrier();
    s_scan[t] += add;
    barrier();
  }
  if (t == 0u) {
    uint keptBefore = 0u, mergedBefore = 0u;
    bool ok = lookBack(block, s_scan[255].x, 0u, s_parity, keptBefore);
    if (ok)
      ok = lookBack(block, s_scan[255].y, 1u, s_parity, mergedBefore);
    else  // the merged count gives up at once
      atomicExchange(status[2u * block + 1u], (s_parity << 31u) | kFlags);
    if (!ok) atomicOr(stuck, kGaveUp);
    s_keptBefore = keptBefore;
    s_mergedBefore = mergedBefore;
    s_ok = ok ? 1u : 0u;
  }
  barrier();

  if (kept && s_ok != 0u) {
    uvec2 before = s_scan[t] - mine;
    uint at = s_keptBefore + before.x;
    if (!merged) {
      next[at] = clusters[x];
    } else {
      // The pass's merges take the inner nodes m - 2, m - 3, ... in order (gpubuild_ploc_merge.glsl).
      uint node = m - 2u - (s_mergedBefore + before.y);
      Cluster c = mergedCluster(clusters[x], clusters[y], node);
      next[at] = c;
      for (uint a = 0u; a < 6u; ++a) nodeBoxes[6u * node + a] = c.box[a];
      uint l = clusters[x].node, rr = clusters[y].node;
      children[2u * node] = l;
      children[2u * node + 1u] = rr;
      parents[l] = node;
      parents[rr] = node;
    }
  }

  // The last workgroup to finish writes the next pass's state (gpubuild_ploc_next.glsl).
  memoryBarrierBuffer();
  barrier();
  if (t == 0u && atomicAdd(done, 1u) == gl_NumWorkGroups.x - 1u) {
    uint last = atomicOr(status[2u * (gl_NumWorkGroups.x - 1u)], 0u);  // the last block's inclusive kept
    uint keptAll = last & kValueBits;
    ticket = 0u;
    done = 0u;
    if ((atomicOr(stuck, 0u) & kGaveUp) == 0u) passes += 1u;
    if ((atomicOr(stuck, 0u) & kGaveUp) != 0u) {  // nothing of this pass counts: the host runs it again, split
      dispatchGroups = uvec3(0u, 1u, 1u);
    } else if (keptAll >= m) {
      stuck = 1u;
      dispatchGroups = uvec3(0u, 1u, 1u);
    } else {
      passClusters = keptAll;
      dispatchGroups = uvec3(keptAll > 1u ? (keptAll + 255u) / 256u : 0u, 1u, 1u);
    }
  }
}
