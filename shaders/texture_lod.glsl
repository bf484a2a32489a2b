// texture_lod.glsl — texture level of detail by ray cones (--texture-lod cones | cones-aniso).
// Compiled in only when the scene samples a texture (material textures or a world map) and a cone
// mode is asked for; otherwise every lookup stays textureLod(..., 0.0). C++ mirror: shaders/tracer.cpp.
//
// Method: Akenine-Möller et al., "Texture Level of Detail Strategies for Real-Time Ray Tracing"
// (Ray Tracing Gems, 2019, ch. 20), and "Improved Shader and Texture Level of Detail Using Ray Cones"
// (JCGT 10(1), 2021). Every ray carries a cone (width w at its origin, spread angle gamma):
//  - primary rays start with w = 0 and gamma = the pixel's angle, atan(2 tan(fov/2) / height)
//    (per sub-sample with SSAA: divided by the grid);
//  - over a distance t the width grows to w + gamma t;
//  - at a hit the width's footprint on the surface selects the level:
//      lambda = log2(|w| / |cos theta|) - 0.5 log2(texel area in world units)
//    (isotropic), or the footprint ellipse (minor axis |w|, major |w| / |cos theta| in the plane of
//    incidence) is sampled by taps along its major axis (cones-aniso, after the 2021 paper's
//    anisotropic variant);
//  - at a reflection the spread widens by the surface's curvature across the footprint: the normal
//    turns by kappa w over it and a mirror doubles that, 2 kappa w (kappa: mean curvature, positive
//    where the surface bulges towards the ray). A refraction scales the spread by eta and adds
//    (eta cos_i - cos_t) kappa w, the refracted direction's change for a normal change of kappa w.
// kappa comes from the primitive (sphere 1/r, cylinder 1/(2r), cone and torus from their principal
// curvatures) and, for meshes, from the vertex normals along the triangle's edges (the 2021 paper's
// per-triangle approximation): kappa_ij = (n_j - n_i).(p_j - p_i) / |p_j - p_i|^2, averaged.

#define TEXTURE_LOD_ANISO (TEXTURE_LOD == 2)

// Grazing hits: |cos theta| is floored so the footprint stays finite. At 1e-3 it is 1000 cone widths,
// past the coarsest level of any texture GL accepts here (16384 = 2^14 texels).
#define CONE_MIN_COS 1e-3
// At most this many taps per anisotropic lookup (anisoTaps): 8 rather than GL's usual 16 to bound the
// cost on a CPU rasteriser; footprints longer than 8:1 blur along their minor axis instead.
#define CONE_MAX_ANISOTROPY 8.0

float g_pixelSpread = 0.0;  // the primary cone's spread angle, set by main()
#ifdef LOD_VIEW
float g_firstLod = -1.0;    // the level of the path's first texture lookup (-1: none yet)
void recordLod(float lod) {
  if (g_firstLod < 0.0) g_firstLod = clamp(lod, 0.0, 15.0);
}
#endif

// The cone a ray has reached at distance t (world units) along it: (width, spread).
vec2 coneAt(vec2 cone, float t) { return vec2(cone.x + cone.y * t, cone.y); }

// uv-space footprint axes of a world-space vector a on the surface with tangents dpdu, dpdv: the
// least-squares solution of a = du dpdu + dv dpdv (exact for a in the tangent plane).
vec2 uvOfVector(vec3 a, vec3 dpdu, vec3 dpdv) {
  float guu = dot(dpdu, dpdu), guv = dot(dpdu, dpdv), gvv = dot(dpdv, dpdv);
  float det = guu * gvv - guv * guv;
  if (!(det > 0.0)) return vec2(0.0);  // degenerate parametrisation (or NaN): no footprint
  vec2 b = vec2(dot(a, dpdu), dot(a, dpdv));
  return vec2(gvv * b.x - guv * b.y, guu * b.y - guv * b.x) / det;
}

// Isotropic level for a footprint of width w at a hit seen at |cos theta|, on a surface whose world
// area per unit uv is |dpdu x dpdv|, of a texture of texSize texels per unit uv.
float coneLodIsotropic(float w, float cosTheta, vec3 dpdu, vec3 dpdv, vec2 texSize) {
  float area = length(cross(dpdu, dpdv)) / (texSize.x * texSize.y);  // world area of one texel
  float width = abs(w) / max(abs(cosTheta), CONE_MIN_COS);
  if (!(area > 0.0) || !(width > 0.0)) return 0.0;  // no parametrisation or no footprint: level 0
  return log2(width) - 0.5 * log2(area);
}

