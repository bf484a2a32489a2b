#include "datasets/procedural.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "datasets/image_io.hpp"
#include "datasets/random_draws.hpp"

namespace bvhlab {

namespace {
constexpr float kPi = 3.14159265358979f;
}

// ---- random numbers --------------------------------------------------------------------------------

uint64_t SplitMix64::next() {
  uint64_t z = (state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

float SplitMix64::uniform() { return float(next() >> 40) * (1.0f / 16777216.0f); }

float SplitMix64::normal() {
  // Box-Muller; 1 - u keeps the log argument in (0, 1].
  const float u = 1.0f - uniform(), v = uniform();
  return std::sqrt(-2.0f * std::log(u)) * std::cos(2.0f * kPi * v);
}

glm::vec3 SplitMix64::uniform3(float lo, float hi) {
  return draw3<glm::vec3>([&] { return uniform(lo, hi); });
}

glm::vec3 SplitMix64::normal3() {
  return draw3<glm::vec3>([&] { return normal(); });
}

glm::vec3 SplitMix64::unitVector() {
  // Uniform z in [-1,1] and azimuth: Archimedes' hat-box theorem makes this uniform on the sphere.
  const float z = uniform(-1.0f, 1.0f), phi = uniform(0.0f, 2.0f * kPi);
  const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
  return glm::vec3(r * std::cos(phi), r * std::sin(phi), z);
}

// ---- textures ----------------------------------------------------------------------------------------

namespace {

glm::vec3 srgb(float r, float g, float b) { return glm::vec3(srgbToLinear(r), srgbToLinear(g), srgbToLinear(b)); }

// Signed distance to an axis-aligned box (centre c, half-size h) with corner radius r.
float sdBox(glm::vec2 p, glm::vec2 c, glm::vec2 h, float r) {
  const glm::vec2 q = glm::abs(p - c) - h + glm::vec2(r);
  return glm::length(glm::max(q, glm::vec2(0.0f))) + std::min(std::max(q.x, q.y), 0.0f) - r;
}

// Signed distance to the segment a-b.
float sdSegment(glm::vec2 p, glm::vec2 a, glm::vec2 b) {
  const glm::vec2 pa = p - a, ba = b - a;
  const float h = std::clamp(glm::dot(pa, ba) / glm::dot(ba, ba), 0.0f, 1.0f);
  return glm::length(pa - ba * h);
}

// Inside test for a triangle (either winding).
bool inTriangle(glm::vec2 p, glm::vec2 a, glm::vec2 b, glm::vec2 c) {
  auto edge = [](glm::vec2 p, glm::vec2 a, glm::vec2 b) { return (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x); };
  const float e0 = edge(p, a, b), e1 = edge(p, b, c), e2 = edge(p, c, a);
  return (e0 >= 0 && e1 >= 0 && e2 >= 0) || (e0 <= 0 && e1 <= 0 && e2 <= 0);
}

// The emblem at a point of the unit square (y up). Shapes are painted back to front.
glm::vec3 logoColor(glm::vec2 p) {
  const glm::vec3 outside = srgb(0.93f, 0.94f, 0.96f);  // light margin around the tile
  const glm::vec3 tile = srgb(0.07f, 0.12f, 0.26f);     // deep navy
  const glm::vec3 white = srgb(0.96f, 0.97f, 1.0f);
  const glm::vec3 orange = srgb(1.0f, 0.56f, 0.12f);
  const glm::vec3 teal = srgb(0.10f, 0.78f, 0.74f);

  if (sdBox(p, {0.5f, 0.5f}, {0.47f, 0.47f}, 0.09f) > 0.0f) return outside;
  glm::vec3 c = tile;

  // Tree edges: root -> inner nodes -> leaves, drawn under the boxes.
  const glm::vec2 root{0.5f, 0.76f}, inner[2] = {{0.285f, 0.505f}, {0.715f, 0.505f}};
  const glm::vec2 leaves[4] = {{0.17f, 0.235f}, {0.39f, 0.235f}, {0.61f, 0.235f}, {0.83f, 0.235f}};
  constexpr float kEdge = 0.011f;
  for (int i = 0; i < 2; ++i)
    if (sdSegment(p, root, inner[i]) < kEdge) c = white;
  for (int i = 0; i < 4; ++i)
    if (sdSegment(p, inner[i / 2], leaves[i]) < kEdge) c = white;

  // Root: a wide box outline (the scene bounds) with a filled core.
  const float dRoot = sdBox(p, root, {0.2f, 0.085f}, 0.02f);
  if (dRoot < 0.0f) c = tile;
  if (std::abs(dRoot) < 0.016f) c = white;
  if (sdBox(p, root, {0.05f, 0.03f}, 0.01f) < 0.0f) c = orange;

  // Inner nodes: orange outlines.
  for (const glm::vec2& q : inner) {
    const float d = sdBox(p, q, {0.16f, 0.075f}, 0.018f);
    if (d < 0.0f) c = tile;
    if (std::abs(d) < 0.014f) c = orange;
  }

  // Leaves: solid boxes, alternately teal and orange, each holding a white triangle (a primitive).
  for (int i = 0; i < 4; ++i) {
    const glm::vec2 q = leaves[i];
    if (sdBox(p, q, {0.085f, 0.075f}, 0.016f) < 0.0f) {
      c = (i % 2 == 0) ? teal : orange;
      const float flip = (i % 2 == 0) ? 1.0f : -1.0f;
      if (inTriangle(p, q + glm::vec2(-0.045f, -0.038f * flip), q + glm::vec2(0.05f, -0.03f * flip),
                     q + glm::vec2(-0.005f, 0.045f * flip)))
        c = white;
    }
  }
  return c;
}

}  // namespace

Image makeLogoTexture(int size) {
  if (size < 8 || size > 8192) throw std::invalid_argument("makeLogoTexture: size " + std::to_string(size));
  Image img;
  img.width = img.height = size;
  img.name = "builtin:logo";
  img.texels.resize(size_t(size) * size);
  // Colours at the pixel corners; a pixel whose corners and centre agree is taken as flat, the rest
  // (edges: a few percent of pixels) get 4x4 supersampling, i.e. 17 coverage levels.
  std::vector<glm::vec3> corner(size_t(size + 1) * (size + 1));
  for (int y = 0; y <= size; ++y)
    for (int x = 0; x <= size; ++x) corner[size_t(y) * (size + 1) + x] = logoColor(glm::vec2(x, y) / float(size));
  constexpr int kSub = 4;
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const glm::vec3 c00 = corner[size_t(y) * (size + 1) + x], c10 = corner[size_t(y) * (size + 1) + x + 1],
                      c01 = corner[size_t(y + 1) * (size + 1) + x], c11 = corner[size_t(y + 1) * (size + 1) + x + 1];
      const glm::vec3 centre = logoColor(glm::vec2(x + 0.5f, y + 0.5f) / float(size));
      glm::vec3 color = centre;
      if (c00 != centre || c10 != centre || c01 != centre || c11 != centre) {
        glm::vec3 sum(0.0f);
        for (int sy = 0; sy < kSub; ++sy)
          for (int sx = 0; sx < kSub; ++sx)
            sum += logoColor(glm::vec2(x + (sx + 0.5f) / kSub, y + (sy + 0.5f) / kSub) / float(size));
        color = sum / float(kSub * kSub);
      }
      img.texels[size_t(y) * size + x] = glm::vec4(color, 1.0f);
    }
  return img;
}

Image makeCheckerTexture(int size, int squares, glm::vec3 a, glm::vec3 b) {
  if (size < 1 || size > 8192 || squares < 1 || squares > size)
    throw std::invalid_argument("makeCheckerTexture: size " + std::to_string(size) + ", squares " + std::to_string(squares));
  Image img;
  img.width = img.height = size;
  img.name = "builtin:checker";
  img.texels.resize(size_t(size) * size);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const int cx = x * squares / size, cy = y * squares / size;
      img.texels[size_t(y) * size + x] = glm::vec4(((cx + cy) % 2 == 0) ? a : b, 1.0f);
    }
  return img;
}

// ---- meshes --------------------------------------------------------------------------------------------

namespace {
// The resource limit (procedural.hpp): `triangles` is computed in 64 bits from the request, so a
// resolution whose product overflows int is caught too.
void checkTriangleBudget(const std::string& request, uint64_t triangles) {
  if (triangles > kMaxProceduralTriangles)
    throw InputError(request + ": asks for " + std::to_string(triangles) + " triangles, more than the limit of " +
                     std::to_string(kMaxProceduralTriangles) +
                     " (kMaxProceduralTriangles, datasets/procedural.hpp: about 16-24 GB with the BVH)");
}
}  // namespace

Mesh makeUvSphere(int segments, int rings) {
  if (segments < 3 || rings < 2) throw std::invalid_argument("makeUvSphere: needs segments >= 3 and rings >= 2");
  checkTriangleBudget("makeUvSphere(" + std::to_string(segments) + ", " + std::to_string(rings) + ")",
                      2 * uint64_t(segments) * uint64_t(rings - 1));
  Mesh m;
  m.name = "uv-sphere";
  for (int i = 0; i <= rings; ++i) {
    const float v = float(i) / rings, theta = kPi * (v - 0.5f);  // latitude, -pi/2 at the south pole
    for (int j = 0; j <= segments; ++j) {
      const float u = float(j) / segments, phi = 2.0f * kPi * u;
      // Exact poles and seam: cos/sin of the end angles are not exactly 0/1 in float.
      const float cosT = (i == 0 || i == rings) ? 0.0f : std::cos(theta);
      const float sinT = i == 0 ? -1.0f : i == rings ? 1.0f : std::sin(theta);
      const float cosP = (j == segments) ? 1.0f : std::cos(phi), sinP = (j == segments) ? 0.0f : std::sin(phi);
      const glm::vec3 p(cosT * cosP, sinT, -cosT * sinP);
      m.positions.push_back(p);
      m.normals.push_back(p);
      m.uvs.emplace_back(u, v);
    }
  }
  const uint32_t row = uint32_t(segments) + 1;
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const uint32_t a = i * row + j, b = a + 1, c = a + row, d = c + 1;
      // Counter-clockwise seen from outside: u grows towards -z seen from +y.
      if (i != 0) m.triangles.emplace_back(a, b, c);
      if (i != rings - 1) m.triangles.emplace_back(b, d, c);
    }
  return m;
}

