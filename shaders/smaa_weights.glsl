// SMAA 1x, pass 2: blending weight calculation (Jimenez et al. 2012): for each edge stored at this
// pixel, search both ends of its line (two pixels per bilinear fetch, decoded by the search texture),
// read the crossing edges at the ends, look the pattern's area up in the area texture and attenuate
// sharp corners. Prefixed with #version 450 core and: SMAA_MAX_SEARCH_STEPS (int),
// SMAA_CORNER_ROUNDING (percent of the area kept at a detected sharp corner; 100 = no detection),
// SMAA_MAX_SEARCH_STEPS_DIAG (units searched along a diagonal line each way; 0 = no diagonal patterns).
// An edge on a staircase of two or more one-pixel steps takes its weights from the diagonal line through
// the whole staircase instead of the orthogonal pattern of its own one-pixel line.
// Conventions (edges, line frame, crossing codes, texture layouts): shaders/smaa_textures.hpp.
// Output: rg = the bottom edge's (owner takes from below, below takes from owner),
//         ba = the left edge's   (owner takes from the left, left takes from owner).

layout(binding = 0) uniform sampler2D u_edges;    // RG8, linear filtering, clamped: bilinear search
layout(binding = 1) uniform sampler2D u_area;     // RG32F, linear filtering, clamped
layout(binding = 2) uniform usampler2D u_search;  // R8UI, texelFetch only
layout(location = 0) out vec4 o_weights;
// The search bounds as uniforms (equal to the defines): with a constant bound the compiler unrolls the
// loops, and llvmpipe then runs every step for every fragment of a SIMD block (the early exits become
// masks); a real loop stops when all fragments are done. Measured on the report scene at 640x360:
// weights pass 46 -> 33 ms (low), 198 -> 94 ms (high, loaded machine, same run).
layout(location = 0) uniform int u_maxSearchSteps;
layout(location = 1) uniform int u_maxDiagSearchSteps;

#define SMAA_AREA_TILE 16
#define SMAA_SEARCH_CODES 33
#define SMAA_SEARCH_CONTINUE 3u

// (cross, line) channels of the edges texture for a line along `along`: a horizontal line (along x)
// is made of g edges and crossed by r edges; a vertical one the other way round.
vec2 smaaCrossLine(vec2 e, ivec2 along) { return along.x != 0 ? e.rg : e.gr; }

float smaaCrossAt(ivec2 p, ivec2 along) {
  ivec2 size = textureSize(u_edges, 0);
  return smaaCrossLine(texelFetch(u_edges, clamp(p, ivec2(0), size - 1), 0).rg, along).x;
}

// Distance (pixels) from p to the end of its line in `direction` (0: backward, 1: forward).
int smaaSearch(ivec2 p, ivec2 along, ivec2 toNeighbour, int direction) {
  vec2 invSize = 1.0 / vec2(textureSize(u_edges, 0));
  ivec2 step = direction == 0 ? -along : along;
  ivec2 q = direction == 0 ? p : p + along;  // first pixel of the first pair
  for (int k = 0; k < u_maxSearchSteps; ++k) {
    // First pixel weighs 3/4 and second 1/4 along the line; owner row 7/8, neighbour row 1/8 across.
    vec2 texel = vec2(q) + 0.5 + 0.25 * vec2(step) + 0.125 * vec2(toNeighbour);
    vec2 code = round(32.0 * smaaCrossLine(textureLod(u_edges, texel * invSize, 0.0).rg, along));
    uint s = texelFetch(u_search, ivec2(direction * SMAA_SEARCH_CODES + int(code.x), int(code.y)), 0).r;
    if (s != SMAA_SEARCH_CONTINUE)
      return direction == 0 ? max(2 * k - 1 + int(s), 0) : 2 * k + int(s);
    q += 2 * step;
  }
  return direction == 0 ? 2 * SMAA_MAX_SEARCH_STEPS - 1 : 2 * SMAA_MAX_SEARCH_STEPS;
}

