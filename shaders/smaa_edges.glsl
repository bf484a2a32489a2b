// SMAA 1x, pass 1: edge detection (Jimenez et al. 2012, Sec. 3 "local contrast adaptation").
// Prefixed with #version 450 core and: SMAA_THRESHOLD (float), SMAA_EDGE_COLOR (0: luma, 1: colour),
// SMAA_EDGE_GEOMETRY (1: luma contrast counted only between pixels whose primary rays hit different
// primitives, or a primitive and nothing: edges of geometry, not of textures; render/smaa.hpp).
// Reads the tracer's colour as stored (sRGB-encoded values, no decode): the paper detects edges on
// gamma-space values. Writes r = edge between (x-1,y) and (x,y), g = edge between (x,y-1) and (x,y).

layout(binding = 0) uniform sampler2D u_color;
layout(location = 0) out vec2 o_edges;
#if SMAA_EDGE_GEOMETRY
layout(binding = 1) uniform usampler2D u_primaryId;  // the tracer's primary hit id + 1 (0: miss)
#endif

// The paper's local contrast adaptation: an edge survives if its contrast is at least
// 1 / SMAA_LOCAL_CONTRAST_FACTOR of the largest contrast among the neighbouring edges.
#define SMAA_LOCAL_CONTRAST_FACTOR 2.0

vec3 smaaFetch(ivec2 p) {
  ivec2 size = textureSize(u_color, 0);
  return texelFetch(u_color, clamp(p, ivec2(0), size - 1), 0).rgb;
}

#if SMAA_EDGE_GEOMETRY
uint smaaPrimaryId(ivec2 p) {
  ivec2 size = textureSize(u_primaryId, 0);
  return texelFetch(u_primaryId, clamp(p, ivec2(0), size - 1), 0).r;
}
// 1 between pixels that see different primitives, else 0: a texture's contrast inside one primitive
// (already filtered by texture LOD, or meant to be seen) is not an edge.
float smaaGeometric(ivec2 a, ivec2 b) { return smaaPrimaryId(a) != smaaPrimaryId(b) ? 1.0 : 0.0; }
#else
float smaaGeometric(ivec2 a, ivec2 b) { return 1.0; }
#endif

float smaaContrast(vec3 a, vec3 b) {
#if SMAA_EDGE_COLOR
  vec3 d = abs(a - b);
  return max(max(d.r, d.g), d.b);
#else
  return abs(dot(a - b, vec3(0.2126, 0.7152, 0.0722)));  // Rec. 709 luma weights
#endif
}

void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  vec3 c = smaaFetch(p);
  vec3 cLeft = smaaFetch(p + ivec2(-1, 0));
  vec3 cBottom = smaaFetch(p + ivec2(0, -1));
  vec2 delta = vec2(smaaContrast(c, cLeft) * smaaGeometric(p, p + ivec2(-1, 0)),
                    smaaContrast(c, cBottom) * smaaGeometric(p, p + ivec2(0, -1)));
  vec2 edges = step(vec2(SMAA_THRESHOLD), delta);
  if (edges.x + edges.y == 0.0) {
    o_edges = vec2(0.0);
    return;
  }
  float deltaRight = smaaContrast(c, smaaFetch(p + ivec2(1, 0))) * smaaGeometric(p, p + ivec2(1, 0));
  float deltaTop = smaaContrast(c, smaaFetch(p + ivec2(0, 1))) * smaaGeometric(p, p + ivec2(0, 1));
  float deltaLeftLeft = smaaContrast(cLeft, smaaFetch(p + ivec2(-2, 0))) * smaaGeometric(p + ivec2(-1, 0), p + ivec2(-2, 0));
  float deltaBottomBottom = smaaContrast(cBottom, smaaFetch(p + ivec2(0, -2))) *
                            smaaGeometric(p + ivec2(0, -1), p + ivec2(0, -2));
  float maxDelta = max(max(max(delta.x, delta.y), max(deltaRight, deltaTop)), max(deltaLeftLeft, deltaBottomBottom));
  edges *= step(vec2(maxDelta), SMAA_LOCAL_CONTRAST_FACTOR * delta);
  o_edges = edges;
}
