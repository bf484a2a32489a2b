#include "shaders/smaa_textures.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace bvhlab::smaa {

namespace {

// Height of the reconstructed line at an end with a single crossing edge: the middle of that edge
// (MLAA's revectorisation, Reshetov 2009; Jimenez et al. 2011), half a pixel into its side.
float endHeight(int e, float offset) { return (e == kCrossOwner ? 0.5f : -0.5f) + offset; }

// Positive and negative parts of the integral of the linear function through (x0, h0), (x1, h1) over
// [x0, x1] (x0 <= x1), split at its zero crossing.
glm::vec2 integrateLinear(float x0, float h0, float x1, float h1) {
  const float w = x1 - x0;
  if (w <= 0.0f) return glm::vec2(0.0f);
  if ((h0 >= 0.0f && h1 >= 0.0f) || (h0 <= 0.0f && h1 <= 0.0f)) {
    const float a = 0.5f * (h0 + h1) * w;
    return a >= 0.0f ? glm::vec2(a, 0.0f) : glm::vec2(0.0f, -a);
  }
  // Opposite signs: h0 != h1, so the crossing is well defined.
  const float t = h0 / (h0 - h1);  // in (0, 1)
  const float a0 = 0.5f * h0 * t * w, a1 = 0.5f * h1 * (1.0f - t) * w;
  return glm::vec2(std::max(a0, 0.0f) + std::max(a1, 0.0f), std::max(-a0, 0.0f) + std::max(-a1, 0.0f));
}

}  // namespace

std::vector<glm::vec2> orthogonalShape(int e1, int e2, float length, float offset) {
  if (e1 < 0 || e1 > 3 || e2 < 0 || e2 > 3) throw std::invalid_argument("crossing code outside 0..3");
  // A kCrossBoth end (a T or + junction) has no orientation of its own. Facing a single crossing at the
  // other end, it continues that step as a Z (the orientation opposite to the other end); otherwise it
  // does not blend.
  if (e1 == kCrossBoth && (e2 == kCrossOther || e2 == kCrossOwner)) e1 = 3 - e2;
  if (e2 == kCrossBoth && (e1 == kCrossOther || e1 == kCrossOwner)) e2 = 3 - e1;
  if (e1 == kCrossBoth) e1 = kCrossNone;
  if (e2 == kCrossBoth) e2 = kCrossNone;
  const float mid = 0.5f * length;
  if (e1 != kCrossNone && e2 != kCrossNone) {
    if (e1 != e2) return {{0.0f, endHeight(e1, offset)}, {length, endHeight(e2, offset)}};  // Z
    return {{0.0f, endHeight(e1, offset)}, {mid, 0.0f}, {length, endHeight(e2, offset)}};   // U
  }
  if (e1 != kCrossNone) return {{0.0f, endHeight(e1, offset)}, {mid, 0.0f}};  // L at the near end
  if (e2 != kCrossNone) return {{mid, 0.0f}, {length, endHeight(e2, offset)}};  // L at the far end
  return {};
}

glm::vec2 orthogonalArea(int e1, int e2, int d1, int d2, float offset) {
  if (d1 < 0 || d2 < 0) throw std::invalid_argument("negative distance");
  const float length = float(d1) + float(d2) + 1.0f;
  const std::vector<glm::vec2> shape = orthogonalShape(e1, e2, length, offset);
  const float a = float(d1), b = a + 1.0f;
  glm::vec2 area(0.0f);
  for (size_t i = 1; i < shape.size(); ++i) {
    const glm::vec2 p = shape[i - 1], q = shape[i];
    const float x0 = std::max(a, p.x), x1 = std::min(b, q.x);
    if (x1 <= x0) continue;
    const float slope = (q.y - p.y) / (q.x - p.x);  // q.x > p.x: shape points are strictly increasing
    area += integrateLinear(x0, p.y + slope * (x0 - p.x), x1, p.y + slope * (x1 - p.x));
  }
  return area;
}

AreaTexture makeOrthogonalAreaTexture(float offset) {
  AreaTexture tex;
  tex.width = tex.height = 4 * kAreaTileSize;
  tex.texels.assign(size_t(tex.width) * tex.height, glm::vec2(0.0f));
  for (int e2 = 0; e2 < 4; ++e2)
    for (int e1 = 0; e1 < 4; ++e1)
      for (int j = 0; j < kAreaTileSize; ++j)
        for (int i = 0; i < kAreaTileSize; ++i)
          tex.texels[size_t(e2 * kAreaTileSize + j) * tex.width + e1 * kAreaTileSize + i] =
              orthogonalArea(e1, e2, i * i, j * j, offset);
  return tex;
}