// Crossing code at the near boundary of pixel `end`: 2 = owner side, 1 = neighbour side, 3 = both.
int smaaCrossing(ivec2 end, ivec2 along, ivec2 toNeighbour) {
  return 2 * int(smaaCrossAt(end, along) > 0.5) + int(smaaCrossAt(end + toNeighbour, along) > 0.5);
}

vec2 smaaArea(int e1, int e2, int d1, int d2) {
  vec2 coord = min(sqrt(vec2(d1, d2)), vec2(SMAA_AREA_TILE - 1));  // quadratic distance compression
  vec2 texel = vec2(e1, e2) * float(SMAA_AREA_TILE) + coord + 0.5;
  return textureLod(u_area, texel / vec2(textureSize(u_area, 0)), 0.0).rg;
}

// Sharp-corner test at one end (near boundary of pixel `end`): a crossing edge that goes on for more than
// one pixel on a side marks a real corner, whose area is kept at SMAA_CORNER_ROUNDING percent.
vec2 smaaCornerFactor(ivec2 end, ivec2 along, ivec2 toNeighbour, float rounding) {
  float owner = smaaCrossAt(end, along) * smaaCrossAt(end - toNeighbour, along);
  float other = smaaCrossAt(end + toNeighbour, along) * smaaCrossAt(end + 2 * toNeighbour, along);
  return rounding * vec2(owner, other);
}

vec2 smaaLineWeights(ivec2 p, ivec2 along, ivec2 toNeighbour) {
  int d1 = smaaSearch(p, along, toNeighbour, 0);
  int d2 = smaaSearch(p, along, toNeighbour, 1);
  ivec2 nearEnd = p - d1 * along, farEnd = p + (d2 + 1) * along;
  int e1 = smaaCrossing(nearEnd, along, toNeighbour);
  int e2 = smaaCrossing(farEnd, along, toNeighbour);
  vec2 area = smaaArea(e1, e2, d1, d2);
#if SMAA_CORNER_ROUNDING < 100
  // The area comes from the nearer end (both when equally near).
  float rounding = 1.0 - float(SMAA_CORNER_ROUNDING) / 100.0;
  vec2 factor = vec2(1.0);
  float share = d1 == d2 ? 0.5 : 1.0;
  if (d1 <= d2) factor -= share * smaaCornerFactor(nearEnd, along, toNeighbour, rounding);
  if (d2 <= d1) factor -= share * smaaCornerFactor(farEnd, along, toNeighbour, rounding);
  area *= clamp(factor, 0.0, 1.0);
#endif
  return area;
}

#if SMAA_MAX_SEARCH_STEPS_DIAG > 0
// ---- diagonal patterns (frame, units and areas: shaders/smaa_textures.hpp, "diagonal patterns") ----
layout(binding = 3) uniform sampler2D u_areaDiag;  // RGBA32F, texelFetch only
#define SMAA_DIAG_TILE 20

ivec2 g_edgesSize;  // textureSize(u_edges, 0), set once in main()

bool smaaEdge(ivec2 p, int channel) {  // channel 0: left edge, 1: bottom edge; nothing outside the frame
  if (any(lessThan(p, ivec2(0))) || any(greaterThanEqual(p, g_edgesSize))) return false;
  return texelFetch(u_edges, p, 0)[channel] > 0.5;
}

// Edges of the slope +1 frame at local offset d from pixel o; `mirrored` maps a slope -1 staircase onto it.
bool smaaDiagBottom(ivec2 o, ivec2 d, bool mirrored) { return smaaEdge(o + ivec2(mirrored ? -d.x : d.x, d.y), 1); }
bool smaaDiagLeft(ivec2 o, ivec2 d, bool mirrored) { return smaaEdge(o + ivec2(mirrored ? 1 - d.x : d.x, d.y), 0); }
bool smaaDiagUnit(ivec2 o, ivec2 d, bool mirrored) {
  return smaaDiagBottom(o, d, mirrored) && smaaDiagLeft(o, d + ivec2(1, 0), mirrored);
}