Mesh makeCube(int n) {
  if (n < 1) throw std::invalid_argument("makeCube: n must be >= 1");
  checkTriangleBudget("makeCube(" + std::to_string(n) + ")", 12 * uint64_t(n) * uint64_t(n));
  Mesh m;
  m.name = "cube";
  // Face frames: normal, and u/v axes with u x v = normal (outward, counter-clockwise).
  const glm::vec3 normals[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  const glm::vec3 us[6] = {{0, 0, -1}, {0, 0, 1}, {1, 0, 0}, {1, 0, 0}, {1, 0, 0}, {-1, 0, 0}};
  for (int f = 0; f < 6; ++f) {
    const glm::vec3 nrm = normals[f], u = us[f], v = glm::cross(nrm, u);
    const uint32_t base = uint32_t(m.positions.size());
    for (int i = 0; i <= n; ++i)
      for (int j = 0; j <= n; ++j) {
        // Grid coordinates from integers, so shared edges get bit-identical positions on both faces.
        const float s = float(2 * j - n) / n, t = float(2 * i - n) / n;
        m.positions.push_back(nrm + s * u + t * v);
        m.normals.push_back(nrm);
        m.uvs.emplace_back(float(j) / n, float(i) / n);
      }
    const uint32_t row = uint32_t(n) + 1;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        const uint32_t a = base + i * row + j, b = a + 1, c = a + row, d = c + 1;
        m.triangles.emplace_back(a, b, d);
        m.triangles.emplace_back(a, d, c);
      }
  }
  return m;
}

