// Synthetic animation clips for the update-strategy tests (tests/test_updates.cpp,
// tests/test_refit_threads.cpp): a grid whose height is a travelling wave (smooth deformation, the
// triangles keep their neighbours) and a sphere whose triangles fly apart, each on its own random
// velocity (an explosion: spatial coherence breaks down).
#pragma once
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include <glm/glm.hpp>

#include "builders/refit.hpp"

namespace bvhlab::testing {


struct Clip {
  std::vector<std::vector<glm::vec3>> v0, v1, v2;  // per frame
  size_t frames() const { return v0.size(); }
  FrameTriangles frame(size_t f) const { return {v0[f], v1[f], v2[f]}; }
  std::vector<FrameTriangles> all() const {
    std::vector<FrameTriangles> out;
    for (size_t f = 0; f < frames(); ++f) out.push_back(frame(f));
    return out;
  }
  void add(const std::vector<glm::vec3>& a, const std::vector<glm::vec3>& b, const std::vector<glm::vec3>& c) {
    v0.push_back(a), v1.push_back(b), v2.push_back(c);
  }
};

// An nx x nz grid over [1, 2]^2 in x and z (2 triangles per cell), height 1 + a travelling wave. No
// coordinate is ever zero: min/max of -0 and +0 keeps whichever comes first (builders/refit.hpp), and
// the bit-for-bit comparisons here are about boxes, not signs of zero.
inline Clip waveClip(uint32_t nx, uint32_t nz, uint32_t frames) {
  Clip clip;
  for (uint32_t f = 0; f < frames; ++f) {
    const float t = 0.25f * float(f);
    auto p = [&](uint32_t i, uint32_t k) {
      const float x = 1.0f + float(i) / float(nx), z = 1.0f + float(k) / float(nz);
      return glm::vec3(x, 1.0f + 0.15f * std::sin(9.0f * x - t) * std::cos(7.0f * z + 0.5f * t), z);
    };
    std::vector<glm::vec3> a, b, c;
    for (uint32_t k = 0; k < nz; ++k)
      for (uint32_t i = 0; i < nx; ++i) {
        a.push_back(p(i, k)), b.push_back(p(i + 1, k)), c.push_back(p(i + 1, k + 1));
        a.push_back(p(i, k)), b.push_back(p(i + 1, k + 1)), c.push_back(p(i, k + 1));
      }
    clip.add(a, b, c);
  }
  return clip;
}

// A UV sphere (nu x nv quads, centre (3, 3, 3), radius 1) whose triangles move rigidly, each with its
// own velocity: random direction, speed 0..`speed` per frame.
inline Clip explodeClip(uint32_t nu, uint32_t nv, uint32_t frames, float speed = 0.2f, uint32_t seed = 5) {
  std::vector<glm::vec3> a, b, c;
  const float pi = 3.14159265358979f;
  auto p = [&](uint32_t i, uint32_t k) {
    const float phi = 2.0f * pi * float(i % nu) / float(nu), theta = pi * (0.05f + 0.9f * float(k) / float(nv));
    return glm::vec3(3.0f) + glm::vec3(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi));
  };
  for (uint32_t k = 0; k < nv; ++k)
    for (uint32_t i = 0; i < nu; ++i) {
      a.push_back(p(i, k)), b.push_back(p(i + 1, k)), c.push_back(p(i + 1, k + 1));
      a.push_back(p(i, k)), b.push_back(p(i + 1, k + 1)), c.push_back(p(i, k + 1));
    }
  std::mt19937 rng(seed);
  std::normal_distribution<float> normal;
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::vector<glm::vec3> velocity(a.size());
  for (glm::vec3& v : velocity) {
    const float z = normal(rng), y = normal(rng), x = normal(rng);  // sequenced: same draws on every compiler
    v = glm::normalize(glm::vec3(x, y, z) + glm::vec3(1e-3f)) * (speed * unit(rng));
  }
  Clip clip;
  for (uint32_t f = 0; f < frames; ++f) {
    std::vector<glm::vec3> fa(a.size()), fb(a.size()), fc(a.size());
    for (size_t i = 0; i < a.size(); ++i) {
      const glm::vec3 d = float(f) * velocity[i];
      fa[i] = a[i] + d, fb[i] = b[i] + d, fc[i] = c[i] + d;
    }
    clip.add(fa, fb, fc);
  }
  return clip;
}

}  // namespace bvhlab::testing