glm::vec2 lookupOrthogonal(const AreaTexture& tex, int e1, int e2, int d1, int d2) {
  // Mirrors smaaArea() in smaa_weights.glsl: texel coordinate = tile origin + sqrt(distance), clamped
  // to the last texel of the tile, then bilinear between the neighbouring texels.
  const float maxCoord = float(kAreaTileSize - 1);
  const glm::vec2 coord = glm::min(glm::sqrt(glm::vec2(float(d1), float(d2))), glm::vec2(maxCoord));
  const glm::ivec2 i0 = glm::ivec2(glm::floor(coord));
  const glm::ivec2 i1 = glm::min(i0 + 1, glm::ivec2(kAreaTileSize - 1));
  const glm::vec2 f = coord - glm::vec2(i0);
  const glm::ivec2 origin(e1 * kAreaTileSize, e2 * kAreaTileSize);
  auto at = [&](int x, int y) { return tex.at(origin.x + x, origin.y + y); };
  return glm::mix(glm::mix(at(i0.x, i0.y), at(i1.x, i0.y), f.x), glm::mix(at(i0.x, i1.y), at(i1.x, i1.y), f.x),
                  f.y);
}

namespace {

// Integral over [0, w] of clamp(g, 0, 1) for g linear from g0 to g1: split where g crosses 0 and 1.
float integrateClamped01(float g0, float g1, float w) {
  if (w <= 0.0f) return 0.0f;
  // Parameters in (0, 1) where g crosses 0 or 1 (g0 != g1 whenever a crossing exists); clamp(g) is
  // linear between consecutive cuts, so the trapezoid rule is exact there.
  float c[2] = {1.0f, 1.0f};
  int count = 0;
  for (float level : {0.0f, 1.0f})
    if ((g0 - level) * (g1 - level) < 0.0f) c[count++] = (level - g0) / (g1 - g0);
  if (c[0] > c[1]) std::swap(c[0], c[1]);
  const float cuts[4] = {0.0f, c[0], c[1], 1.0f};
  float sum = 0.0f;
  for (int i = 0; i < 3; ++i) {
    const float a = cuts[i], b = cuts[i + 1];
    const float ga = glm::clamp(g0 + (g1 - g0) * a, 0.0f, 1.0f), gb = glm::clamp(g0 + (g1 - g0) * b, 0.0f, 1.0f);
    sum += 0.5f * (ga + gb) * (b - a);
  }
  return sum * w;
}

// Offset h(X) of the reconstructed diagonal line from the midpoint line: the shape's polyline, 0 where
// the shape does not reach (an L covers half the run) or when there is no pattern.
float shapeHeight(const std::vector<glm::vec2>& shape, float x) {
  for (size_t i = 1; i < shape.size(); ++i)
    if (x >= shape[i - 1].x && x <= shape[i].x)
      return glm::mix(shape[i - 1].y, shape[i].y, (x - shape[i - 1].x) / (shape[i].x - shape[i - 1].x));
  return 0.0f;
}

// Integral over X in [x0, x0 + 1] of clamp(f(X), 0, 1) where f(X) = a + s * (X - x0) + sign * h(X):
// exact, as f is linear between the shape's vertices.
float integrateOverPixel(const std::vector<glm::vec2>& shape, float x0, float a, float s, float sign) {
  std::vector<float> xs = {x0, x0 + 1.0f};
  for (const glm::vec2& v : shape)
    if (v.x > x0 && v.x < x0 + 1.0f) xs.push_back(v.x);
  // Every shape starts or ends at height 0 where it does not span the run (an L), so h is continuous and
  // linear between these points.
  std::sort(xs.begin(), xs.end());
  float sum = 0.0f;
  for (size_t i = 1; i < xs.size(); ++i) {
    const float g0 = a + s * (xs[i - 1] - x0) + sign * shapeHeight(shape, xs[i - 1]);
    const float g1 = a + s * (xs[i] - x0) + sign * shapeHeight(shape, xs[i]);
    sum += integrateClamped01(g0, g1, xs[i] - xs[i - 1]);
  }
  return sum;
}

}  // namespace