// For the unit at local offset u (which exists): (inner(k), outer(k-1), outer(k), d1 + d2) of its run,
// or w = 0 for a run of one unit (the orthogonal patterns describe it as well).
vec4 smaaDiagAreas(ivec2 o, ivec2 u, bool mirrored) {
  int d1 = 0, d2 = 0;
  while (d1 < u_maxDiagSearchSteps && smaaDiagUnit(o, u - (d1 + 1) * ivec2(1), mirrored)) ++d1;
  while (d2 < u_maxDiagSearchSteps && smaaDiagUnit(o, u + (d2 + 1) * ivec2(1), mirrored)) ++d2;
  if (d1 + d2 == 0) return vec4(0.0);
  ivec2 first = u - d1 * ivec2(1), next = u + (d2 + 1) * ivec2(1);
  // End codes as crossings: 2 = owner side (+1/2, inner), 1 = other side (-1/2, outer), 0 = none. An end
  // the search did not reach counts as none.
  int e1 = d1 == u_maxDiagSearchSteps ? 0
           : smaaDiagLeft(o, first + ivec2(0, -1), mirrored)   ? 1
           : smaaDiagBottom(o, first + ivec2(-1, 0), mirrored) ? 2 : 0;
  int e2 = d2 == u_maxDiagSearchSteps ? 0
           : smaaDiagBottom(o, next, mirrored)                 ? 1
           : smaaDiagLeft(o, next, mirrored)                   ? 2 : 0;
  vec4 a = texelFetch(u_areaDiag, ivec2(e1 * SMAA_DIAG_TILE + d1, e2 * SMAA_DIAG_TILE + d2), 0);
  return vec4(a.xyz, float(d1 + d2));
}

#endif

void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  vec2 e = texelFetch(u_edges, p, 0).rg;
  vec4 w = vec4(0.0);
#if SMAA_MAX_SEARCH_STEPS_DIAG > 0
  g_edgesSize = textureSize(u_edges, 0);
#endif
  if (e.g > 0.5) {  // bottom edge: p is the inner pixel of a unit at local offset 0 in either frame
#if SMAA_MAX_SEARCH_STEPS_DIAG > 0
    vec4 up = smaaDiagUnit(p, ivec2(0), false) ? smaaDiagAreas(p, ivec2(0), false) : vec4(0.0);
    vec4 down = smaaDiagUnit(p, ivec2(0), true) ? smaaDiagAreas(p, ivec2(0), true) : vec4(0.0);
    // The longer run wins; a tie (including two single units) leaves the edge to the orthogonal patterns.
    if (up.w != down.w) w.rg = (up.w > down.w ? up : down).xy;  // p takes inner(k); below takes outer(k-1)
    else
#endif
    w.rg = smaaLineWeights(p, ivec2(1, 0), ivec2(0, -1));  // horizontal line
  }
  if (e.r > 0.5) {  // left edge: the riser of a slope +1 unit at p - (1,0), or of a slope -1 unit at p
#if SMAA_MAX_SEARCH_STEPS_DIAG > 0
    vec4 up = smaaDiagUnit(p, ivec2(-1, 0), false) ? smaaDiagAreas(p, ivec2(-1, 0), false) : vec4(0.0);
    vec4 down = smaaDiagUnit(p, ivec2(0), true) ? smaaDiagAreas(p, ivec2(0), true) : vec4(0.0);
    // Slope +1: p is the outer pixel o_k and its left neighbour the inner q_k; slope -1 the other way.
    if (up.w != down.w) w.ba = up.w > down.w ? up.zx : down.xz;
    else
#endif
    w.ba = smaaLineWeights(p, ivec2(0, 1), ivec2(-1, 0));  // vertical line
  }
  o_weights = w;
}
