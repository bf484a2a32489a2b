// What ploc-gpu's split passes and plocpp-gpu's fused pass share, word for word, so that both choose and
// merge as builders/ploc.cpp does (a prelude module: compiled ahead of the pass's own source,
// ComputeProgram's `prelude`).
//   Cluster       a cluster as the passes store it: its box (min xyz, max xyz) and its node
//   candidateKey  the key of pairing x with j: the merged half area as the CPU computes it (extents
//                 max - min, then (x y + y z) + z x, each operation rounded on its own under `precise`;
//                 a zero area as +0, since min and max of -0 and +0 may give either sign), then the
//                 pair's tie key (distance, the lower position's parity, the side)
//   less          the keys' order, as one 64-bit number, high word first
//   mergedCluster the union of two clusters' boxes as Aabb::grow makes it (y < x ? y : x, x < y ? y : x)
struct Cluster { float box[6]; uint node; };

uvec2 candidateKey(uint x, uint j, vec3 xlo, vec3 xhi, vec3 jlo, vec3 jhi) {
  precise float ex = max(xhi.x, jhi.x) - min(xlo.x, jlo.x);
  precise float ey = max(xhi.y, jhi.y) - min(xlo.y, jlo.y);
  precise float ez = max(xhi.z, jhi.z) - min(xlo.z, jlo.z);
  precise float area = (ex * ey + ey * ez) + ez * ex;
  uint d = x > j ? x - j : j - x, lower = min(x, j);
  return uvec2(area == 0.0 ? 0u : floatBitsToUint(area), 4u * d + 2u * (lower & 1u) + (j > x ? 1u : 0u));
}

bool less(uvec2 a, uvec2 b) { return a.x < b.x || (a.x == b.x && a.y < b.y); }

Cluster mergedCluster(Cluster a, Cluster b, uint node) {
  Cluster c;
  for (uint k = 0u; k < 3u; ++k) {
    c.box[k] = b.box[k] < a.box[k] ? b.box[k] : a.box[k];
    c.box[3u + k] = a.box[3u + k] < b.box[3u + k] ? b.box[3u + k] : a.box[3u + k];
  }
  c.node = node;
  return c;
}
