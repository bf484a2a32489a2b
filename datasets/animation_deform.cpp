// Procedural mesh deformations (datasets/animation.hpp: wave, twist, breathe, explode), evaluated in
// double precision in object space and rounded to float once by the caller. Each is exactly the rest
// mesh at t = 0: its displacement, angle or velocity term is a product with sin(0) = 0 (or zero elapsed
// time), and c + (p - c) in double rounds back to the float p.
#include <cmath>
#include <numeric>

#include <glm/gtc/constants.hpp>

#include "datasets/animation.hpp"
#include "datasets/random_draws.hpp"

namespace bvhlab {
namespace {

constexpr double kTwoPi = 2.0 * glm::pi<double>();

// Rotation of v about the unit axis a by `angle` radians (Rodrigues).
glm::dvec3 rotateAbout(const glm::dvec3& v, const glm::dvec3& a, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  return v * c + glm::cross(a, v) * s + a * (glm::dot(a, v) * (1.0 - c));
}

glm::dmat3 rotationMatrix(const glm::dvec3& a, double angle) {
  glm::dmat3 r;
  for (int i = 0; i < 3; ++i) {
    glm::dvec3 e(0.0);
    e[i] = 1.0;
    r[i] = rotateAbout(e, a, angle);
  }
  return r;
}

// splitmix64 (Steele, Lea & Flood, "Fast splittable pseudorandom number generators", OOPSLA 2014):
// a per-piece stream keyed by (seed, piece), so each piece's draw depends on nothing else.
struct SplitMix {
  uint64_t state;
  uint64_t next() {
    uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double unit() { return double(next() >> 11) * 0x1.0p-53; }  // [0, 1)
};

// A point in the unit ball (rejection from the cube: deterministic for a given stream).
glm::dvec3 inUnitBall(SplitMix& rng) {
  for (;;) {
    // In a fixed order, so a seed gives the same ball point with every compiler (datasets/random_draws.hpp).
    const glm::dvec3 r = draw3<glm::dvec3>([&] { return 2.0 * rng.unit() - 1.0; });
    if (glm::dot(r, r) <= 1.0) return r;
  }
}

uint32_t findRoot(std::vector<uint32_t>& parent, uint32_t v) {
  while (parent[v] != v) v = parent[v] = parent[parent[v]];
  return v;
}

}  // namespace

void deformPositions(const ObjectAnimation& anim, const Mesh& rest, double t, std::vector<glm::dvec3>& out) {
  const Deform& d = anim.deform;
  const size_t n = rest.positions.size();
  out.resize(n);
  switch (d.kind) {
    case DeformKind::None:
      for (size_t i = 0; i < n; ++i) out[i] = glm::dvec3(rest.positions[i]);
      break;
    case DeformKind::Wave: {
      const double s = d.amplitude * std::sin(kTwoPi * d.frequency * t);
      for (size_t i = 0; i < n; ++i) {
        const glm::dvec3 p(rest.positions[i]);
        out[i] = p + d.axis * (s * std::sin(kTwoPi * glm::dot(p - d.centre, d.direction) / d.wavelength));
      }
      break;
    }
    case DeformKind::Twist: {
      const double perLength = glm::radians(d.angleDeg) * std::sin(kTwoPi * d.frequency * t) / anim.halfHeight;
      for (size_t i = 0; i < n; ++i) {
        const glm::dvec3 v = glm::dvec3(rest.positions[i]) - d.centre;
        out[i] = d.centre + rotateAbout(v, d.axis, perLength * glm::dot(v, d.axis));
      }
      break;
    }
    case DeformKind::Breathe: {
      const double k = 1.0 + d.amplitude * std::sin(kTwoPi * d.frequency * t);
      for (size_t i = 0; i < n; ++i) out[i] = d.centre + (glm::dvec3(rest.positions[i]) - d.centre) * k;
      break;
    }
    case DeformKind::Explode: {
      const double elapsed = std::max(0.0, t - d.start);
      for (size_t i = 0; i < n; ++i)
        out[i] = glm::dvec3(rest.positions[i]) + anim.pieceVelocity[anim.vertexPiece[i]] * elapsed;
      break;
    }
  }
}

glm::dmat3 deformJacobian(const ObjectAnimation& anim, const glm::dvec3& p, double t) {
  const Deform& d = anim.deform;
  switch (d.kind) {
    case DeformKind::None:
    case DeformKind::Explode:  // pieces translate
      return glm::dmat3(1.0);
    case DeformKind::Wave: {
      const double s = d.amplitude * std::sin(kTwoPi * d.frequency * t);
      const double k = kTwoPi / d.wavelength;
      return glm::dmat3(1.0) + glm::outerProduct(d.axis, d.direction) * (s * k * std::cos(k * glm::dot(p - d.centre, d.direction)));
    }
    case DeformKind::Twist: {
      const double perLength = glm::radians(d.angleDeg) * std::sin(kTwoPi * d.frequency * t) / anim.halfHeight;
      const glm::dvec3 v = p - d.centre;
      const glm::dmat3 r = rotationMatrix(d.axis, perLength * glm::dot(v, d.axis));
      // d/dp [R(theta(p)) v] = R + (axis x R v) (dtheta/dp)^T, dtheta/dp = perLength * axis.
      return r + glm::outerProduct(glm::cross(d.axis, r * v), d.axis * perLength);
    }
    case DeformKind::Breathe:
      return glm::dmat3(1.0 + d.amplitude * std::sin(kTwoPi * d.frequency * t));
  }
  return glm::dmat3(1.0);
}

Mesh unweldTriangles(const Mesh& mesh) {
  Mesh out;
  out.name = mesh.name;
  out.material = mesh.material;
  out.positions.reserve(3 * mesh.triangles.size());
  out.triangles.reserve(mesh.triangles.size());
  for (const glm::uvec3& t : mesh.triangles) {
    const uint32_t base = uint32_t(out.positions.size());
    for (int k = 0; k < 3; ++k) {
      out.positions.push_back(mesh.positions[t[k]]);
      if (!mesh.normals.empty()) out.normals.push_back(mesh.normals[t[k]]);
      if (!mesh.uvs.empty()) out.uvs.push_back(mesh.uvs[t[k]]);
    }
    out.triangles.emplace_back(base, base + 1, base + 2);
  }
  return out;
}

void prepareExplode(ObjectAnimation& anim, const Mesh& rest) {
  const Deform& d = anim.deform;
  const size_t n = rest.positions.size();
  // Pieces: connected components of the triangles' vertex sharing (union-find), or one per triangle.
  std::vector<uint32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0u);
  if (d.componentPieces)
    for (const glm::uvec3& t : rest.triangles) {
      const uint32_t a = findRoot(parent, t.x);
      parent[findRoot(parent, t.y)] = a;
      parent[findRoot(parent, t.z)] = a;
    }
  else
    for (const glm::uvec3& t : rest.triangles) parent[t.y] = parent[t.z] = t.x;  // unwelded: unique corners
  // Number pieces in order of first appearance in the triangle list (deterministic).
  anim.vertexPiece.assign(n, UINT32_MAX);
  std::vector<uint32_t> rootPiece(n, UINT32_MAX);
  std::vector<glm::dvec3> sum;
  std::vector<double> count;
  for (const glm::uvec3& t : rest.triangles)
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = t[k];
      if (anim.vertexPiece[v] != UINT32_MAX) continue;
      const uint32_t root = findRoot(parent, v);
      if (rootPiece[root] == UINT32_MAX) {
        rootPiece[root] = uint32_t(sum.size());
        sum.emplace_back(0.0);
        count.push_back(0.0);
      }
      const uint32_t piece = rootPiece[root];
      anim.vertexPiece[v] = piece;
      sum[piece] += glm::dvec3(rest.positions[v]);
      count[piece] += 1.0;
    }
  for (uint32_t& p : anim.vertexPiece)
    if (p == UINT32_MAX) p = 0;  // a vertex no triangle uses: moves with piece 0, invisible either way
  anim.pieceVelocity.resize(sum.size());
  for (size_t piece = 0; piece < sum.size(); ++piece) {
    SplitMix rng{d.seed * 0x9E3779B97F4A7C15ull ^ (uint64_t(piece) + 1) * 0xD1B54A32D192ED03ull};
    const double u = rng.unit();
    const glm::dvec3 r = inUnitBall(rng);
    const glm::dvec3 away = sum[piece] / count[piece] - d.centre;
    const double len = glm::length(away);
    // A piece centred exactly on the centre has no outward direction: its random one (r is drawn from
    // the ball; a zero draw, probability 0, falls back to +Y).
    glm::dvec3 dir = len > 0.0 ? away / len : (glm::length(r) > 0.0 ? glm::normalize(r) : glm::dvec3(0, 1, 0));
    // |dir + jitter r| >= 1 - jitter > 0 for jitter < 1, and its dot with dir is >= 1 - jitter: outward.
    dir = glm::normalize(dir + d.jitter * r);
    anim.pieceVelocity[piece] = dir * (d.speed * (1.0 - d.speedJitter * u));
  }
}

}  // namespace bvhlab
