// Compiled ahead of gpubuild_wide_costs.glsl: a double division rounded as IEEE division rounds it,
// whatever the driver's division does (the wide collapse divides every half area by the root's, and a
// quotient one ulp off could change a choice, making the GPU's tree differ from the CPU's).
// tests/test_gpu_pack.cpp runs correctQuotient from both neighbours of the IEEE quotient.

// The neighbours of a positive finite double (its bits as a 64-bit integer, plus or minus one).
double nextUp(double q) {
  uvec2 w = unpackDouble2x32(q);
  w.x += 1u;
  if (w.x == 0u) w.y += 1u;
  return packDouble2x32(w);
}
double nextDown(double q) {
  uvec2 w = unpackDouble2x32(q);
  if (w.x == 0u) w.y -= 1u;
  w.x -= 1u;
  return packDouble2x32(w);
}

// x = hi + lo exactly, hi holding x's upper 26 significant bits (Veltkamp's split, 2^27 + 1 for a
// 53-bit significand; `precise` keeps every operation rounded on its own).
void split(double x, out double hi, out double lo) {
  precise double t = 134217729.0LF * x;
  precise double h = t - (t - x);
  precise double l = x - h;
  hi = h, lo = l;
}

// a - q b exactly, for q one of the two doubles around a / b: Dekker's product gives q b = p + e exactly;
// a - p is exact (two doubles within a factor 2 of each other: Sterbenz's lemma), and so is its
// difference with e, since that residual is itself a double. Only + - * rounded to nearest, which GLSL
// and every GPU give for doubles; no fma, whose fusing Mesa's llvmpipe does not promise.
double residual(double a, double q, double b) {
  precise double p = q * b;
  double qh, ql, bh, bl;
  split(q, qh, ql);
  split(b, bh, bl);
  precise double e = ((qh * bh - p) + qh * bl + ql * bh) + ql * bl;
  precise double r = (a - p) - e;
  return r;
}

// a / b rounded to nearest, as an IEEE division rounds it, for finite a >= 0 and b > 0 (areas here, so
// no product in residual overflows or underflows), from q, one of the two doubles around a / b: q is
// checked against its neighbour on the side its residual points to; the nearer of the two leaves the
// smaller residual (a quotient of doubles is never halfway between two doubles, so there is no tie).
double correctQuotient(double a, double b, double q) {
  if (a == 0.0) return 0.0;
  double r = residual(a, q, b);
  if (r == 0.0) return q;
  double n = r > 0.0 ? nextUp(q) : nextDown(q);
  return abs(residual(a, n, b)) < abs(r) ? n : q;
}

// a / b rounded as an IEEE division rounds it. GLSL promises no rounding for a double division: the
// driver's quotient is taken to be within an ulp (one of the two doubles around a / b) and corrected.
double divideRounded(double a, double b) { return correctQuotient(a, b, a / b); }
