// offset_ulp.hpp — C++ mirror of offset_ulp.glsl (Wächter & Binder 2019, Ray Tracing Gems ch. 6;
// the reasoning and the domain are there). glm's floatBitsToInt / intBitsToFloat are GLSL's: a bit
// copy, no conversion.
#pragma once
#include "shaders/common.hpp"

namespace bvhlab::glsl {

constexpr float kOffsetUlpOrigin = 1.0f / 32.0f;
constexpr float kOffsetUlpFloatScale = 1.0f / 65536.0f;
constexpr float kOffsetUlpIntScale = 256.0f;

inline vec3 offsetRayOriginUlp(vec3 p, vec3 n, float magnitude) {
  ivec3 ulps = ivec3(kOffsetUlpIntScale * n);
  ivec3 bitsOffset = mix(ulps, -ulps, lessThan(p, vec3(0.0f)));
  // GLSL's int addition wraps; C++'s signed overflow is undefined, so add as unsigned (C++20 defines
  // the conversion back as the same bits).
  vec3 pUlp = intBitsToFloat(ivec3(uvec3(floatBitsToInt(p)) + uvec3(bitsOffset)));
  vec3 pAbsolute = p + (kOffsetUlpFloatScale * magnitude) * n;
  return mix(pUlp, pAbsolute, lessThan(abs(p), vec3(kOffsetUlpOrigin * magnitude)));
}

}  // namespace bvhlab::glsl