// Footprint ellipse axes in uv (times texSize: texels), minor then major (see the header).
void coneEllipse(float w, vec3 dir, vec3 n, vec3 dpdu, vec3 dpdv, out vec2 g1, out vec2 g2) {
  float cosTheta = max(abs(dot(dir, n)), CONE_MIN_COS);
  vec3 inPlane = dir - dot(dir, n) * n;
  // At normal incidence the ellipse is a circle: any tangent will do.
  vec3 major = dot(inPlane, inPlane) > 0.0 ? normalize(inPlane) : normalize(dpdu + dpdv);
  vec3 minor = cross(n, major);
  g1 = uvOfVector(minor * abs(w), dpdu, dpdv);
  g2 = uvOfVector(major * (abs(w) / cosTheta), dpdu, dpdv);
}

// The anisotropic footprint sampled as EXT_texture_filter_anisotropic describes it: N = min(ceil(Pmax /
// Pmin), CONE_MAX_ANISOTROPY) trilinear taps spread along the major axis, each at lambda = log2(Pmax / N),
// where P are the axes' lengths in texels. Done in the shader rather than by GL's filter, so the C++
// mirror takes the same taps (llvmpipe's own anisotropic textureGrad also took ~40 s a frame here).
struct AnisoTaps {
  float lod;
  int count;
  vec2 major;  // uv extent of the major axis; tap i sits at ((i + 0.5) / count - 0.5) * major
};
AnisoTaps anisoTaps(vec2 g1, vec2 g2, vec2 texSize) {
  float p1 = length(g1 * texSize), p2 = length(g2 * texSize);
  AnisoTaps a;
  a.major = p1 > p2 ? g1 : g2;
  float pMax = max(p1, p2), pMin = min(p1, p2);
  a.count = 1;
  a.lod = 0.0;
  if (!(pMax > 0.0)) return a;  // no footprint (or NaN): one tap at level 0
  float n = pMin > 0.0 ? min(ceil(pMax / pMin), CONE_MAX_ANISOTROPY) : CONE_MAX_ANISOTROPY;
  a.count = int(n);
  a.lod = log2(pMax / n);
  return a;
}

// The spread after a reflection (reflected = true) or refraction at a hit with mean curvature kappa
// (positive where the surface bulges towards the incoming ray), for a cone of width w there.
float coneSpreadAfter(float spread, float w, float kappa, bool reflected, float eta, float cosI, float cosT) {
#ifdef CONE_NO_CURVATURE
  kappa = 0.0;  // test switch: the cone keeps its spread at curved surfaces
#endif
  if (reflected) return spread + 2.0 * kappa * w;
  return eta * spread + (eta * cosI - cosT) * kappa * w;
}

