#include "datasets/bench_generators.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "datasets/procedural.hpp"

namespace bvhlab {

namespace {

constexpr float kPi = 3.14159265358979f;

// Appends triangles up to a fixed budget and silently drops everything past it, so every generator
// emits exactly its budget: the structures are planned to fit, the last one may be cut short, and
// fill() tops up whatever planning left over.
class Builder {
 public:
  explicit Builder(uint64_t budget) : budget_(budget) {
    mesh_.triangles.reserve(size_t(budget));
    mesh_.positions.reserve(size_t(budget));  // a hint: 0.5 (grids) to 2 (quads) vertices per triangle
  }
  uint64_t left() const { return budget_ - mesh_.triangles.size(); }
  bool full() const { return left() == 0; }
  uint32_t vert(glm::vec3 p) {
    mesh_.positions.push_back(p);
    return uint32_t(mesh_.positions.size() - 1);
  }
  void tri(uint32_t a, uint32_t b, uint32_t c) {
    if (!full()) mesh_.triangles.emplace_back(a, b, c);
  }
  void tri(glm::vec3 a, glm::vec3 b, glm::vec3 c) {
    if (full()) return;
    const uint32_t i = vert(a);
    vert(b);
    vert(c);
    tri(i, i + 1, i + 2);
  }
  // Two triangles a b c, a c d (counter-clockwise seen from the front).
  void quad(glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d) {
    if (left() < 2) {
      tri(a, b, c);
      return;
    }
    const uint32_t i = vert(a);
    vert(b);
    vert(c);
    vert(d);
    tri(i, i + 1, i + 2);
    tri(i, i + 2, i + 3);
  }
  // An axis-aligned box as 12 triangles (fewer if the budget runs out).
  void box(glm::vec3 lo, glm::vec3 hi) {
    const glm::vec3 c[8] = {{lo.x, lo.y, lo.z}, {hi.x, lo.y, lo.z}, {hi.x, hi.y, lo.z}, {lo.x, hi.y, lo.z},
                            {lo.x, lo.y, hi.z}, {hi.x, lo.y, hi.z}, {hi.x, hi.y, hi.z}, {lo.x, hi.y, hi.z}};
    static constexpr int kFaces[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 4, 7, 3},
                                         {1, 2, 6, 5}, {0, 1, 5, 4}, {3, 7, 6, 2}};
    for (const auto& f : kFaces) quad(c[f[0]], c[f[1]], c[f[2]], c[f[3]]);
  }
  // Tops up the budget with small random triangles (edge ~`size`) in the box centre +- half.
  void fill(glm::vec3 centre, glm::vec3 half, float size, SplitMix64& rng) {
    while (!full()) {
      const glm::vec3 p = centre + half * rng.uniform3(-1.0f, 1.0f);
      const glm::vec3 c = p + size * rng.unitVector();  // the last corner is drawn first (see SplitMix64)
      const glm::vec3 b = p + size * rng.unitVector();
      tri(p, b, c);
    }
  }
  Mesh take() { return std::move(mesh_); }

 private:
  uint64_t budget_;
  Mesh mesh_;
};

// ---- stadium ----

// The (2,3) torus knot, in [-3, 3] x [-1, 1] x [-3, 3] before scaling.
glm::vec3 torusKnot(float t) {
  const float r = std::cos(3.0f * t) + 2.0f;
  return {r * std::cos(2.0f * t), -std::sin(3.0f * t), r * std::sin(2.0f * t)};
}

}  // namespace

