// main.glsl — the full-screen pass: one camera ray per pixel (or per sub-sample), the chosen view,
// tone mapping and the sRGB encode. C++ mirror: shaders/tracer.hpp (renderPixel).

#define VIEW_SHADED 0
#define VIEW_NORMAL 1
#define VIEW_DEPTH 2
#define VIEW_PRIMID 3

uniform vec3 u_eye;
uniform vec3 u_forward;  // unit view direction
uniform vec3 u_right;    // scaled by tan(fov/2) * aspect
uniform vec3 u_up;       // scaled by tan(fov/2)
uniform vec2 u_resolution;
uniform float u_exposure;
uniform float u_sceneRadius;  // for the depth view

layout(location = 0) out vec4 o_color;
#ifdef COUNT_STATS
// x node visits, y triangle tests, z mesh rays | stack-overflow bit 31,
// w primary id + 1 (debug views; 0 = miss or shaded view) | non-finite bit 31 (see nonFinite)
layout(location = 1) out uvec4 o_stats;
// ray-box tests (g_boxTests) of the pixel's rays: a wide node visit tests several boxes
layout(location = 2) out uint o_boxTests;
#endif
#ifdef PRIMARY_ID_OUT
// The primary ray's hit id + 1 (0: miss), for SMAA's geometry edges (smaa_edges.glsl).
layout(location = 3) out uint o_primaryId;
#endif

Ray cameraRay(vec2 pixel) {
  vec2 ndc = 2.0 * pixel / u_resolution - 1.0;
  return Ray(u_eye, normalize(u_forward + ndc.x * u_right + ndc.y * u_up));
}

float srgbEncode(float c) {
  return c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}

// Exposure, tone map and clamp: the displayable linear value. Supersamples are averaged here,
// before the sRGB encode, so one bright sample cannot dominate a pixel.
vec3 toneMap(vec3 c) {
  c *= u_exposure;
#ifdef TONEMAP_REINHARD
  c = c / (1.0 + c);
#endif
  return clamp(c, 0.0, 1.0);
}

vec3 srgbEncode(vec3 c) { return vec3(srgbEncode(c.r), srgbEncode(c.g), srgbEncode(c.b)); }

// True when a component is NaN or +-infinite (all exponent bits set). A bit test rather than
// isnan/isinf, which a compiler that assumes finite math may fold to false. The RGBA8 target would
// clamp such a value to some colour and hide it; the stats target reports it instead.
bool nonFinite(vec3 c) {
  return any(equal(floatBitsToUint(c) & uvec3(0x7F800000u), uvec3(0x7F800000u)));
}

// A distinct, never-black colour per primitive id.
vec3 idColor(int id) {
  uint h = uint(id) * 2654435761u;
  h ^= h >> 15;
  return vec3(0.2) + 0.8 * vec3(float(h & 255u), float((h >> 8) & 255u), float((h >> 16) & 255u)) / 255.0;
}

void main() {
#ifdef TEXTURE_LOD
  // The primary cone's spread: one pixel's angle (Ray Tracing Gems ch. 20), per sub-sample.
  g_pixelSpread = atan(2.0 * length(u_up) / u_resolution.y) / float(SSAA_GRID);
#endif
  Ray ray = cameraRay(gl_FragCoord.xy);
  int primaryId = -1;
  bool nonFiniteValue = false;  // the radiance (shaded) or view value of some sample was not finite
  vec3 color;
#if VIEW == VIEW_SHADED
#if SSAA_GRID > 1
  // Supersampling in the tracer: a regular SSAA_GRID x SSAA_GRID grid of sub-pixel rays.
  vec3 sum = vec3(0.0);
  for (int j = 0; j < SSAA_GRID; ++j)
    for (int i = 0; i < SSAA_GRID; ++i) {
      vec2 offset = (vec2(i, j) + 0.5) / float(SSAA_GRID) - 0.5;
      vec3 L = radiance(cameraRay(gl_FragCoord.xy + offset));
      nonFiniteValue = nonFiniteValue || nonFinite(L);
      sum += toneMap(L);
    }
  color = srgbEncode(sum / float(SSAA_GRID * SSAA_GRID));
#else
  vec3 L = radiance(ray);
  nonFiniteValue = nonFinite(L);
  color = srgbEncode(toneMap(L));
#endif
#else
  Hit h;
  bool found = intersectScene(ray, INF, h);
  color = vec3(0.0);  // misses are pure black in every debug view
  if (found) {
    primaryId = h.id;
#if VIEW == VIEW_NORMAL
    color = abs(h.normal);  // a unit vector always has a component >= 1/sqrt(3): never black
#elif VIEW == VIEW_DEPTH
    color = vec3(max(u_sceneRadius / (u_sceneRadius + h.t), 1.0 / 255.0));
#elif VIEW == VIEW_PRIMID
    color = idColor(h.id);
#endif
  }
  nonFiniteValue = nonFinite(color);
#endif
#ifdef LOD_VIEW
  // Test view: the level of the first texture lookup along the primary path, 16 steps per level
  // (0: no lookup). C++ mirror: the same encoding (tracer.cpp).
  color = vec3(g_firstLod < 0.0 ? 0.0 : (g_firstLod * 16.0 + 1.0) / 255.0);
#endif
  o_color = vec4(color, 1.0);
#ifdef COUNT_STATS
#if defined(TWO_LEVEL) && defined(HAS_MESH)
  // Node visits and box tests of the TLAS walk with the BLAS walks' (as `trace --update` counts them);
  // instance tests are not triangle tests.
  g_nodeVisits += g_tlasNodeVisits;
  g_boxTests += g_tlasBoxTests;
#endif
  o_stats = uvec4(g_nodeVisits, g_triTests, g_meshRays | (g_stackOverflow ? 0x80000000u : 0u),
                  uint(primaryId + 1) | (nonFiniteValue ? 0x80000000u : 0u));
  o_boxTests = g_boxTests;
#endif
#ifdef PRIMARY_ID_OUT
#if VIEW == VIEW_SHADED
  o_primaryId = uint(g_primaryId + 1);
#else
  o_primaryId = uint(primaryId + 1);
#endif
#endif
}
