// prim_torus.glsl — ray vs the torus about +Y in the XZ plane, radii = (major R, minor r).
// C++ mirror: shaders/primitives.hpp. Conventions (t, tMin/tMax, outward normal, NaN) as in prim_sphere.glsl.
//
// Surface: f(P) = (|P|^2 + R^2 - r^2)^2 - 4 R^2 (P.x^2 + P.z^2) = 0, f < 0 inside the tube. Along the ray it
// is a quartic. Solver (no Ferrari/Descartes closed form: those lose most float digits to cancellation):
// ROOT ISOLATION BY DERIVATIVES + SAFEGUARDED NEWTON–BISECTION.
//  1. Normalise: unit direction e, lengths in units of the bounding radius S = R + r, and the origin moved to
//     the closest approach to the centre, p (as in prim_sphere.glsl). The quartic in u (distance along e
//     from p) is then monic with O(1) coefficients whatever the ray's length, scale or distance.
//  2. Clip u to the ray's interval inside the bounding sphere (a line missing it is pruned here), inside the
//     slab |y| <= r (both enlarged by TORUS_CLIP_MARGIN), and inside (tMin, tMax).
//  3. The roots of f'' (a quadratic, stable formula) split the interval into pieces where f' is monotonic;
//     each holds at most one root of f' (a critical point of f), found by safeguarded Newton–bisection.
//  4. The critical points split the interval into pieces where f is monotonic, each with at most one root.
//     Scanning them in order, the first sign change brackets the nearest hit. Later critical points are not
//     computed.
//  5. The bracketed root is refined by safeguarded Newton–bisection on the DISTANCE to the tube,
//     g = |(rho - R, y)| - r, rather than on f. Since f = g (g + 2r) ((rho + R)^2 + y^2 - r^2), for a ring
//     torus (R > r) g has the sign of f, but g is evaluated to a few ulps of S whatever r, with |grad g| = 1,
//     while the expanded quartic loses about log10(S / r) digits near its roots (O(1) coefficients, slope
//     O(r)): measured for r = R / 100, position errors of 64 eps S on f against 1.7 on g. Spindle tori (r >= R: f also has an inner
//     sheet, which g does not describe, and r is not small) refine on f.
// A tangent ray (a double root, no sign change) counts as a miss; that is the grazing tolerance the tests
// state. Accuracy: see tests/test_primitives.cpp for the measured bounds.

// Newton–bisection stops when a Newton step (or the bracket) falls below TORUS_TOLERANCE normalised units.
// 2^-23 is one float ulp at 1, the bounding radius: f cannot be evaluated more finely than that.
const float TORUS_TOLERANCE = 1.0 / 8388608.0;
// Iteration budget: enough for pure bisection from width 2 (the bounding sphere's diameter) down to
// TORUS_TOLERANCE (24 halvings), so the budget, not luck, bounds the work even where Newton stalls.
const int TORUS_MAX_STEPS = 26;
// The clip region (step 2) is enlarged by this fraction of the bounding radius. The torus touches its bounding
// sphere (outer equator) and slab (top and bottom circles), and a root exactly at a clip end has f = 0 there
// and no sign change to find. 1/256 is far above the rounding of the clip ends (~1e-7) and keeps u = O(1).
const float TORUS_CLIP_MARGIN = 1.0 / 256.0;

// k4 u^4 + k.w u^3 + k.z u^2 + k.y u + k.x and its derivative, by Horner.
float torusPoly(float k4, vec4 k, float u, out float deriv) {
  float v = k4;
  deriv = 0.0;
  deriv = deriv * u + v;
  v = v * u + k.w;
  deriv = deriv * u + v;
  v = v * u + k.z;
  deriv = deriv * u + v;
  v = v * u + k.y;
  deriv = deriv * u + v;
  v = v * u + k.x;
  return v;
}

// Distance from P to the tube, |(rho - R, y)| - r (radii normalised), and its derivative along the unit
// direction e (NaN on the axis or the core circle, where g is not differentiable: it only ever turns a
// Newton step into bisection).
float torusDistance(vec3 P, vec3 e, vec2 radii, out float deriv) {
  float rho = length(P.xz);
  vec2 q = vec2(rho - radii.x, P.y);
  float qLen = length(q);
  deriv = (q.x * (P.x * e.x + P.z * e.z) / rho + q.y * e.y) / qLen;
  return qLen - radii.y;
}