Mesh makeStadium(uint64_t triangles, uint64_t seed) {
  checkBenchRequest("stadium", int64_t(triangles));
  Builder b(triangles);
  SplitMix64 rng(seed);
  // Enclosure: a few thousand large triangles at most (4096), never more than 1/16 of the budget so the
  // dense object always dominates the count, as a detailed prop dominates a real stadium model.
  const uint64_t enclosure = std::min<uint64_t>(4096, triangles / 16);
  // The pitch: one quad 600 m wide under the object (2 triangles that span its whole region).
  constexpr float kPitch = 300.0f;
  b.quad({-kPitch, 0, -kPitch}, {-kPitch, 0, kPitch}, {kPitch, 0, kPitch}, {kPitch, 0, -kPitch});
  // The bowl: a surface of revolution, `segs` around, `rows` tiers rising from r = 400 to 1000 m and
  // y = 0 to 190 m (a stadium's rake), at least 4 rows when the budget allows.
  const uint64_t segs = std::clamp<uint64_t>((enclosure - 2) / (2 * 4), 4, 64);
  const uint64_t rows = std::max<uint64_t>(1, (enclosure - 2) / (2 * segs));
  // The seed turns the bowl by 0.02 rad per unit (within one segment; 4099 is a prime period), so
  // different seeds give different meshes even when no flakes are needed below.
  const float jitter = std::fmod(0.02f * float(seed % 4099), 2 * kPi / float(segs));
  for (uint64_t i = 0; i < rows; ++i) {
    const float f0 = float(i) / float(rows), f1 = float(i + 1) / float(rows);
    const float r0 = 400.0f + 600.0f * f0, r1 = 400.0f + 600.0f * f1;
    const float y0 = 190.0f * f0 * f0, y1 = 190.0f * f1 * f1;  // steeper towards the top, like upper tiers
    for (uint64_t s = 0; s < segs; ++s) {
      const float a0 = 2 * kPi * float(s) / float(segs) + jitter, a1 = 2 * kPi * float(s + 1) / float(segs) + jitter;
      b.quad({r0 * std::cos(a0), y0, r0 * std::sin(a0)}, {r1 * std::cos(a0), y1, r1 * std::sin(a0)},
             {r1 * std::cos(a1), y1, r1 * std::sin(a1)}, {r0 * std::cos(a1), y0, r0 * std::sin(a1)});
    }
  }
  // The dense object: a torus-knot tube 2.4 m across (1.2e-3 of the 2000 m bowl) at the centre,
  // `sides` around the tube, as many rings along the knot as the rest of the budget allows.
  constexpr uint64_t kSides = 16;
  const uint64_t rings = std::max<uint64_t>(3, b.left() / (2 * kSides));
  constexpr float kScale = 0.4f, kTube = 0.3f;  // knot radius 3 -> 1.2 m; tube 0.12 m
  const glm::vec3 centre(0.0f, 1.2f, 0.0f);
  std::vector<uint32_t> ringStart(static_cast<size_t>(rings));
  for (uint64_t i = 0; i < rings; ++i) {
    const float t = 2 * kPi * float(i) / float(rings);
    const glm::vec3 p = torusKnot(t);
    const glm::vec3 tangent = glm::normalize(torusKnot(t + 1e-3f) - torusKnot(t - 1e-3f));
    // The knot's tangent always has an xz component of length >= 2 (r >= 1, d/dt of angle 2t), so the
    // cross product with +Y never vanishes.
    const glm::vec3 n = glm::normalize(glm::cross(tangent, glm::vec3(0, 1, 0)));
    const glm::vec3 bn = glm::cross(tangent, n);
    for (uint64_t s = 0; s < kSides; ++s) {
      const float a = 2 * kPi * float(s) / float(kSides);
      const uint32_t v = b.vert(centre + kScale * (p + kTube * (std::cos(a) * n + std::sin(a) * bn)));
      if (s == 0) ringStart[size_t(i)] = v;
    }
  }
  for (uint64_t i = 0; i < rings; ++i) {
    const uint32_t r0 = ringStart[size_t(i)], r1 = ringStart[size_t((i + 1) % rings)];
    for (uint32_t s = 0; s < kSides; ++s) {
      const uint32_t s1 = (s + 1) % kSides;
      b.tri(r0 + s, r1 + s, r1 + s1);
      b.tri(r0 + s, r1 + s1, r0 + s1);
    }
  }
  // Fewer than 2 * kSides triangles are left: small flakes on the object (same region, same density).
  b.fill(centre, glm::vec3(1.2f, 0.4f, 1.2f), 0.05f, rng);
  return b.take();
}

// ---- interior ----

