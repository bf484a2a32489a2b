// offset_ulp.glsl — secondary-ray origins moved off the surface by a number of float spacings
// (ulps) instead of a fixed relative epsilon: Wächter & Binder (2019), "A Fast and Robust Method for
// Avoiding Self-Intersection", Ray Tracing Gems, chapter 6. Alternative to offsetRayOrigin in
// shade.glsl. C++ mirror: offset_ulp.hpp.
//
// The error of a computed hit point grows with its magnitude in ulps, so the offset is a fixed
// number of ulps per coordinate (up to kOffsetUlpIntScale, scaled by the normal's component), added
// to the float's bit pattern as an integer. Near 0 the ulp shrinks without bound while the absolute
// error of the hit point does not, so below kOffsetUlpOrigin a fixed absolute offset is used instead.
// The constants are the chapter's (it derives them from measured self-intersection on its scenes),
// for a hit point computed from magnitudes around 1. Its absolute branch stands for the error of a
// point computed as o + t d, which grows with max|o| + t |d| (shade.glsl's hitMagnitude), not with
// |p|: so here the threshold and the absolute offset are those constants times that magnitude. The
// chapter's fixed values fail at other scales (acne on a floor at y = 0 of a scene scaled by 100; an
// offset as large as a scene scaled by 1e-4).
const float kOffsetUlpOrigin = 1.0 / 32.0;      // |coordinate| below this (x magnitude): absolute offset
const float kOffsetUlpFloatScale = 1.0 / 65536.0;  // that absolute offset per unit of n (x magnitude)
const float kOffsetUlpIntScale = 256.0;         // ulps per unit of n elsewhere

// p: a point on the surface; n: the (unit) direction to move it in, e.g. the normal facing the side
// the new ray leaves into (-n for a refracted ray). Domain: |p| components below 2^127 (adding at most
// 256 to the bit pattern of a larger float could reach inf/NaN).
vec3 offsetRayOriginUlp(vec3 p, vec3 n, float magnitude) {
  ivec3 ulps = ivec3(kOffsetUlpIntScale * n);  // truncation toward 0, as the chapter's int cast
  // The bit pattern of a negative float grows with its magnitude: moving toward +n means subtracting.
  ivec3 bitsOffset = mix(ulps, -ulps, lessThan(p, vec3(0.0)));
  vec3 pUlp = intBitsToFloat(floatBitsToInt(p) + bitsOffset);
  vec3 pAbsolute = p + (kOffsetUlpFloatScale * magnitude) * n;
  return mix(pUlp, pAbsolute, lessThan(abs(p), vec3(kOffsetUlpOrigin * magnitude)));
}
