// texture_lod.hpp — C++ mirror of texture_lod.glsl (ray cones: footprint, level, curvature) and of
// GL's texture filters the tracer uses (bilinear at level 0, trilinear between the host's mip levels,
// shaders/texture_mips.hpp). Same names and order of operations as the GLSL; see there for the method.
#pragma once
#include <vector>

#include "shaders/common.hpp"
#include "shaders/texture_mips.hpp"
#include "traversal/kernels.hpp"

namespace bvhlab::glsl {

constexpr float CONE_MIN_COS = 1e-3f;
constexpr float CONE_MAX_ANISOTROPY = 8.0f;
constexpr float CAP_NORMAL_Y = 0.9f;
constexpr float CONE_MIN_RHO = 1e-4f;

// texture()/textureLod() with GL_LINEAR on one level: texel centres at (i + 0.5) / size; s repeats,
// t repeats or clamps.
inline vec4 bilinear(const vec4* texels, int w, int h, vec2 uv, bool repeatT) {
  float x = uv.x * float(w) - 0.5f, y = uv.y * float(h) - 0.5f;
  float fx = floor(x), fy = floor(y);
  float ax = x - fx, ay = y - fy;
  auto at = [&](int i, int j) {
    i = ((i % w) + w) % w;  // GL_REPEAT in s
    j = repeatT ? ((j % h) + h) % h : clamp(j, 0, h - 1);
    return texels[size_t(j) * size_t(w) + size_t(i)];
  };
  int i0 = int(fx), j0 = int(fy);
  return mix(mix(at(i0, j0), at(i0 + 1, j0), ax), mix(at(i0, j0 + 1), at(i0 + 1, j0 + 1), ax), ay);
}

// textureLod() with GL_LINEAR_MIPMAP_LINEAR minification and GL_LINEAR magnification on a mip chain
// (layer `layer` of each level): lambda <= 0 magnifies (level 0), otherwise lambda is clamped to the
// last level and the two levels around it are blended (OpenGL 4.5 core, section 8.14).
inline vec4 trilinear(const std::vector<MipLevel>& chain, int layer, vec2 uv, float lambda, bool repeatT) {
  auto level = [&](int k) {
    const MipLevel& m = chain[size_t(k)];
    return bilinear(m.texels.data() + size_t(layer) * size_t(m.width) * size_t(m.height), m.width, m.height, uv,
                    repeatT);
  };
  if (!(lambda > 0.0f)) return level(0);
  const float q = float(chain.size() - 1);
  lambda = min(lambda, q);
  const float d1 = floor(lambda);
  if (d1 >= q) return level(int(q));
  return mix(level(int(d1)), level(int(d1) + 1), lambda - d1);
}

inline vec2 coneAt(vec2 cone, float t) { return vec2(cone.x + cone.y * t, cone.y); }

inline vec2 uvOfVector(vec3 a, vec3 dpdu, vec3 dpdv) {
  float guu = dot(dpdu, dpdu), guv = dot(dpdu, dpdv), gvv = dot(dpdv, dpdv);
  float det = guu * gvv - guv * guv;
  if (!(det > 0.0f)) return vec2(0.0f);
  vec2 b = vec2(dot(a, dpdu), dot(a, dpdv));
  return vec2(gvv * b.x - guv * b.y, guu * b.y - guv * b.x) / det;
}

inline float coneLodIsotropic(float w, float cosTheta, vec3 dpdu, vec3 dpdv, vec2 texSize) {
  float area = length(cross(dpdu, dpdv)) / (texSize.x * texSize.y);
  float width = abs(w) / max(abs(cosTheta), CONE_MIN_COS);
  if (!(area > 0.0f) || !(width > 0.0f)) return 0.0f;
  return log2(width) - 0.5f * log2(area);
}

inline void coneEllipse(float w, vec3 dir, vec3 n, vec3 dpdu, vec3 dpdv, vec2& g1, vec2& g2) {
  float cosTheta = max(abs(dot(dir, n)), CONE_MIN_COS);
  vec3 inPlane = dir - dot(dir, n) * n;
  vec3 major = dot(inPlane, inPlane) > 0.0f ? normalize(inPlane) : normalize(dpdu + dpdv);
  vec3 minor = cross(n, major);
  g1 = uvOfVector(minor * abs(w), dpdu, dpdv);
  g2 = uvOfVector(major * (abs(w) / cosTheta), dpdu, dpdv);
}

struct AnisoTaps {
  float lod;
  int count;
  vec2 major;
};
inline AnisoTaps anisoTaps(vec2 g1, vec2 g2, vec2 texSize) {
  float p1 = length(g1 * texSize), p2 = length(g2 * texSize);
  AnisoTaps a;
  a.major = p1 > p2 ? g1 : g2;
  float pMax = max(p1, p2), pMin = min(p1, p2);
  a.count = 1;
  a.lod = 0.0f;
  if (!(pMax > 0.0f)) return a;
  float n = pMin > 0.0f ? min(ceil(pMax / pMin), CONE_MAX_ANISOTROPY) : CONE_MAX_ANISOTROPY;
  a.count = int(n);
  a.lod = log2(pMax / n);
  return a;
}

inline float coneSpreadAfter(float spread, float w, float kappa, bool reflected, float eta, float cosI, float cosT,
                             bool curvature) {
  if (!curvature) kappa = 0.0f;  // CONE_NO_CURVATURE
  if (reflected) return spread + 2.0f * kappa * w;
  return eta * spread + (eta * cosI - cosT) * kappa * w;
}

inline void objectSurface(int kind, vec2 radii, vec3 q, vec3 n, vec3& dpdu, vec3& dpdv, float& kappa) {
  vec3 around = 2.0f * PI * vec3(q.z, 0.0f, -q.x);
  float rho = length(vec2(q.x, q.z));
  bool cap = abs(n.y) > CAP_NORMAL_Y * length(n);
  dpdu = vec3(2.0f, 0.0f, 0.0f);
  dpdv = vec3(0.0f, 0.0f, 2.0f);
  kappa = 0.0f;
  if (kind == 0) {
    dpdu = around;
    dpdv = PI * (rho > 0.0f ? vec3(-q.y * q.x / rho, rho, -q.y * q.z / rho) : vec3(0.0f, 0.0f, 1.0f));
    kappa = 1.0f;
  } else if (kind == 1) {
    vec3 a = abs(n);
    if (a.x >= a.y && a.x >= a.z) dpdu = vec3(0.0f, 0.0f, -2.0f * sign(n.x)), dpdv = vec3(0.0f, 2.0f, 0.0f);
    else if (a.y >= a.z) dpdu = vec3(2.0f, 0.0f, 0.0f), dpdv = vec3(0.0f, 0.0f, -2.0f * sign(n.y));
    else dpdu = vec3(2.0f * sign(n.z), 0.0f, 0.0f), dpdv = vec3(0.0f, 2.0f, 0.0f);
  } else if (kind == 2) {
    if (cap) dpdv = vec3(0.0f, 0.0f, -2.0f * sign(n.y));
    else dpdu = around, dpdv = vec3(0.0f, 2.0f, 0.0f), kappa = 0.5f;
  } else if (kind == 3) {
    if (!cap) {
      float r = max(rho, CONE_MIN_RHO);
      dpdu = around;
      dpdv = vec3(-q.x / r, 2.0f, -q.z / r);
      kappa = 0.5f * (2.0f / sqrt(5.0f)) / r;
    }
  } else if (kind == 4) {
    float R = radii.x, r = radii.y;
    float cosT = (rho - R) / r, sinT = q.y / r;
    dpdu = around;
    dpdv = 2.0f * PI * r *
           (rho > 0.0f ? vec3(-sinT * q.x / rho, cosT, -sinT * q.z / rho) : vec3(0.0f, cosT, -sinT));
    kappa = 0.5f * (1.0f / r + (rho > 0.0f ? cosT / rho : 0.0f));
  }
}

inline void meshSurface(const Storage& storage, int tri, vec3 v0, vec3 v1, vec3 v2, vec3& dpdu, vec3& dpdv,
                        float& kappa) {
  vec3 n0, n1, n2;
  vec2 t0, t1, t2;
  loadAttributes(storage, tri, vec2(0.0f, 0.0f), n0, t0);
  loadAttributes(storage, tri, vec2(1.0f, 0.0f), n1, t1);
  loadAttributes(storage, tri, vec2(0.0f, 1.0f), n2, t2);
  vec3 e1 = v1 - v0, e2 = v2 - v0;
  vec2 d1 = t1 - t0, d2 = t2 - t0;
  float det = d1.x * d2.y - d1.y * d2.x;
  dpdu = vec3(0.0f);
  dpdv = vec3(0.0f);
  if (abs(det) > 0.0f) {
    dpdu = (d2.y * e1 - d1.y * e2) / det;
    dpdv = (d1.x * e2 - d2.x * e1) / det;
  }
  vec3 e3 = v2 - v1;
  float k01 = dot(n1 - n0, e1) / dot(e1, e1);
  float k02 = dot(n2 - n0, e2) / dot(e2, e2);
  float k12 = dot(n2 - n1, e3) / dot(e3, e3);
  kappa = (k01 + k02 + k12) / 3.0f;
  if (!(abs(kappa) < INF)) kappa = 0.0f;
}

}  // namespace bvhlab::glsl