Mesh makeInterior(uint64_t triangles, uint64_t seed) {
  checkBenchRequest("interior", int64_t(triangles));
  Builder b(triangles);
  SplitMix64 rng(seed);
  constexpr int kStoreys = 3;
  constexpr float kStorey = 3.0f;   // floor to floor, m
  constexpr float kRoom = 6.0f;     // rooms are 6 x 6 m
  constexpr float kDoorW = 1.0f;
  constexpr int kBands = 6;         // a wall is 6 bands of 0.5 m, each one long thin quad (2 slivers)
  constexpr int kLowBands = 4;      // bands below the 2 m door head (4 x 0.5 m): split around the doorways
  constexpr int kColumnsPerSide = 3;  // 3 x 3 = 9 octagonal columns per room
  constexpr int kColumnSides = 8;
  // Triangles one room costs (two walls: low bands in 2 pieces per room; columns), for planning only:
  // 70% of the budget goes to rooms, the rest to furniture (boxes), which absorbs any planning error.
  constexpr uint64_t kPerRoom = 2 * kLowBands * 2 * 2 + kColumnsPerSide * kColumnsPerSide * kColumnSides * kBands * 2;
  const uint64_t rooms = std::max<uint64_t>(1, triangles * 7 / 10 / kPerRoom / kStoreys);
  const uint64_t nz = std::max<uint64_t>(1, uint64_t(std::sqrt(double(rooms) / 2.0)));  // twice as wide as deep
  const uint64_t nx = std::max<uint64_t>(1, rooms / nz);
  const float W = kRoom * float(nx), D = kRoom * float(nz);
  const float band = kStorey / float(kBands);

  for (int f = 0; f <= kStoreys; ++f) {  // floor slabs (the top one is the roof): 2 triangles each
    const float y = kStorey * float(f);
    b.quad({0, y, 0}, {0, y, D}, {W, y, D}, {W, y, 0});
  }
  for (int f = 0; f < kStoreys; ++f) {
    const float y0 = kStorey * float(f);
    // Walls along x at z = k * kRoom, and along z at x = k * kRoom. The bands above the door head span
    // the whole building (a 60 m x 0.5 m sliver pair at 200k triangles); the low bands are cut around
    // one doorway per room (none in the outer walls).
    for (int axis = 0; axis < 2; ++axis) {
      const uint64_t across = axis == 0 ? nz : nx, along = axis == 0 ? nx : nz;
      const float length = axis == 0 ? W : D;
      auto P = [&](float u, float y, float w) { return axis == 0 ? glm::vec3(u, y, w) : glm::vec3(w, y, u); };
      for (uint64_t k = 0; k <= across; ++k) {
        const float w = kRoom * float(k);
        const bool outer = k == 0 || k == across;
        for (int j = 0; j < kBands; ++j) {
          const float ya = y0 + band * float(j), yb = ya + band;
          if (j >= kLowBands || outer) {
            b.quad(P(0, ya, w), P(length, ya, w), P(length, yb, w), P(0, yb, w));
            continue;
          }
          for (uint64_t r = 0; r < along; ++r) {  // left of the door, right of the door
            const float u0 = kRoom * float(r), door = u0 + 0.5f * kRoom;
            b.quad(P(u0, ya, w), P(door - 0.5f * kDoorW, ya, w), P(door - 0.5f * kDoorW, yb, w), P(u0, yb, w));
            b.quad(P(door + 0.5f * kDoorW, ya, w), P(u0 + kRoom, ya, w), P(u0 + kRoom, yb, w),
                   P(door + 0.5f * kDoorW, yb, w));
          }
        }
      }
    }
    // Stairs in the first room of each storey: 15 steps of 0.2 m rising along z at x = 0.5..1.5.
    constexpr int kSteps = 15;
    for (int s = 0; s < kSteps && f + 1 < kStoreys; ++s) {
      const float z0 = 1.0f + 0.25f * float(s);
      b.box({0.5f, y0 + 0.2f * float(s), z0}, {1.5f, y0 + 0.2f * float(s + 1), z0 + 0.25f});
    }
  }
  // Columns: kColumnsPerSide^2 octagonal prisms (radius 0.15 m) per room, each side a long thin sliver
  // stack of kBands bands, floor to ceiling.
  for (int f = 0; f < kStoreys; ++f)
    for (uint64_t rx = 0; rx < nx; ++rx)
      for (uint64_t rz = 0; rz < nz; ++rz)
        for (int cx = 0; cx < kColumnsPerSide; ++cx)
          for (int cz = 0; cz < kColumnsPerSide; ++cz) {
            const glm::vec3 c(kRoom * (float(rx) + (float(cx) + 0.5f) / kColumnsPerSide), kStorey * float(f),
                              kRoom * (float(rz) + (float(cz) + 0.5f) / kColumnsPerSide));
            for (int s = 0; s < kColumnSides; ++s) {
              const float a0 = 2 * kPi * float(s) / kColumnSides, a1 = 2 * kPi * float(s + 1) / kColumnSides;
              const glm::vec3 d0 = 0.15f * glm::vec3(std::cos(a0), 0, std::sin(a0));
              const glm::vec3 d1 = 0.15f * glm::vec3(std::cos(a1), 0, std::sin(a1));
              for (int j = 0; j < kBands; ++j) {
                const glm::vec3 y(0, band * float(j), 0), y1(0, band * float(j + 1), 0);
                b.quad(c + d0 + y, c + d1 + y, c + d1 + y1, c + d0 + y1);
              }
            }
          }
  // Furniture: random boxes (0.3..1.2 m, tables and cabinets) on the floors until the budget is spent.
  while (b.left() >= 12) {
    const int f = int(rng.next() % kStoreys);
    const glm::vec3 size = rng.uniform3(0.3f, 1.2f);
    const float z = rng.uniform(0.0f, D - size.z), x = rng.uniform(0.0f, W - size.x);  // z first: SplitMix64
    const glm::vec3 lo(x, kStorey * float(f), z);
    b.box(lo, lo + size);
  }
  b.fill({0.5f * W, 0.5f, 0.5f * D}, {0.5f * W, 0.5f, 0.5f * D}, 0.1f, rng);
  return b.take();
}

