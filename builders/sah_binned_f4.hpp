// sah-binned's SIMD vocabulary: four floats (SSE2 where the target has it, a plain loop elsewhere),
// a box as two of them, the half area with the same bits as Aabb::halfArea, and branch-free selects.
// Private to builders/sah_binned*.cpp.
#pragma once
#include <bit>
#include <cstdint>
#include <cstring>
#include <limits>

// BVHLAB_NO_SIMD forces the portable path (to check that it builds the same trees).
#if defined(__SSE2__) && !defined(BVHLAB_NO_SIMD)
#define BVHLAB_BINNED_SSE 1
#include <emmintrin.h>
#endif

#include <glm/glm.hpp>

#include "builders/bvh.hpp"

namespace bvhlab::binned {

constexpr float kInf = std::numeric_limits<float>::infinity();

// Four floats with the handful of operations binning needs: SSE where the target has it, a plain
// loop elsewhere. (GCC does not vectorise the loop form itself: std::min/max on floats are not
// min/max instructions to it without -ffinite-math-only.) Lanes 0..2 are x, y, z, validated finite;
// lane 3 is bookkeeping (an index or a count as an integer, or +-inf / 0 padding) that reaches no
// arithmetic whose result is read and decides nothing.
struct alignas(16) F4 {
#if defined(BVHLAB_BINNED_SSE)
  __m128 v;
  static F4 set(float x, float y, float z, float w) { return {_mm_setr_ps(x, y, z, w)}; }
  static F4 splat(float x) { return {_mm_set1_ps(x)}; }
  void store(float* p) const { _mm_store_ps(p, v); }
  friend F4 min(F4 a, F4 b) { return {_mm_min_ps(a.v, b.v)}; }
  friend F4 max(F4 a, F4 b) { return {_mm_max_ps(a.v, b.v)}; }
  friend F4 operator-(F4 a, F4 b) { return {_mm_sub_ps(a.v, b.v)}; }
  friend F4 operator*(F4 a, F4 b) { return {_mm_mul_ps(a.v, b.v)}; }
  friend F4 operator/(F4 a, F4 b) { return {_mm_div_ps(a.v, b.v)}; }
  // Truncation toward zero of values in [0, 2^31).
  void truncate(int32_t* out) const { _mm_store_si128(reinterpret_cast<__m128i*>(out), _mm_cvttps_epi32(v)); }
  // Lane 3 as an integer (a bin's count), and the same vector with it incremented or zeroed.
  uint32_t lane3() const { return uint32_t(_mm_cvtsi128_si32(_mm_shuffle_epi32(_mm_castps_si128(v), 0xff))); }
  F4 plusOneIn3() const { return {_mm_castsi128_ps(_mm_add_epi32(_mm_castps_si128(v), _mm_setr_epi32(0, 0, 0, 1)))}; }
  F4 xyz() const { return {_mm_and_ps(v, _mm_castsi128_ps(_mm_setr_epi32(-1, -1, -1, 0)))}; }
  static F4 withLane3(float x, float y, float z, uint32_t w) {
    return {_mm_castsi128_ps(_mm_setr_epi32(std::bit_cast<int32_t>(x), std::bit_cast<int32_t>(y), std::bit_cast<int32_t>(z), int32_t(w)))};
  }
#else
  float v[4];
  static F4 set(float x, float y, float z, float w) { return {{x, y, z, w}}; }
  static F4 splat(float x) { return {{x, x, x, x}}; }
  void store(float* p) const { std::memcpy(p, v, sizeof v); }
  template <class Op>
  static F4 map(F4 a, F4 b, Op op) { return {{op(a.v[0], b.v[0]), op(a.v[1], b.v[1]), op(a.v[2], b.v[2]), op(a.v[3], b.v[3])}}; }
  friend F4 min(F4 a, F4 b) { return map(a, b, [](float x, float y) { return x < y ? x : y; }); }
  friend F4 max(F4 a, F4 b) { return map(a, b, [](float x, float y) { return x > y ? x : y; }); }
  friend F4 operator-(F4 a, F4 b) { return map(a, b, [](float x, float y) { return x - y; }); }
  friend F4 operator*(F4 a, F4 b) { return map(a, b, [](float x, float y) { return x * y; }); }
  friend F4 operator/(F4 a, F4 b) { return map(a, b, [](float x, float y) { return x / y; }); }
  void truncate(int32_t* out) const { for (int k = 0; k < 4; ++k) out[k] = int32_t(v[k]); }
  uint32_t lane3() const { return std::bit_cast<uint32_t>(v[3]); }
  F4 plusOneIn3() const { F4 r = *this; r.v[3] = std::bit_cast<float>(lane3() + 1); return r; }
  F4 xyz() const { return {{v[0], v[1], v[2], 0.0f}}; }
  static F4 withLane3(float x, float y, float z, uint32_t w) { return {{x, y, z, std::bit_cast<float>(w)}}; }
#endif
  float operator[](int k) const {
    alignas(16) float f[4];
    store(f);
    return f[k];
  }
};

inline F4 point(const glm::vec3& p) { return F4::set(p.x, p.y, p.z, 0.0f); }
inline glm::vec3 vec3(F4 a) {
  alignas(16) float f[4];
  a.store(f);
  return {f[0], f[1], f[2]};
}

// Half the surface area of a non-empty box, e.x * e.y + e.y * e.z + e.z * e.x in float and in that
// order (the products are exact-order-independent; the two sums are done left to right): the same
// bits as Aabb::halfArea, whatever the path.
inline float halfArea(F4 lo, F4 hi) {
#if defined(BVHLAB_BINNED_SSE)
  const __m128 xyz = _mm_castsi128_ps(_mm_setr_epi32(-1, -1, -1, 0));  // lane 3 may hold anything
  const __m128 e = _mm_sub_ps(_mm_and_ps(hi.v, xyz), _mm_and_ps(lo.v, xyz));
  const __m128 p = _mm_mul_ps(e, _mm_shuffle_ps(e, e, _MM_SHUFFLE(3, 0, 2, 1)));  // xy, yz, zx, ww
  const __m128 s = _mm_add_ss(p, _mm_shuffle_ps(p, p, _MM_SHUFFLE(1, 1, 1, 1)));  // xy + yz
  return _mm_cvtss_f32(_mm_add_ss(s, _mm_movehl_ps(p, p)));                        // + zx
#else
  const glm::vec3 e = vec3(hi - lo);
  return e.x * e.y + e.y * e.z + e.z * e.x;
#endif
}

// Branch-free choices (the compiler keeps these as masks: the conditions are data, not control).
inline uint32_t select(bool c, uint32_t a, uint32_t b) {
  const uint32_t m = 0u - uint32_t(c);
  return (a & m) | (b & ~m);
}
inline double select(bool c, double a, double b) {
  const uint64_t m = 0 - uint64_t(c);
  return std::bit_cast<double>((std::bit_cast<uint64_t>(a) & m) | (std::bit_cast<uint64_t>(b) & ~m));
}


// A box as two F4 corners; starts empty (+inf/-inf).
struct Box4 {
  F4 lo = F4::splat(kInf);
  F4 hi = F4::splat(-kInf);

  void grow(F4 l, F4 h) { lo = min(lo, l), hi = max(hi, h); }
  void grow(const Box4& b) { grow(b.lo, b.hi); }
  float halfArea() const { return binned::halfArea(lo, hi); }  // only on non-empty boxes
  Aabb aabb() const { return {vec3(lo), vec3(hi)}; }
};

}  // namespace bvhlab::binned
