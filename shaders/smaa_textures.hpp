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