// ---- hairball ----

Mesh makeHairball(uint64_t triangles, uint64_t seed) {
  checkBenchRequest("hairball", int64_t(triangles));
  Builder b(triangles);
  SplitMix64 rng(seed);
  constexpr int kSegments = 24;         // per strand: 48 triangles
  constexpr float kStep = 0.08f;        // segment length: a strand is ~1.9 long, about the diameter
  constexpr float kHalfWidth = 0.002f;  // ribbons 0.004 wide: triangles 20x longer than wide
  constexpr float kWiggle = 0.35f;      // direction change per segment (a random vector of this length)
  while (!b.full()) {
    const glm::vec3 towards = rng.unitVector();  // drawn before the radius (see SplitMix64)
    glm::vec3 p = 0.9f * std::cbrt(rng.uniform()) * towards;  // uniform in the ball of radius 0.9
    glm::vec3 d = rng.unitVector();
    glm::vec3 side = glm::cross(d, rng.unitVector());
    // A unit vector almost parallel to d gives no side: fall back to an axis that cannot be parallel.
    if (!(glm::length(side) > 1e-3f)) side = glm::cross(d, std::abs(d.x) < 0.5f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0));
    side = kHalfWidth * glm::normalize(side);
    uint32_t a = b.vert(p - side), c = b.vert(p + side);
    for (int s = 0; s < kSegments && !b.full(); ++s) {
      d = glm::normalize(d + kWiggle * rng.unitVector());
      glm::vec3 q = p + kStep * d;
      if (!(glm::length(q) < 1.0f)) {  // leaving the ball: reflect the direction about the surface normal
        const glm::vec3 n = glm::normalize(q);
        d = glm::normalize(d - 2.0f * glm::dot(d, n) * n);
        q = p + kStep * d;
      }
      const glm::vec3 s2 = glm::cross(d, side);  // keep the ribbon's side perpendicular to the strand
      if (glm::length(s2) > 1e-9f) side = kHalfWidth * glm::normalize(glm::cross(s2, d));
      const uint32_t a2 = b.vert(q - side), c2 = b.vert(q + side);
      b.tri(a, a2, c2);
      b.tri(a, c2, c);
      a = a2;
      c = c2;
      p = q;
    }
  }
  return b.take();
}

// ---- terrain ----

namespace {

// Value noise lattice: a hash of (ix, iz, octave, seed) to [0, 1).
float lattice(int64_t ix, int64_t iz, int octave, uint64_t seed) {
  SplitMix64 h(seed * 0x9E3779B97F4A7C15ull ^ (uint64_t(ix) * 0xD1B54A32D192ED03ull) ^
               (uint64_t(iz) * 0xABC98388FB8FAC03ull) ^ (uint64_t(octave) << 56));
  return h.uniform();
}

float valueNoise(float x, float z, int octave, uint64_t seed) {
  const float fx = std::floor(x), fz = std::floor(z);
  const int64_t ix = int64_t(fx), iz = int64_t(fz);
  float tx = x - fx, tz = z - fz;
  tx = tx * tx * (3 - 2 * tx);  // smoothstep: C1 across lattice cells
  tz = tz * tz * (3 - 2 * tz);
  const float a = lattice(ix, iz, octave, seed), b = lattice(ix + 1, iz, octave, seed);
  const float c = lattice(ix, iz + 1, octave, seed), d = lattice(ix + 1, iz + 1, octave, seed);
  return (a + (b - a) * tx) + ((c + (d - c) * tx) - (a + (b - a) * tx)) * tz;
}

}  // namespace