// What torusRefine solves: f' (its coefficients in k, k4 = 0), f (k, k4 = 1) or the tube distance g along
// p + u e.
const int TORUS_DERIVATIVE = 0;
const int TORUS_QUARTIC = 1;
const int TORUS_DISTANCE = 2;

float torusEval(int mode, vec4 k, vec3 p, vec3 e, vec2 radii, float u, out float deriv) {
  if (mode == TORUS_DISTANCE) return torusDistance(p + u * e, e, radii, deriv);
  return torusPoly(mode == TORUS_QUARTIC ? 1.0 : 0.0, k, u, deriv);
}

// The root in [lo, hi] of the function `mode`, which changes sign exactly once there (valueLo: its value at
// lo). Safeguarded Newton–bisection: keep the sign-change bracket; take the Newton step when it lands
// inside the bracket and is at most half the previous step, else bisect. A NaN step (zero or undefined
// derivative) fails the test and bisects.
float torusRefine(int mode, vec4 k, vec3 p, vec3 e, vec2 radii, float lo, float hi, float valueLo) {
  bool negativeLo = valueLo < 0.0;
  float u = 0.5 * (lo + hi);
  float stepOld = hi - lo;
  for (int i = 0; i < TORUS_MAX_STEPS; ++i) {
    float deriv;
    float v = torusEval(mode, k, p, e, radii, u, deriv);
    if (v == 0.0) break;
    if ((v < 0.0) == negativeLo) {
      lo = u;
    } else {
      hi = u;
    }
    float step = v / deriv;
    float next = u - step;
    if (next > lo && next < hi && abs(step) <= 0.5 * stepOld) {
      stepOld = abs(step);
      u = next;
      if (stepOld <= TORUS_TOLERANCE) break;
    } else {
      stepOld = 0.5 * (hi - lo);
      u = 0.5 * (lo + hi);
      if (stepOld <= TORUS_TOLERANCE) break;
    }
  }
  return u;
}

// Step 5: the root of the quartic c in [lo, hi] (one sign change there; fLo = f(lo)), refined on the tube
// distance for a ring torus. Should g not change sign over the bracket (rounding of f at a bracket end
// lying within a few ulps of the surface), the quartic itself is refined.
float torusRoot(vec4 c, vec3 p, vec3 e, vec2 radii, float lo, float hi, float fLo) {
  if (radii.x > radii.y) {
    float unused;
    float gLo = torusDistance(p + lo * e, e, radii, unused);
    float gHi = torusDistance(p + hi * e, e, radii, unused);
    if ((gLo < 0.0) != (gHi < 0.0)) return torusRefine(TORUS_DISTANCE, c, p, e, radii, lo, hi, gLo);
  }
  return torusRefine(TORUS_QUARTIC, c, p, e, radii, lo, hi, fLo);
}