Mesh makeGridPlane(int nx, int nz) {
  if (nx < 1 || nz < 1) throw std::invalid_argument("makeGridPlane: bad resolution");
  checkTriangleBudget("makeGridPlane(" + std::to_string(nx) + ", " + std::to_string(nz) + ")",
                      2 * uint64_t(nx) * uint64_t(nz));
  Mesh m;
  m.name = "grid-plane";
  for (int i = 0; i <= nz; ++i)
    for (int j = 0; j <= nx; ++j) {
      const float x = float(2 * j - nx) / nx, z = float(2 * i - nz) / nz;
      m.positions.emplace_back(x, 0.0f, z);
      m.normals.emplace_back(0.0f, 1.0f, 0.0f);
      m.uvs.emplace_back(float(j) / nx, float(i) / nz);
    }
  const uint32_t row = uint32_t(nx) + 1;
  for (int i = 0; i < nz; ++i)
    for (int j = 0; j < nx; ++j) {
      const uint32_t a = i * row + j, b = a + 1, c = a + row, d = c + 1;
      // Counter-clockwise seen from +Y: (x, z) -> (x+1, z) -> (x+1, z+1) turns left when seen from above.
      m.triangles.emplace_back(a, d, b);
      m.triangles.emplace_back(a, c, d);
    }
  return m;
}

Mesh makeTriangleSoup(size_t count, uint64_t seed, float minSize, float maxSize) {
  if (!(minSize > 0.0f && maxSize >= minSize)) throw std::invalid_argument("makeTriangleSoup: bad size range");
  checkTriangleBudget("makeTriangleSoup(" + std::to_string(count) + ")", count);
  Mesh m;
  m.name = "soup" + std::to_string(count);
  SplitMix64 rng(seed);
  const float logRange = std::log(maxSize / minSize);
  m.positions.reserve(3 * count);
  m.triangles.reserve(count);
  for (size_t i = 0; i < count; ++i) {
    const glm::vec3 c = rng.uniform3(0.0f, 1.0f);
    const float size = minSize * std::exp(logRange * rng.uniform());
    const uint32_t base = uint32_t(m.positions.size());
    for (int k = 0; k < 3; ++k)
      m.positions.push_back(c + size * rng.uniform3(-1.0f, 1.0f));
    m.triangles.emplace_back(base, base + 1, base + 2);
  }
  return m;
}