Mesh makeTerrain(uint64_t triangles, uint64_t seed) {
  checkBenchRequest("terrain", int64_t(triangles));
  Builder b(triangles);
  constexpr float kHalf = 500.0f;      // 1 km square
  constexpr float kHeight = 160.0f;    // relief: hills up to 160 m
  constexpr int kOctaves = 7;          // 250 m hills down to ~4 m bumps
  constexpr float kBaseCell = 250.0f;  // lattice spacing of the first octave, m
  // A square-ish grid of nx quads per row, as many rows as the budget needs (the last one partial).
  const uint64_t nx = std::max<uint64_t>(1, uint64_t(std::sqrt(double(triangles) / 2.0)));
  const uint64_t nz = (triangles + 2 * nx - 1) / (2 * nx);
  auto height = [&](float x, float z) {
    float sum = 0, amp = 1, norm = 0, cell = kBaseCell;
    for (int o = 0; o < kOctaves; ++o, amp *= 0.5f, cell *= 0.5f) {  // gain 1/2, lacunarity 2 (fBm)
      sum += amp * valueNoise(x / cell, z / cell, o, seed);
      norm += amp;
    }
    const float h = sum / norm;  // in [0, 1), mostly near 0.5: stretch the contrast and square for valleys
    const float t = std::clamp(1.6f * (h - 0.2f), 0.0f, 1.0f);
    return kHeight * t * t;
  };
  for (uint64_t j = 0; j <= nz; ++j)
    for (uint64_t i = 0; i <= nx; ++i) {
      const float x = -kHalf + 2 * kHalf * float(i) / float(nx), z = -kHalf + 2 * kHalf * float(j) / float(nz);
      b.vert({x, height(x, z), z});
    }
  const uint32_t row = uint32_t(nx + 1);
  for (uint64_t j = 0; j < nz; ++j)
    for (uint64_t i = 0; i < nx; ++i) {
      const uint32_t v = uint32_t(j) * row + uint32_t(i);
      b.tri(v, v + row, v + row + 1);
      b.tri(v, v + row + 1, v + 1);
    }
  return b.take();
}

// ---- registry ----

namespace {
Mesh makeScaling(uint64_t triangles, uint64_t seed) {
  checkBenchRequest("scaling", int64_t(triangles));
  return makeLargeMesh(size_t(triangles), seed);
}
}  // namespace

const std::vector<BenchGenerator>& benchGenerators() {
  static const std::vector<BenchGenerator> generators = {
      {"stadium", "teapot in a stadium: dense torus knot 1e-3 the size of a sparse bowl", makeStadium},
      {"interior", "building: slabs, long sliver walls with doorways, columns, stairs, furniture", makeInterior},
      {"hairball", "tangle of long thin overlapping ribbons in a sphere", makeHairball},
      {"terrain", "fractal heightfield, 1 km square, for grazing views", makeTerrain},
      {"scaling", "makeLargeMesh: bumpy sphere in a clustered cloud, any size (cost vs size)", makeScaling},
  };
  return generators;
}

std::string benchGeneratorNames() {
  std::string s;
  for (const BenchGenerator& g : benchGenerators()) s += (s.empty() ? "" : ", ") + g.name;
  return s;
}

void checkBenchRequest(const std::string& name, int64_t triangles) {
  if (triangles < int64_t(kMinBenchTriangles) || uint64_t(triangles) > uint64_t(kMaxProceduralTriangles))
    throw InputError("generator '" + name + "': triangles must be in [" + std::to_string(kMinBenchTriangles) + ", " +
                     std::to_string(kMaxProceduralTriangles) + "] (got " + std::to_string(triangles) + ")");
}

Mesh generateBenchMesh(const std::string& name, int64_t triangles, uint64_t seed) {
  for (const BenchGenerator& g : benchGenerators())
    if (g.name == name) {
      checkBenchRequest(name, triangles);
      Mesh m = g.make(uint64_t(triangles), seed);
      m.name = "generate:" + name + ":" + std::to_string(triangles) + ":" + std::to_string(seed);
      return m;
    }
  throw InputError("unknown generator '" + name + "' (known: " + benchGeneratorNames() + ")");
}

uint64_t meshContentHash(const Mesh& mesh) {
  uint64_t h = 0xcbf29ce484222325ull;  // FNV-1a 64 offset basis and prime
  auto mix = [&h](const void* data, size_t n) {
    const unsigned char* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 0x100000001b3ull;
  };
  if (!mesh.positions.empty()) mix(mesh.positions.data(), mesh.positions.size() * sizeof(glm::vec3));
  if (!mesh.triangles.empty()) mix(mesh.triangles.data(), mesh.triangles.size() * sizeof(glm::uvec3));
  return h;
}

}  // namespace bvhlab
