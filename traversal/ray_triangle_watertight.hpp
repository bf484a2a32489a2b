// ray_triangle_watertight.hpp — C++ mirror of ray_triangle_watertight.glsl (Woop, Benthin & Wald
// 2013; the reasoning is there). Same name and signature as ray_triangle.hpp, in its own namespace:
// a kernel mirror selects it with `using watertight::intersectTriangle;` (or a template parameter).
// GLSL's `precise` has no C++ spelling: this project builds with -std=c++20 (not gnu++20), where GCC
// defaults to -ffp-contract=off, so nothing is fused here either.
#pragma once
#include "shaders/common.hpp"

namespace bvhlab::glsl::watertight {

constexpr float kWatertightMinNormal = 1.17549435e-38f;

inline bool intersectTriangle(Ray ray, vec3 v0, vec3 v1, vec3 v2, float tMin, float tMax, float& t, vec2& bary) {
  t = tMax;
  bary = vec2(0.0f);
  vec3 absDir = abs(ray.dir);
  int kz = absDir.x >= absDir.y ? (absDir.x >= absDir.z ? 0 : 2) : (absDir.y >= absDir.z ? 1 : 2);
  int kx = kz == 2 ? 0 : kz + 1;
  int ky = kx == 2 ? 0 : kx + 1;
  if (ray.dir[kz] < 0.0f) {
    int swapped = kx;
    kx = ky;
    ky = swapped;
  }
  if (!(absDir[kz] >= kWatertightMinNormal)) return false;
  float sx = ray.dir[kx] / ray.dir[kz];
  float sy = ray.dir[ky] / ray.dir[kz];
  float sz = 1.0f / ray.dir[kz];

  vec3 a = v0 - ray.origin;
  vec3 b = v1 - ray.origin;
  vec3 c = v2 - ray.origin;
  float ax = a[kx] - sx * a[kz];
  float ay = a[ky] - sy * a[kz];
  float bx = b[kx] - sx * b[kz];
  float by = b[ky] - sy * b[kz];
  float cx = c[kx] - sx * c[kz];
  float cy = c[ky] - sy * c[kz];

  float u = cx * by - cy * bx;
  float v = ax * cy - ay * cx;
  float w = bx * ay - by * ax;
  if (u == 0.0f || v == 0.0f || w == 0.0f) {
    double uExact = double(cx) * double(by) - double(cy) * double(bx);
    double vExact = double(ax) * double(cy) - double(ay) * double(cx);
    double wExact = double(bx) * double(ay) - double(by) * double(ax);
    u = float(uExact);
    v = float(vExact);
    w = float(wExact);
    if (u == 0.0f && uExact != 0.0) u = uExact > 0.0 ? kWatertightMinNormal : -kWatertightMinNormal;
    if (v == 0.0f && vExact != 0.0) v = vExact > 0.0 ? kWatertightMinNormal : -kWatertightMinNormal;
    if (w == 0.0f && wExact != 0.0) w = wExact > 0.0 ? kWatertightMinNormal : -kWatertightMinNormal;
  }
  if ((u < 0.0f || v < 0.0f || w < 0.0f) && (u > 0.0f || v > 0.0f || w > 0.0f)) return false;
  float det = u + v + w;
  if (!(abs(det) >= kWatertightMinNormal)) return false;

  float az = sz * a[kz];
  float bz = sz * b[kz];
  float cz = sz * c[kz];
  float scaledT = u * az + v * bz + w * cz;
  float invDet = 1.0f / det;
  float hitT = scaledT * invDet;
  if (hitT <= tMin || hitT >= tMax) return false;
  t = hitT;
  bary = vec2(v * invDet, w * invDet);
  return true;
}

}  // namespace bvhlab::glsl::watertight