glm::vec4 diagonalArea(int e1, int e2, int d1, int d2) {
  if (d1 < 0 || d2 < 0) throw std::invalid_argument("negative distance");
  if (e1 == kCrossBoth || e2 == kCrossBoth) throw std::invalid_argument("diagonal ends have no kCrossBoth");
  const int n = d1 + d2 + 1;
  const std::vector<glm::vec2> shape = orthogonalShape(e1, e2, float(n + 1));
  // Line Y(X) = X - 1/2 + h(X). Inner pixel k = [k, k+1] x [k, k+1]: covered below the line by
  // clamp(Y(X) - k, 0, 1) = clamp(X - k - 1/2 + h, 0, 1). Outer pixel j = [j+1, j+2] x [j, j+1]: covered
  // above the line by clamp(j + 1 - Y(X), 0, 1) = clamp(1/2 - (X - j - 1) - h, 0, 1).
  auto inner = [&](int k) { return integrateOverPixel(shape, float(k), -0.5f, 1.0f, 1.0f); };
  auto outer = [&](int j) { return integrateOverPixel(shape, float(j + 1), 0.5f, -1.0f, -1.0f); };
  return glm::vec4(inner(d1), outer(d1 - 1), outer(d1), 0.0f);
}

DiagonalAreaTexture makeDiagonalAreaTexture() {
  DiagonalAreaTexture tex;
  tex.texels.assign(size_t(tex.width) * tex.height, glm::vec4(0.0f));
  for (int e2 = 0; e2 < 3; ++e2)  // kCrossBoth does not occur at a diagonal end: its tiles stay 0
    for (int e1 = 0; e1 < 3; ++e1)
      for (int d2 = 0; d2 < kDiagTileSize; ++d2)
        for (int d1 = 0; d1 < kDiagTileSize; ++d1)
          tex.texels[size_t(e2 * kDiagTileSize + d2) * tex.width + e1 * kDiagTileSize + d1] =
              diagonalArea(e1, e2, d1, d2);
  return tex;
}

int encodeSearchBits(bool a, bool b, bool c, bool d) { return 21 * a + 7 * b + 3 * c + 1 * d; }

uint8_t searchDecisionFromBits(int direction, std::array<bool, 4> cross, std::array<bool, 4> line) {
  // Bits: [0] first pixel owner row, [1] second pixel owner row, [2] first neighbour row, [3] second
  // neighbour row. A crossing edge at a pixel is a perpendicular edge on either side of the line.
  const bool crossFirst = cross[0] || cross[2], crossSecond = cross[1] || cross[3];
  const bool lineFirst = line[0], lineSecond = line[1];
  if (direction == 0) {
    // Backward: the pair is (q, q-1) with q already reached. The cross bit of a pixel is its near
    // (left/bottom) boundary, which lies between it and the next pixel of the search.
    //   q off the line -> 0; a crossing at q's near boundary -> q is the end (1);
    //   q-1 off the line -> 1; a crossing at q-1's near boundary -> q-1 is the end (2).
    if (!lineFirst) return 0;
    if (crossFirst) return 1;
    if (!lineSecond) return 1;
    if (crossSecond) return 2;
    return kSearchContinue;
  }
  // Forward: the pair is (p, p+1) beyond the last reached pixel p-1. A pixel joins the line if it
  // carries the line edge and no crossing edge lies at its near boundary (between it and p-1 / p).
  if (crossFirst || !lineFirst) return 0;
  if (crossSecond || !lineSecond) return 1;
  return kSearchContinue;
}

SearchTexture makeSearchTexture() {
  SearchTexture tex;
  tex.texels.assign(size_t(tex.width) * tex.height, 0);
  for (int direction = 0; direction < 2; ++direction)
    for (int c = 0; c < 16; ++c)
      for (int l = 0; l < 16; ++l) {
        const std::array<bool, 4> cross{bool(c & 1), bool(c & 2), bool(c & 4), bool(c & 8)};
        const std::array<bool, 4> line{bool(l & 1), bool(l & 2), bool(l & 4), bool(l & 8)};
        const int cc = encodeSearchBits(cross[0], cross[1], cross[2], cross[3]);
        const int lc = encodeSearchBits(line[0], line[1], line[2], line[3]);
        tex.texels[size_t(lc) * tex.width + direction * kSearchCodes + cc] =
            searchDecisionFromBits(direction, cross, line);
      }
  return tex;
}

}  // namespace bvhlab::smaa
