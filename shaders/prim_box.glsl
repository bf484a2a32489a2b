// prim_box.glsl — ray vs the box [-1,1]^3. C++ mirror: shaders/primitives.hpp.
// Conventions (t, tMin/tMax, outward normal, NaN) as in prim_sphere.glsl.
//
// Slab test: the ray's interval inside the box is the intersection of its intervals inside the three
// slabs |x|,|y|,|z| <= 1, [sIn, sOut]; the hit is sIn, or sOut when the ray starts inside. The origin is
// first moved to the closest approach to the centre (as in prim_sphere.glsl), which also rejects lines
// that miss the bounding sphere (radius sqrt(3)) and keeps the hit point p + s d free of a large origin.
// A direction component of 0 is handled explicitly, not through 1/0 = INF (whose product with a 0 distance
// is a NaN that GLSL's min/max would silently drop).
bool intersectBox(Ray ray, float tMin, float tMax, out float t, out vec3 normal, out vec2 uv) {
  t = 0.0;
  normal = vec3(0.0, 1.0, 0.0);
  uv = vec2(0.0);
  float dd = dot(ray.dir, ray.dir);
  if (!(dd > 0.0 && dd < INF)) return false;  // zero, overflowing or NaN direction
  float tc = -dot(ray.origin, ray.dir) / dd;
  vec3 p = ray.origin + tc * ray.dir;
  if (!(dot(p, p) <= 3.0)) return false;  // misses the bounding sphere (or NaN)
  float sIn = -INF;
  float sOut = INF;
  int axisIn = 0;
  int axisOut = 0;
  for (int i = 0; i < 3; ++i) {
    if (ray.dir[i] != 0.0) {
      float s0 = (-1.0 - p[i]) / ray.dir[i];
      float s1 = (1.0 - p[i]) / ray.dir[i];
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
    } else if (!(abs(p[i]) <= 1.0)) {
      return false;  // parallel to the slab and outside it
    }
  }
  if (!(sIn <= sOut)) return false;
  float tIn = tc + sIn;
  float tOut = tc + sOut;
  float s;
  int axis;
  float side;  // +1 or -1: which of the two faces of `axis`
  if (tIn > tMin && tIn < tMax) {
    t = tIn;
    s = sIn;
    axis = axisIn;
    side = ray.dir[axisIn] > 0.0 ? -1.0 : 1.0;  // entering: the face the ray moves away from
  } else if (tOut > tMin && tOut < tMax) {
    t = tOut;
    s = sOut;
    axis = axisOut;
    side = ray.dir[axisOut] > 0.0 ? 1.0 : -1.0;  // leaving: the face the ray moves towards
  } else {
    return false;
  }
  vec3 hit = p + s * ray.dir;
  normal = vec3(0.0);
  normal[axis] = side;
  // Per-face uv: u to the right and v up as seen from outside (the Y faces seen with -Z up on +Y).
  if (axis == 0) {
    uv = vec2(-side * hit.z, hit.y);
  } else if (axis == 1) {
    uv = vec2(hit.x, -side * hit.z);
  } else {
    uv = vec2(side * hit.x, hit.y);
  }
  uv = clamp(0.5 * uv + 0.5, 0.0, 1.0);
  return true;
}