namespace {

// Lattice value noise in [-1, 1]: a hash per integer point, smooth (C1) trilinear blend.
float latticeValue(int x, int y, int z, uint64_t seed) {
  SplitMix64 h(seed ^ (uint64_t(uint32_t(x)) * 0x8DA6B343ull) ^ (uint64_t(uint32_t(y)) * 0xD8163841ull << 1) ^
               (uint64_t(uint32_t(z)) * 0xCB1AB31Full << 2));
  return h.uniform() * 2.0f - 1.0f;
}

float valueNoise(glm::vec3 p, uint64_t seed) {
  const glm::vec3 f = glm::floor(p);
  const glm::ivec3 i(f);
  const glm::vec3 t = p - f, s = t * t * (3.0f - 2.0f * t);  // smoothstep weights
  float v[2][2][2];
  for (int dz = 0; dz < 2; ++dz)
    for (int dy = 0; dy < 2; ++dy)
      for (int dx = 0; dx < 2; ++dx) v[dz][dy][dx] = latticeValue(i.x + dx, i.y + dy, i.z + dz, seed);
  auto lerp = [](float a, float b, float w) { return a + (b - a) * w; };
  const float y0 = lerp(lerp(v[0][0][0], v[0][0][1], s.x), lerp(v[0][1][0], v[0][1][1], s.x), s.y);
  const float y1 = lerp(lerp(v[1][0][0], v[1][0][1], s.x), lerp(v[1][1][0], v[1][1][1], s.x), s.y);
  return lerp(y0, y1, s.z);
}

// Four octaves of value noise (fractional Brownian motion), amplitude halving, frequency doubling.
float fbm(glm::vec3 p, uint64_t seed) {
  float sum = 0.0f, amp = 0.5f;
  for (int o = 0; o < 4; ++o) {
    sum += amp * valueNoise(p, seed + uint64_t(o));
    p *= 2.03f;  // not exactly 2, so octave lattices do not line up
    amp *= 0.5f;
  }
  return sum;
}

}  // namespace

Mesh makeLargeMesh(size_t triangles, uint64_t seed) {
  if (triangles < 100) throw std::invalid_argument("makeLargeMesh: needs at least 100 triangles");
  checkTriangleBudget("makeLargeMesh(" + std::to_string(triangles) + ")", triangles);
  // Sphere part: segments = 2 * rings gives 4 rings (rings - 1) triangles; take the largest that fits 3/4.
  const size_t sphereBudget = triangles * 3 / 4;
  int rings = std::max(2, int(std::sqrt(double(sphereBudget) / 4.0)));
  while (rings > 2 && 4 * size_t(rings) * size_t(rings - 1) > sphereBudget) --rings;
  Mesh m = makeUvSphere(2 * rings, rings);
  m.name = "large" + std::to_string(triangles);
  for (glm::vec3& p : m.positions) p *= 1.0f + 0.18f * fbm(p * 2.5f, seed);  // bumps along the radius
  m.normals.clear();
  m.uvs.clear();

  // Debris: tetrahedra in Gaussian clusters on a shell around the sphere.
  SplitMix64 rng(seed * 0x9E3779B97F4A7C15ull + 7);
  constexpr int kClusters = 48;
  glm::vec3 centres[kClusters];
  float spreads[kClusters];
  for (int c = 0; c < kClusters; ++c) {
    const float radius = rng.uniform(1.4f, 3.5f);  // drawn before the direction (see SplitMix64)
    centres[c] = rng.unitVector() * radius;
    spreads[c] = rng.uniform(0.05f, 0.4f);
  }
  auto addTriangle = [&](glm::vec3 a, glm::vec3 b, glm::vec3 c) {
    const uint32_t base = uint32_t(m.positions.size());
    m.positions.push_back(a);
    m.positions.push_back(b);
    m.positions.push_back(c);
    m.triangles.emplace_back(base, base + 1, base + 2);
  };
  const float logRange = std::log(0.06f / 0.003f);  // sizes 0.003 .. 0.06, log-uniform
  while (m.triangles.size() < triangles) {
    const int c = int(rng.next() % kClusters);
    const glm::vec3 centre =
        centres[c] + spreads[c] * rng.normal3();
    const float size = 0.003f * std::exp(logRange * rng.uniform());
    const glm::vec3 p0 = centre + size * rng.unitVector(), p1 = centre + size * rng.unitVector(),
                    p2 = centre + size * rng.unitVector(), p3 = centre + size * rng.unitVector();
    const size_t left = triangles - m.triangles.size();
    addTriangle(p0, p1, p2);
    if (left >= 4) {
      addTriangle(p0, p3, p1);
      addTriangle(p1, p3, p2);
      addTriangle(p2, p3, p0);
    }
  }
  return m;
}

}  // namespace bvhlab