// The uv parametrisation and mean curvature of an analytic primitive at object-space point q with
// outward normal n (not unit), in object space: dpdu, dpdv as the prim_*.glsl uv mappings define them.
// kind in ObjectKind order (scene.glsl's KIND_*); radii: the torus's (major, minor).
// Caps and box faces are told apart from curved sides by the normal: caps are exactly +-Y, a cone's
// side has |n.y| / |n| = 1/sqrt(5) and a cylinder's 0, so any threshold in between separates them.
#define CAP_NORMAL_Y 0.9
// The cone's circumferential curvature grows as 1/rho towards the apex: rho is floored at 1e-4 object
// units, where a cone of that width already selects the coarsest level of any texture here.
#define CONE_MIN_RHO 1e-4
void objectSurface(int kind, vec2 radii, vec3 q, vec3 n, out vec3 dpdu, out vec3 dpdv, out float kappa) {
  vec3 around = 2.0 * PI * vec3(q.z, 0.0, -q.x);  // d/du of the longitude phi = atan(x, z), u = phi / 2pi
  float rho = length(q.xz);
  bool cap = abs(n.y) > CAP_NORMAL_Y * length(n);
  dpdu = vec3(2.0, 0.0, 0.0);  // planar mappings: uv = 0.5 * coordinate + 0.5
  dpdv = vec3(0.0, 0.0, 2.0);
  kappa = 0.0;
  if (kind == 0) {  // sphere: v = 0.5 + latitude / pi
    dpdu = around;
    dpdv = PI * (rho > 0.0 ? vec3(-q.y * q.x / rho, rho, -q.y * q.z / rho) : vec3(0.0, 0.0, 1.0));
    kappa = 1.0;
  } else if (kind == 1) {  // box: each face is planar, uv from its two in-face coordinates
    vec3 a = abs(n);
    if (a.x >= a.y && a.x >= a.z) dpdu = vec3(0.0, 0.0, -2.0 * sign(n.x)), dpdv = vec3(0.0, 2.0, 0.0);
    else if (a.y >= a.z) dpdu = vec3(2.0, 0.0, 0.0), dpdv = vec3(0.0, 0.0, -2.0 * sign(n.y));
    else dpdu = vec3(2.0 * sign(n.z), 0.0, 0.0), dpdv = vec3(0.0, 2.0, 0.0);
  } else if (kind == 2) {  // cylinder: side u = phi / 2pi, v = 0.5 + 0.5 y; principal curvatures 1, 0
    if (cap) dpdv = vec3(0.0, 0.0, -2.0 * sign(n.y));
    else dpdu = around, dpdv = vec3(0.0, 2.0, 0.0), kappa = 0.5;
  } else if (kind == 3) {  // cone: rho = (1 - y) / 2; circumferential curvature (2/sqrt(5)) / rho, 0
    if (!cap) {
      float r = max(rho, CONE_MIN_RHO);
      dpdu = around;
      dpdv = vec3(-q.x / r, 2.0, -q.z / r);
      kappa = 0.5 * (2.0 / sqrt(5.0)) / r;
    }
  } else if (kind == 4) {  // torus: u = phi / 2pi, v = 0.5 + theta / 2pi; curvatures 1/r (tube), cos(theta)/rho
    float R = radii.x, r = radii.y;
    float cosT = (rho - R) / r, sinT = q.y / r;
    dpdu = around;
    dpdv = 2.0 * PI * r * (rho > 0.0 ? vec3(-sinT * q.x / rho, cosT, -sinT * q.z / rho) : vec3(0.0, cosT, -sinT));
    kappa = 0.5 * (1.0 / r + (rho > 0.0 ? cosT / rho : 0.0));
  }
  // kind 5, plane: the planar default
}

#ifdef HAS_MESH
// A triangle's uv parametrisation (from its vertices' uvs) and mean curvature (from its vertex normals
// along the edges), world space. A triangle without uvs has dpdu = dpdv = 0 (no footprint: level 0).
void meshSurface(int tri, vec3 v0, vec3 v1, vec3 v2, out vec3 dpdu, out vec3 dpdv, out float kappa) {
  vec3 n0, n1, n2;
  vec2 t0, t1, t2;
  loadAttributes(tri, vec2(0.0, 0.0), n0, t0);
  loadAttributes(tri, vec2(1.0, 0.0), n1, t1);
  loadAttributes(tri, vec2(0.0, 1.0), n2, t2);
#ifdef TWO_LEVEL
  // v0..v2 are in world space (scene.glsl); the normals of a BLAS are in its instance's object space.
  n0 = normalize(instanceNormalToWorld(g_instance, n0));
  n1 = normalize(instanceNormalToWorld(g_instance, n1));
  n2 = normalize(instanceNormalToWorld(g_instance, n2));
#endif
  vec3 e1 = v1 - v0, e2 = v2 - v0;
  vec2 d1 = t1 - t0, d2 = t2 - t0;
  float det = d1.x * d2.y - d1.y * d2.x;
  dpdu = vec3(0.0);
  dpdv = vec3(0.0);
  if (abs(det) > 0.0) {
    dpdu = (d2.y * e1 - d1.y * e2) / det;
    dpdv = (d1.x * e2 - d2.x * e1) / det;
  }
  vec3 e3 = v2 - v1;
  float k01 = dot(n1 - n0, e1) / dot(e1, e1);
  float k02 = dot(n2 - n0, e2) / dot(e2, e2);
  float k12 = dot(n2 - n1, e3) / dot(e3, e3);
  kappa = (k01 + k02 + k12) / 3.0;
  if (!(abs(kappa) < INF)) kappa = 0.0;  // a degenerate edge (0/0 or x/0): no curvature estimate
}
#endif
