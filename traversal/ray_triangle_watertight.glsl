// ray_triangle_watertight.glsl — Woop, Benthin & Wald (2013), "Watertight Ray/Triangle
// Intersection", JCGT 2(1). Drop-in for ray_triangle.glsl (same intersectTriangle). C++ mirror:
// ray_triangle_watertight.hpp.
//
// Why it does not leak: the vertices are moved into a frame where the ray is the +z axis through the
// origin (a translation, a permutation and a shear that depend on the ray only), and the hit is
// decided by the signs of three 2D edge functions of the transformed vertices. A vertex is
// transformed the same way whichever triangle it belongs to, and an edge's function in the neighbour
// (traversed in the opposite direction) is exactly the negation (round-to-nearest is symmetric), so a
// ray through a shared edge or vertex is inside (edges included) of at least one triangle. An edge
// function that rounds to exactly 0 is recomputed in double: the products of two floats are exact
// there, so its sign is exact too (paper, section 3.4).
// `precise` forbids fused multiply-adds and reordering: fusing one vertex's shear but not the other's,
// or one edge function but not its neighbour's negation, would break the argument above.

// The smallest normal float. A direction whose largest component is below it is treated as no
// direction (1 / dir[kz] would overflow); a determinant below it likewise (1 / det would overflow).
// Both guards are written so that a NaN input also fails them: NaN never reaches a later branch.
const float kWatertightMinNormal = 1.17549435e-38;

// Hit iff tMin < t < tMax and the ray meets the closed triangle with a non-zero determinant (a
// zero-area triangle or a ray in the triangle's plane: no single hit point, no hit).
// bary = (u, v): the weights of v1 and v2; v0 weighs 1 - u - v.
bool intersectTriangle(Ray ray, vec3 v0, vec3 v1, vec3 v2, float tMin, float tMax, out float t, out vec2 bary) {
  t = tMax;
  bary = vec2(0.0);
  // The ray frame: kz is the dominant axis; swapping kx, ky when dir[kz] < 0 keeps the winding.
  vec3 absDir = abs(ray.dir);
  int kz = absDir.x >= absDir.y ? (absDir.x >= absDir.z ? 0 : 2) : (absDir.y >= absDir.z ? 1 : 2);
  int kx = kz == 2 ? 0 : kz + 1;
  int ky = kx == 2 ? 0 : kx + 1;
  if (ray.dir[kz] < 0.0) {
    int swapped = kx;
    kx = ky;
    ky = swapped;
  }
  if (!(absDir[kz] >= kWatertightMinNormal)) return false;
  precise float sx = ray.dir[kx] / ray.dir[kz];
  precise float sy = ray.dir[ky] / ray.dir[kz];
  precise float sz = 1.0 / ray.dir[kz];

  precise vec3 a = v0 - ray.origin;
  precise vec3 b = v1 - ray.origin;
  precise vec3 c = v2 - ray.origin;
  precise float ax = a[kx] - sx * a[kz];
  precise float ay = a[ky] - sy * a[kz];
  precise float bx = b[kx] - sx * b[kz];
  precise float by = b[ky] - sy * b[kz];
  precise float cx = c[kx] - sx * c[kz];
  precise float cy = c[ky] - sy * c[kz];

  // Edge functions: u is opposite v0 (edge v1 v2), v opposite v1, w opposite v2.
  precise float u = cx * by - cy * bx;
  precise float v = ax * cy - ay * cx;
  precise float w = bx * ay - by * ax;
  if (u == 0.0 || v == 0.0 || w == 0.0) {
    precise double uExact = double(cx) * double(by) - double(cy) * double(bx);
    precise double vExact = double(ax) * double(cy) - double(ay) * double(cx);
    precise double wExact = double(bx) * double(ay) - double(by) * double(ax);
    u = float(uExact);
    v = float(vExact);
    w = float(wExact);
    // float() of a non-zero double below the float range rounds to 0: only the sign matters for the
    // decision, so such a value becomes the smallest normal float of that sign.
    if (u == 0.0 && uExact != 0.0lf) u = uExact > 0.0lf ? kWatertightMinNormal : -kWatertightMinNormal;
    if (v == 0.0 && vExact != 0.0lf) v = vExact > 0.0lf ? kWatertightMinNormal : -kWatertightMinNormal;
    if (w == 0.0 && wExact != 0.0lf) w = wExact > 0.0lf ? kWatertightMinNormal : -kWatertightMinNormal;
  }
  // Mixed signs: the ray passes outside (both windings are hits: no culling).
  if ((u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0)) return false;
  precise float det = u + v + w;
  if (!(abs(det) >= kWatertightMinNormal)) return false;  // 0: zero area, or the ray in its plane

  precise float az = sz * a[kz];
  precise float bz = sz * b[kz];
  precise float cz = sz * c[kz];
  precise float scaledT = u * az + v * bz + w * cz;
  float invDet = 1.0 / det;
  float hitT = scaledT * invDet;
  if (hitT <= tMin || hitT >= tMax) return false;
  t = hitT;
  bary = vec2(v * invDet, w * invDet);
  return true;
}
