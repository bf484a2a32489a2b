// lbvh-gpu, morton phase 2 (one invocation): the quantisation grid of builders/morton.cpp from the
// centroid bounds: min, and per axis scale = float(2^21) / extent rounded as the CPU's float division
// rounds it (correctly), 0 where the axis has no extent or the quotient overflows a float.
layout(local_size_x = 1) in;
layout(std430, binding = 0) readonly buffer Bounds { uint boundKeys[6]; };
layout(std430, binding = 1) writeonly buffer Grid { float grid[6]; };  // min xyz, scale xyz
uniform int u_cube;  // MortonGrid::Cube: every axis over the longest extent

float fromKey(uint k) { return uintBitsToFloat((k & 0x80000000u) != 0u ? k & 0x7fffffffu : ~k); }

// 2^21 / e correctly rounded to float, for a finite e > 0; 0 when that is +inf. GLSL's float division
// is only accurate to 2.5 ulp, so the quotient is found exactly: its double approximation, rounded to
// float, is within one float ulp of the correctly rounded quotient; of that float and its two
// neighbours the correctly rounded one has the smallest |2^21 - s e| (|a/e - s| = |a - s e| / e).
// Every s * e is exact in double (24 + 24 significant bits) and so is 2^21 - s * e (Sterbenz: s * e
// is within a factor 2 of 2^21). A quotient of two floats is never exactly halfway between two
// floats, so there is no tie to break.
float roundedScale(float e) {
  const double a = 2097152.0LF;
  const double b = double(e);
  // The float quotient is +inf exactly when a / b >= 2^128 - 2^103, the midpoint above FLT_MAX (a tie
  // there rounds to even, i.e. up); (2^25 - 1) * 2^103 * b is exact (25 + 24 bits).
  precise double limit = 33554431.0LF * ldexp(1.0LF, 103) * b;
  if (a >= limit) return 0.0;
  float s0 = float(a / b);
  if (isinf(s0)) s0 = uintBitsToFloat(0x7f7fffffu);
  uint u0 = floatBitsToUint(s0);
  float best = s0;
  precise double bestErr = abs(a - double(s0) * b);
  for (int d = -1; d <= 1; d += 2) {
    float s = uintBitsToFloat(uint(int(u0) + d));
    if (isinf(s) || !(s > 0.0)) continue;
    precise double err = abs(a - double(s) * b);
    if (err < bestErr) { bestErr = err; best = s; }
  }
  return best;
}

void main() {
  precise vec3 lo = vec3(fromKey(boundKeys[0]), fromKey(boundKeys[1]), fromKey(boundKeys[2]));
  precise vec3 hi = vec3(fromKey(boundKeys[3]), fromKey(boundKeys[4]), fromKey(boundKeys[5]));
  precise vec3 extents = hi - lo;
  float longest = max(max(extents.x, extents.y), extents.z);
  for (int a = 0; a < 3; ++a) {
    grid[a] = lo[a];
    float e = u_cube != 0 ? longest : extents[a];
    grid[3 + a] = extents[a] > 0.0 ? roundedScale(e) : 0.0;
  }
}
