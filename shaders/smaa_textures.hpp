// The two precomputed textures of SMAA 1x (Jimenez et al., "SMAA: Enhanced Subpixel Morphological
// Antialiasing", CGF 31(2), 2012), generated here from the algorithm's definition (no stored blobs).
//
// Conventions shared with shaders/smaa_*.glsl (GL, y up):
//   edges texture  r(x,y) = 1: edge between pixels (x-1,y) and (x,y)  ("left" edge of the pixel)
//                  g(x,y) = 1: edge between pixels (x,y-1) and (x,y)  ("bottom" edge of the pixel)
//   An edge line is a run of such edges along one pixel boundary. In its local frame X runs along the line
//   from its first pixel's near boundary (X = 0) to the last pixel's far boundary (X = L); Y is the
//   perpendicular, positive towards the pixel that stores the edge ("owner" side), negative towards the
//   neighbour ("other" side).
//   Crossing edges at an end: kCrossNone, kCrossOther (the perpendicular edge runs into the neighbour
//   side), kCrossOwner (into the owner side), kCrossBoth.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

namespace bvhlab::smaa {

enum Crossing : int { kCrossNone = 0, kCrossOther = 1, kCrossOwner = 2, kCrossBoth = 3 };

// ---- area texture -----------------------------------------------------------------------------------
// Orthogonal patterns: a 4x4 grid of tiles, tile (e1, e2) for the crossing edges at the near (e1) and
// far (e2) end. Inside a tile, texel (i, j) holds the area for distances d1 = i^2, d2 = j^2 pixels to the
// two ends (the paper's quadratic compression: 16 texels reach 225 pixels and bilinear filtering in
// sqrt-distance space interpolates between them).
constexpr int kAreaTileSize = 16;
constexpr int kAreaMaxDistance = (kAreaTileSize - 1) * (kAreaTileSize - 1);

// Area of one pixel's two sides for the pixel [d1, d1 + 1] of a line of length L = d1 + d2 + 1:
// x = coverage of the owner pixel by the other side's colour (the owner takes x from the neighbour),
// y = the neighbour takes y from the owner. Each is in [0, 0.5] for offset 0.
// `offset` shifts the reconstructed line perpendicular to the edge (subsample offset; 0 for SMAA 1x).
glm::vec2 orthogonalArea(int e1, int e2, int d1, int d2, float offset = 0.0f);

// Reconstructed line of an orthogonal pattern after resolving kCrossBoth (see the .cpp): points (X, Y),
// empty when the pattern does not blend. Exposed for the tests.
std::vector<glm::vec2> orthogonalShape(int e1, int e2, float length, float offset = 0.0f);

struct AreaTexture {
  int width = 0, height = 0;
  std::vector<glm::vec2> texels;  // row-major, row 0 first (GL bottom row)
  glm::vec2 at(int x, int y) const { return texels[size_t(y) * width + x]; }
};

// Orthogonal: (4 * 16) x (4 * 16) texels, tile (e1, e2) at (16 * e1, 16 * e2).
AreaTexture makeOrthogonalAreaTexture(float offset = 0.0f);

// What the shader reads for integer distances: bilinear filtering of the orthogonal texture at
// sqrt-compressed coordinates, clamped to the tile (the same arithmetic as smaa_weights.glsl).
glm::vec2 lookupOrthogonal(const AreaTexture& tex, int e1, int e2, int d1, int d2);

// ---- diagonal patterns ----------------------------------------------------------------------------
// A staircase of one-pixel steps is a diagonal line. With the edge conventions above, a "unit" of a
// slope +1 staircase at pixel q is the pair bottom(q) + left(q + (1,0)): an elbow whose corner is q's
// lower-right corner. Pixel q lies on the inner (upper-left) side, o = q + (1,0) on the outer side, and
// the next unit is at q + (1,1). A slope -1 staircase is the mirror image (x -> -x), which the shader
// maps onto this frame: in mirrored coordinates bottom'(q) = bottom(mirror q) and left'(q) =
// left(mirror q + (1,0)), so the unit left(q) + bottom(q) of a slope -1 staircase becomes a unit here.
//
// A run of n = d1 + d2 + 1 units q_k = q_0 + k (1,1), k = 0..n-1, is reconstructed as a line in the run's
// frame (origin at q_0's lower-left corner): Y(X) = X - 1/2 + h(X) for X in [0, n + 1], where X - 1/2 is
// the line through the midpoints of all the run's edges and h is the offset that the ends call for,
// built like an orthogonal pattern (orthogonalShape with length n + 1, end heights +-1/2):
//   start end: the staircase continues horizontally before q_0 (bottom(q_0 - (1,0)), no left(q_0 -
//     (0,1))) -> +1/2 (kCrossOwner, the line starts at the inner corner: the edge is shallower than 45
//     degrees); it continues vertically (left(q_0 - (0,1))) -> -1/2 (kCrossOther); else kCrossNone.
//   far end, with q_n = q_0 + n (1,1): bottom(q_n) (horizontal continuation) -> -1/2 (kCrossOther);
//     left(q_n) (vertical continuation) -> +1/2 (kCrossOwner); else kCrossNone.
// (Two horizontal continuations give the line (0, 0) -> (n + 1, n): slope n / (n + 1), the straight edge
// that makes n one-pixel steps between two two-pixel steps.)
// The weights are areas of whole pixels on the far side of the line:
//   inner(k): area of q_k below the line (q_k takes it from its outer neighbours);
//   outer(k): area of o_k above the line (o_k takes it from its inner neighbours), k = -1..n-1.
constexpr int kDiagTileSize = 20;                     // distances 0..19 units to each end
constexpr int kDiagMaxDistance = kDiagTileSize - 1;

// For the unit k = d1 of a run of d1 + d2 + 1 units: (inner(k), outer(k - 1), outer(k), 0).
glm::vec4 diagonalArea(int e1, int e2, int d1, int d2);

struct DiagonalAreaTexture {
  int width = 4 * kDiagTileSize, height = 4 * kDiagTileSize;
  std::vector<glm::vec4> texels;  // row-major: texel (e1 * 20 + d1, e2 * 20 + d2), read with texelFetch
  glm::vec4 at(int e1, int e2, int d1, int d2) const {
    return texels[size_t(e2 * kDiagTileSize + d2) * width + e1 * kDiagTileSize + d1];
  }
};
DiagonalAreaTexture makeDiagonalAreaTexture();

// ---- search texture ---------------------------------------------------------------------------------
// The search reads two pixels of the line per bilinear fetch. The fetch point is placed so that the
// first pixel (in search order) weighs 3/4 and the second 1/4 along the line, and the owner row weighs
// 7/8 and the neighbour row 1/8 across it; each channel then returns (21 a + 7 b + 3 c + d) / 32 for bits
// a (first, owner), b (second, owner), c (first, neighbour), d (second, neighbour), a sum that is unique
// for all 16 bit patterns. The line channel tells whether the two pixels continue the line; the cross
// channel tells whether a perpendicular edge crosses it at the pixels' boundaries.
//
// searchDecision(direction, crossCode, lineCode) with codes round(32 * value) in 0..32 returns
//   0, 1, 2: the line ends and that many of the two pixels belong to it; kSearchContinue: both belong,
//   and no crossing edge stops the search.
// direction 0 = backward (towards -X: left / down), 1 = forward (towards +X: right / up).
constexpr int kSearchCodes = 33;
constexpr uint8_t kSearchContinue = 3;
int encodeSearchBits(bool a, bool b, bool c, bool d);  // 21a + 7b + 3c + d
uint8_t searchDecisionFromBits(int direction, std::array<bool, 4> cross, std::array<bool, 4> line);

struct SearchTexture {
  int width = 2 * kSearchCodes, height = kSearchCodes;  // backward table at x < 33, forward at x >= 33
  std::vector<uint8_t> texels;                          // row-major: texel (direction*33 + cross, line)
  uint8_t at(int direction, int crossCode, int lineCode) const {
    return texels[size_t(lineCode) * width + direction * kSearchCodes + crossCode];
  }
};
SearchTexture makeSearchTexture();

}  // namespace bvhlab::smaa
