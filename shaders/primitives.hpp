// primitives.hpp — C++ mirrors of shaders/prim_*.glsl (analytic ray–primitive intersections in object
// space). Each function reads like its GLSL: same names, same statements in the same order; `out` parameters
// become references and GLSL swizzles become constructors. The comments explaining the numerics live in the
// .glsl files and are not repeated here. Canonical shapes: datasets/scene.hpp.
#pragma once
#include "shaders/common.hpp"

namespace bvhlab::glsl {
using namespace glm;

// ---- prim_sphere.glsl --------------------------------------------------------------------------------
inline bool intersectSphere(Ray ray, float tMin, float tMax, float& t, vec3& normal, vec2& uv) {
  t = 0.0f;
  normal = vec3(0.0f, 1.0f, 0.0f);
  uv = vec2(0.0f);
  float a = dot(ray.dir, ray.dir);
  if (!(a > 0.0f && a < INF)) return false;
  float tc = -dot(ray.origin, ray.dir) / a;
  vec3 p = ray.origin + tc * ray.dir;
  float b = dot(p, ray.dir);
  float c = dot(p, p) - 1.0f;
  float disc = b * b - a * c;
  if (!(disc >= 0.0f)) return false;
  float q = -(b + (b >= 0.0f ? sqrt(disc) : -sqrt(disc)));
  float s0 = q / a;
  float s1 = q != 0.0f ? c / q : s0;
  float sNear = min(s0, s1);
  float sFar = max(s0, s1);
  float tNear = tc + sNear;
  float tFar = tc + sFar;
  float s;
  if (tNear > tMin && tNear < tMax) {
    t = tNear;
    s = sNear;
  } else if (tFar > tMin && tFar < tMax) {
    t = tFar;
    s = sFar;
  } else {
    return false;
  }
  vec3 hit = p + s * ray.dir;
  normal = hit;
  float phi = (hit.x != 0.0f || hit.z != 0.0f) ? atan(hit.x, hit.z) : 0.0f;
  float theta = atan(hit.y, length(vec2(hit.x, hit.z)));
  uv = clamp(vec2(0.5f + phi / (2.0f * PI), 0.5f + theta / PI), 0.0f, 1.0f);
  return true;
}

// ---- prim_box.glsl -----------------------------------------------------------------------------------
inline bool intersectBox(Ray ray, float tMin, float tMax, float& t, vec3& normal, vec2& uv) {
  t = 0.0f;
  normal = vec3(0.0f, 1.0f, 0.0f);
  uv = vec2(0.0f);
  float dd = dot(ray.dir, ray.dir);
  if (!(dd > 0.0f && dd < INF)) return false;
  float tc = -dot(ray.origin, ray.dir) / dd;
  vec3 p = ray.origin + tc * ray.dir;
  if (!(dot(p, p) <= 3.0f)) return false;
  float sIn = -INF;
  float sOut = INF;
  int axisIn = 0;
  int axisOut = 0;
  for (int i = 0; i < 3; ++i) {
    if (ray.dir[i] != 0.0f) {
      float s0 = (-1.0f - p[i]) / ray.dir[i];
      float s1 = (1.0f - p[i]) / ray.dir[i];
      float sNear = min(s0, s1);
      float sFar = max(s0, s1);
      if (sNear > sIn) {
        sIn = sNear;
        axisIn = i;
      }
      if (sFar < sOut) {
        sOut = sFar;
        axisOut = i;
      }
    } else if (!(abs(p[i]) <= 1.0f)) {
      return false;
    }
  }
  if (!(sIn <= sOut)) return false;
  float tIn = tc + sIn;
  float tOut = tc + sOut;
  float s;
  int axis;
  float side;
  if (tIn > tMin && tIn < tMax) {
    t = tIn;
    s = sIn;
    axis = axisIn;
    side = ray.dir[axisIn] > 0.0f ? -1.0f : 1.0f;
  } else if (tOut > tMin && tOut < tMax) {
    t = tOut;
    s = sOut;
    axis = axisOut;
    side = ray.dir[axisOut] > 0.0f ? 1.0f : -1.0f;
  } else {
    return false;
  }
  vec3 hit = p + s * ray.dir;
  normal = vec3(0.0f);
  normal[axis] = side;
  if (axis == 0) {
    uv = vec2(-side * hit.z, hit.y);
  } else if (axis == 1) {
    uv = vec2(hit.x, -side * hit.z);
  } else {
    uv = vec2(side * hit.x, hit.y);
  }
  uv = clamp(0.5f * uv + 0.5f, 0.0f, 1.0f);
  return true;
}

// ---- prim_cylinder.glsl ------------------------------------------------------------------------------
inline bool intersectCylinder(Ray ray, float tMin, float tMax, float& t, vec3& normal, vec2& uv) {
  t = 0.0f;
  normal = vec3(0.0f, 1.0f, 0.0f);
  uv = vec2(0.0f);
  float dd = dot(ray.dir, ray.dir);
  if (!(dd > 0.0f && dd < INF)) return false;
  float tc = -dot(ray.origin, ray.dir) / dd;
  vec3 p = ray.origin + tc * ray.dir;
  if (!(dot(p, p) <= 2.0f)) return false;
  float a = ray.dir.x * ray.dir.x + ray.dir.z * ray.dir.z;
  float b = p.x * ray.dir.x + p.z * ray.dir.z;
  float c = p.x * p.x + p.z * p.z - 1.0f;
  float sideIn = -INF;
  float sideOut = INF;
  if (a > 0.0f) {
    float disc = b * b - a * c;
    if (!(disc >= 0.0f)) return false;
    float q = -(b + (b >= 0.0f ? sqrt(disc) : -sqrt(disc)));
    float s0 = q / a;
    float s1 = q != 0.0f ? c / q : s0;
    sideIn = min(s0, s1);
    sideOut = max(s0, s1);
  } else if (!(c <= 0.0f)) {
    return false;
  }
  float capIn = -INF;
  float capOut = INF;
  if (ray.dir.y != 0.0f) {
    float s0 = (-1.0f - p.y) / ray.dir.y;
    float s1 = (1.0f - p.y) / ray.dir.y;
    capIn = min(s0, s1);
    capOut = max(s0, s1);
  } else if (!(abs(p.y) <= 1.0f)) {
    return false;
  }
  float sIn = max(sideIn, capIn);
  float sOut = min(sideOut, capOut);
  if (!(sIn <= sOut)) return false;
  float tIn = tc + sIn;
  float tOut = tc + sOut;
  float s;
  bool onCap;
  if (tIn > tMin && tIn < tMax) {
    t = tIn;
    s = sIn;
    onCap = capIn >= sideIn;
  } else if (tOut > tMin && tOut < tMax) {
    t = tOut;
    s = sOut;
    onCap = capOut <= sideOut;
  } else {
    return false;
  }
  vec3 hit = p + s * ray.dir;
  if (onCap) {
    float side = hit.y >= 0.0f ? 1.0f : -1.0f;
    normal = vec3(0.0f, side, 0.0f);
    uv = vec2(hit.x, -side * hit.z);
    uv = clamp(0.5f * uv + 0.5f, 0.0f, 1.0f);
  } else {
    normal = vec3(hit.x, 0.0f, hit.z);
    float phi = (hit.x != 0.0f || hit.z != 0.0f) ? atan(hit.x, hit.z) : 0.0f;
    uv = clamp(vec2(0.5f + phi / (2.0f * PI), 0.5f + 0.5f * hit.y), 0.0f, 1.0f);
  }
  return true;
}

// ---- prim_cone.glsl ----------------------------------------------------------------------------------
inline bool intersectCone(Ray ray, float tMin, float tMax, float& t, vec3& normal, vec2& uv) {
  t = 0.0f;
  normal = vec3(0.0f, 1.0f, 0.0f);
  uv = vec2(0.0f);
  float dd = dot(ray.dir, ray.dir);
  if (!(dd > 0.0f && dd < INF)) return false;
  float tc = -dot(ray.origin, ray.dir) / dd;
  vec3 p = ray.origin + tc * ray.dir;
  if (!(dot(p, p) <= 2.0f)) return false;
  float w = 1.0f - p.y;
  float A = 4.0f * (ray.dir.x * ray.dir.x + ray.dir.z * ray.dir.z) - ray.dir.y * ray.dir.y;
  float B = 4.0f * (p.x * ray.dir.x + p.z * ray.dir.z) + w * ray.dir.y;
  float C = 4.0f * (p.x * p.x + p.z * p.z) - w * w;
  float sideIn = -INF;
  float sideOut = INF;
  if (A != 0.0f) {
    float disc = B * B - A * C;
    if (A < 0.0f) disc = max(disc, 0.0f);
    if (!(disc >= 0.0f)) return false;
    float q = -(B + (B >= 0.0f ? sqrt(disc) : -sqrt(disc)));
    float s0 = q / A;
    float s1 = q != 0.0f ? C / q : s0;
    float sLo = min(s0, s1);
    float sHi = max(s0, s1);
    if (A > 0.0f) {
      sideIn = sLo;
      sideOut = sHi;
    } else if (ray.dir.y < 0.0f) {
      sideIn = sHi;
    } else {
      sideOut = sLo;
    }
  } else if (B != 0.0f) {
    float s0 = -C / (2.0f * B);
    if (B > 0.0f) {
      sideOut = s0;
    } else {
      sideIn = s0;
    }
  } else if (!(C <= 0.0f)) {
    return false;
  }
  float capIn = -INF;
  float capOut = INF;
  if (ray.dir.y != 0.0f) {
    float s0 = (-1.0f - p.y) / ray.dir.y;
    float s1 = (1.0f - p.y) / ray.dir.y;
    capIn = min(s0, s1);
    capOut = max(s0, s1);
  } else if (!(abs(p.y) <= 1.0f)) {
    return false;
  }
  float sIn = max(sideIn, capIn);
  float sOut = min(sideOut, capOut);
  if (!(sIn <= sOut)) return false;
  float tIn = tc + sIn;
  float tOut = tc + sOut;
  float s;
  bool onCap;
  if (tIn > tMin && tIn < tMax) {
    t = tIn;
    s = sIn;
    onCap = capIn > sideIn;
  } else if (tOut > tMin && tOut < tMax) {
    t = tOut;
    s = sOut;
    onCap = capOut < sideOut;
  } else {
    return false;
  }
  vec3 hit = p + s * ray.dir;
  float r = length(vec2(hit.x, hit.z));
  if (onCap && hit.y < 0.0f) {
    normal = vec3(0.0f, -1.0f, 0.0f);
    uv = clamp(0.5f * vec2(hit.x, hit.z) + 0.5f, 0.0f, 1.0f);
  } else {
    normal = r > 0.0f ? vec3(2.0f * hit.x / r, 1.0f, 2.0f * hit.z / r) : vec3(0.0f, 1.0f, 0.0f);
    float phi = r > 0.0f ? atan(hit.x, hit.z) : 0.0f;
    uv = clamp(vec2(0.5f + phi / (2.0f * PI), 0.5f + 0.5f * hit.y), 0.0f, 1.0f);
  }
  return true;
}

// ---- prim_torus.glsl ---------------------------------------------------------------------------------
constexpr float TORUS_TOLERANCE = 1.0f / 8388608.0f;
constexpr int TORUS_MAX_STEPS = 26;
constexpr float TORUS_CLIP_MARGIN = 1.0f / 256.0f;

inline float torusPoly(float k4, vec4 k, float u, float& deriv) {
  float v = k4;
  deriv = 0.0f;
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

inline float torusDistance(vec3 P, vec3 e, vec2 radii, float& deriv) {
  float rho = length(vec2(P.x, P.z));
  vec2 q = vec2(rho - radii.x, P.y);
  float qLen = length(q);
  deriv = (q.x * (P.x * e.x + P.z * e.z) / rho + q.y * e.y) / qLen;
  return qLen - radii.y;
}

constexpr int TORUS_DERIVATIVE = 0;
constexpr int TORUS_QUARTIC = 1;
constexpr int TORUS_DISTANCE = 2;

inline float torusEval(int mode, vec4 k, vec3 p, vec3 e, vec2 radii, float u, float& deriv) {
  if (mode == TORUS_DISTANCE) return torusDistance(p + u * e, e, radii, deriv);
  return torusPoly(mode == TORUS_QUARTIC ? 1.0f : 0.0f, k, u, deriv);
}

inline float torusRefine(int mode, vec4 k, vec3 p, vec3 e, vec2 radii, float lo, float hi, float valueLo) {
  bool negativeLo = valueLo < 0.0f;
  float u = 0.5f * (lo + hi);
  float stepOld = hi - lo;
  for (int i = 0; i < TORUS_MAX_STEPS; ++i) {
    float deriv;
    float v = torusEval(mode, k, p, e, radii, u, deriv);
    if (v == 0.0f) break;
    if ((v < 0.0f) == negativeLo) {
      lo = u;
    } else {
      hi = u;
    }
    float step = v / deriv;
    float next = u - step;
    if (next > lo && next < hi && abs(step) <= 0.5f * stepOld) {
      stepOld = abs(step);
      u = next;
      if (stepOld <= TORUS_TOLERANCE) break;
    } else {
      stepOld = 0.5f * (hi - lo);
      u = 0.5f * (lo + hi);
      if (stepOld <= TORUS_TOLERANCE) break;
    }
  }
  return u;
}

inline float torusRoot(vec4 c, vec3 p, vec3 e, vec2 radii, float lo, float hi, float fLo) {
  if (radii.x > radii.y) {
    float unused;
    float gLo = torusDistance(p + lo * e, e, radii, unused);
    float gHi = torusDistance(p + hi * e, e, radii, unused);
    if ((gLo < 0.0f) != (gHi < 0.0f)) return torusRefine(TORUS_DISTANCE, c, p, e, radii, lo, hi, gLo);
  }
  return torusRefine(TORUS_QUARTIC, c, p, e, radii, lo, hi, fLo);
}

inline bool intersectTorus(Ray ray, vec2 radii, float tMin, float tMax, float& t, vec3& normal, vec2& uv) {
  t = 0.0f;
  normal = vec3(0.0f, 1.0f, 0.0f);
  uv = vec2(0.0f);
  float scale = radii.x + radii.y;
  if (!(radii.x >= 0.0f && radii.y > 0.0f && scale < INF)) return false;
  float dd = dot(ray.dir, ray.dir);
  if (!(dd > 0.0f && dd < INF)) return false;
  float invLen = 1.0f / sqrt(dd);
  vec3 e = ray.dir * invLen;
  vec3 o = ray.origin / scale;
  float R = radii.x / scale;
  float r = radii.y / scale;
  float k = scale * invLen;
  float uc = -dot(o, e);
  vec3 p = o + uc * e;
  float pp = dot(p, p);
  float pe = dot(p, e);
  float bound = 1.0f + TORUS_CLIP_MARGIN;
  float miss2 = pp - pe * pe;
  if (!(miss2 <= bound * bound)) return false;
  float tc = uc * k;
  float h = sqrt(bound * bound - miss2);
  float lo = -pe - h;
  float hi = -pe + h;
  if (e.y != 0.0f) {
    float s0 = (-r - TORUS_CLIP_MARGIN - p.y) / e.y;
    float s1 = (r + TORUS_CLIP_MARGIN - p.y) / e.y;
    lo = max(lo, min(s0, s1));
    hi = min(hi, max(s0, s1));
  } else if (!(abs(p.y) <= r)) {
    return false;
  }
  lo = max(lo, (tMin - tc) / k);
  hi = min(hi, (tMax - tc) / k);
  if (!(lo < hi)) return false;
  float R2 = R * R;
  float K = pp + R2 - r * r;
  vec4 c = vec4(K * K - 4.0f * R2 * (p.x * p.x + p.z * p.z),
                4.0f * pe * K - 8.0f * R2 * (p.x * e.x + p.z * e.z),
                4.0f * pe * pe + 2.0f * K - 4.0f * R2 * (e.x * e.x + e.z * e.z),
                4.0f * pe);
  vec4 dc = vec4(c.y, 2.0f * c.z, 3.0f * c.w, 4.0f);
  float inflection0 = hi;
  float inflection1 = hi;
  float bh = 1.5f * c.w;
  float discH = bh * bh - 6.0f * c.z;
  if (discH > 0.0f) {
    float q = -(bh + (bh >= 0.0f ? sqrt(discH) : -sqrt(discH)));
    float i0 = q / 6.0f;
    float i1 = q != 0.0f ? c.z / q : i0;
    inflection0 = min(i0, i1);
    inflection1 = max(i0, i1);
  }
  float bounds[4] = {lo, clamp(inflection0, lo, hi), clamp(inflection1, lo, hi), hi};
  float unused;
  float uPrev = lo;
  float fPrev = torusPoly(1.0f, c, lo, unused);
  float dPrev = torusPoly(0.0f, dc, lo, unused);
  float root = hi;
  bool found = false;
  for (int i = 1; i < 4 && !found; ++i) {
    float dCur = torusPoly(0.0f, dc, bounds[i], unused);
    if ((dPrev < 0.0f) != (dCur < 0.0f)) {
      float crit = torusRefine(TORUS_DERIVATIVE, dc, p, e, vec2(R, r), bounds[i - 1], bounds[i], dPrev);
      float fCrit = torusPoly(1.0f, c, crit, unused);
      if ((fPrev < 0.0f) != (fCrit < 0.0f)) {
        root = torusRoot(c, p, e, vec2(R, r), uPrev, crit, fPrev);
        found = true;
      }
      uPrev = crit;
      fPrev = fCrit;
    }
    dPrev = dCur;
  }
  if (!found) {
    float fHi = torusPoly(1.0f, c, hi, unused);
    if ((fPrev < 0.0f) != (fHi < 0.0f)) {
      root = torusRoot(c, p, e, vec2(R, r), uPrev, hi, fPrev);
      found = true;
    }
  }
  if (!found) return false;
  float tHit = tc + root * k;
  if (!(tHit > tMin && tHit < tMax)) return false;
  t = tHit;
  vec3 P = p + root * e;
  normal = (dot(P, P) + R2 - r * r) * P - 2.0f * R2 * vec3(P.x, 0.0f, P.z);
  if (!(dot(normal, normal) > 0.0f)) normal = vec3(0.0f, P.y >= 0.0f ? 1.0f : -1.0f, 0.0f);
  float rho = length(vec2(P.x, P.z));
  float phi = rho > 0.0f ? atan(P.x, P.z) : 0.0f;
  float theta = (P.y != 0.0f || rho != R) ? atan(P.y, rho - R) : 0.0f;
  uv = clamp(vec2(0.5f + phi / (2.0f * PI), 0.5f + theta / (2.0f * PI)), 0.0f, 1.0f);
  return true;
}

// ---- prim_plane.glsl ---------------------------------------------------------------------------------
inline bool intersectPlane(Ray ray, bool infinite, float tMin, float tMax, float& t, vec3& normal, vec2& uv) {
  t = 0.0f;
  normal = vec3(0.0f, 1.0f, 0.0f);
  uv = vec2(0.0f);
  if (!(abs(ray.dir.y) > 0.0f)) return false;
  float tHit = -ray.origin.y / ray.dir.y;
  if (!(tHit > tMin && tHit < tMax)) return false;
  vec2 xz = vec2(ray.origin.x, ray.origin.z) + tHit * vec2(ray.dir.x, ray.dir.z);
  if (!infinite && !(abs(xz.x) <= 1.0f && abs(xz.y) <= 1.0f)) return false;
  t = tHit;
  uv = infinite ? fract(0.5f * xz + 0.5f) : clamp(0.5f * xz + 0.5f, 0.0f, 1.0f);
  return true;
}

}  // namespace bvhlab::glsl
