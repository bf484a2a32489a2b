#pragma once
// Random vectors from a standard-library engine, drawn in a fixed order so that a seed gives the same
// vectors with every compiler.
//
// In glm::vec3(u(rng), u(rng), u(rng)) the order of the three calls is unspecified: GCC makes the last
// one first, clang the first one, so the same seed gave each compiler its own soups and rays. These draw
// the last coordinate first (z, then y, then x): GCC's order, which is what every seeded input here was
// made with, so those stay as they were and clang now makes the same ones. Where two draws meet in one
// expression elsewhere (two arguments of a call, the operands of *), the code draws them in named steps,
// in that same order. SplitMix64 (procedural.hpp) has the same rule in uniform3 and normal3.

namespace bvhlab {

template <class Vec, class Draw>
Vec draw3(Draw&& draw) {
  const auto z = draw();
  const auto y = draw();
  const auto x = draw();
  return Vec(x, y, z);
}

template <class Vec, class Dist, class Rng>
Vec draw3(Dist& dist, Rng& rng) {
  return draw3<Vec>([&] { return dist(rng); });
}

template <class Vec, class Dist, class Rng>
Vec draw2(Dist& dist, Rng& rng) {
  const auto y = dist(rng);
  const auto x = dist(rng);
  return Vec(x, y);
}

// A point of the plane y = 0: z drawn first, then x.
template <class Vec, class Dist, class Rng>
Vec drawXZ(Dist& dist, Rng& rng) {
  const auto z = dist(rng);
  const auto x = dist(rng);
  return Vec(x, 0, z);
}

}  // namespace bvhlab