bool intersectTorus(Ray ray, vec2 radii, float tMin, float tMax, out float t, out vec3 normal, out vec2 uv) {
  t = 0.0;
  normal = vec3(0.0, 1.0, 0.0);
  uv = vec2(0.0);
  float scale = radii.x + radii.y;  // bounding-sphere radius
  if (!(radii.x >= 0.0 && radii.y > 0.0 && scale < INF)) return false;
  float dd = dot(ray.dir, ray.dir);
  if (!(dd > 0.0 && dd < INF)) return false;  // zero, overflowing or NaN direction
  float invLen = 1.0 / sqrt(dd);
  vec3 e = ray.dir * invLen;
  vec3 o = ray.origin / scale;
  float R = radii.x / scale;
  float r = radii.y / scale;
  float k = scale * invLen;  // t per normalised unit of u
  float uc = -dot(o, e);
  vec3 p = o + uc * e;
  float pp = dot(p, p);
  // p is off the exact closest approach by ~eps |o| along e (the rounding of uc e, as large as 1e-3 for
  // far origins): the sphere interval is centred on u = -pe, not 0, and that offset cannot be folded into
  // tc (below its ulp). Everything after uses p + u e as is, consistently.
  float pe = dot(p, e);
  float bound = 1.0 + TORUS_CLIP_MARGIN;
  float miss2 = pp - pe * pe;  // squared distance of the line from the centre
  if (!(miss2 <= bound * bound)) return false;  // misses the bounding sphere (or NaN)
  float tc = uc * k;
  float h = sqrt(bound * bound - miss2);
  float lo = -pe - h;
  float hi = -pe + h;
  if (e.y != 0.0) {
    float s0 = (-r - TORUS_CLIP_MARGIN - p.y) / e.y;
    float s1 = (r + TORUS_CLIP_MARGIN - p.y) / e.y;
    lo = max(lo, min(s0, s1));
    hi = min(hi, max(s0, s1));
  } else if (!(abs(p.y) <= r)) {
    return false;  // parallel to the torus's plane, above or below it
  }
  lo = max(lo, (tMin - tc) / k);
  hi = min(hi, (tMax - tc) / k);
  if (!(lo < hi)) return false;
  // f(p + u e) = u^4 + c.w u^3 + c.z u^2 + c.y u + c.x.
  float R2 = R * R;
  float K = pp + R2 - r * r;
  vec4 c = vec4(K * K - 4.0 * R2 * (p.x * p.x + p.z * p.z),
                4.0 * pe * K - 8.0 * R2 * (p.x * e.x + p.z * e.z),
                4.0 * pe * pe + 2.0 * K - 4.0 * R2 * (e.x * e.x + e.z * e.z),
                4.0 * pe);
  vec4 dc = vec4(c.y, 2.0 * c.z, 3.0 * c.w, 4.0);  // f'
  // Inflection points: f''/2 = 6 u^2 + 3 c.w u + c.z = 0. Absent ones sit at hi (an empty piece).
  float inflection0 = hi;
  float inflection1 = hi;
  float bh = 1.5 * c.w;
  float discH = bh * bh - 6.0 * c.z;
  if (discH > 0.0) {
    float q = -(bh + (bh >= 0.0 ? sqrt(discH) : -sqrt(discH)));  // bh >= 0.0: GLSL's sign(0.0) is 0.0
    float i0 = q / 6.0;
    float i1 = q != 0.0 ? c.z / q : i0;
    inflection0 = min(i0, i1);
    inflection1 = max(i0, i1);
  }
  float bounds[4] = float[4](lo, clamp(inflection0, lo, hi), clamp(inflection1, lo, hi), hi);
  float unused;
  float uPrev = lo;  // start of the current piece where f is monotonic
  float fPrev = torusPoly(1.0, c, lo, unused);
  float dPrev = torusPoly(0.0, dc, lo, unused);
  float root = hi;
  bool found = false;
  for (int i = 1; i < 4 && !found; ++i) {
    float dCur = torusPoly(0.0, dc, bounds[i], unused);
    if ((dPrev < 0.0) != (dCur < 0.0)) {
      float crit = torusRefine(TORUS_DERIVATIVE, dc, p, e, vec2(R, r), bounds[i - 1], bounds[i], dPrev);
      float fCrit = torusPoly(1.0, c, crit, unused);
      if ((fPrev < 0.0) != (fCrit < 0.0)) {
        root = torusRoot(c, p, e, vec2(R, r), uPrev, crit, fPrev);
        found = true;
      }
      uPrev = crit;
      fPrev = fCrit;
    }
    dPrev = dCur;
  }
  if (!found) {
    float fHi = torusPoly(1.0, c, hi, unused);
    if ((fPrev < 0.0) != (fHi < 0.0)) {
      root = torusRoot(c, p, e, vec2(R, r), uPrev, hi, fPrev);
      found = true;
    }
  }
  if (!found) return false;
  float tHit = tc + root * k;
  if (!(tHit > tMin && tHit < tMax)) return false;  // rounding of tc + root k at the interval's ends
  t = tHit;
  vec3 P = p + root * e;  // hit point, normalised object space
  // Outward normal: the gradient of f / 4. It vanishes only at the pinch points of a spindle torus (r > R)
  // on the axis, where +-Y is used.
  normal = (dot(P, P) + R2 - r * r) * P - 2.0 * R2 * vec3(P.x, 0.0, P.z);
  if (!(dot(normal, normal) > 0.0)) normal = vec3(0.0, P.y >= 0.0 ? 1.0 : -1.0, 0.0);
  // u: angle about +Y from +Z towards +X (as the sphere); v: angle about the tube from the outer equator,
  // seam on the inner equator. atan(0, 0) is undefined in GLSL: guarded.
  float rho = length(P.xz);
  float phi = rho > 0.0 ? atan(P.x, P.z) : 0.0;
  float theta = (P.y != 0.0 || rho != R) ? atan(P.y, rho - R) : 0.0;
  uv = clamp(vec2(0.5 + phi / (2.0 * PI), 0.5 + theta / (2.0 * PI)), 0.0, 1.0);
  return true;
}
