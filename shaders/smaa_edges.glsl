// SMAA 1x, pass 1: edge detection (Jimenez et al. 2012, Sec. 3 "local contrast adaptation").
// Prefixed with #version 450 core and: SMAA_THRESHOLD (float), SMAA_EDGE_COLOR (0: luma, 1: colour).
// Reads the tracer's colour as stored (sRGB-encoded values, no decode): the paper detects edges on
// gamma-space values. Writes r = edge between (x-1,y) and (x,y), g = edge between (x,y-1) and (x,y).

layout(binding = 0) uniform sampler2D u_color;
layout(location = 0) out vec2 o_edges;

// The paper's local contrast adaptation: an edge survives if its contrast is at least
// 1 / SMAA_LOCAL_CONTRAST_FACTOR of the largest contrast among the neighbouring edges.
#define SMAA_LOCAL_CONTRAST_FACTOR 2.0

vec3 smaaFetch(ivec2 p) {
  ivec2 size = textureSize(u_color, 0);
  return texelFetch(u_color, clamp(p, ivec2(0), size - 1), 0).rgb;
}

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
  vec2 delta = vec2(smaaContrast(c, cLeft), smaaContrast(c, cBottom));
  vec2 edges = step(vec2(SMAA_THRESHOLD), delta);
  if (edges.x + edges.y == 0.0) {
    o_edges = vec2(0.0);
    return;
  }
  float deltaRight = smaaContrast(c, smaaFetch(p + ivec2(1, 0)));
  float deltaTop = smaaContrast(c, smaaFetch(p + ivec2(0, 1)));
  float deltaLeftLeft = smaaContrast(cLeft, smaaFetch(p + ivec2(-2, 0)));
  float deltaBottomBottom = smaaContrast(cBottom, smaaFetch(p + ivec2(0, -2)));
  float maxDelta = max(max(max(delta.x, delta.y), max(deltaRight, deltaTop)), max(deltaLeftLeft, deltaBottomBottom));
  edges *= step(vec2(maxDelta), SMAA_LOCAL_CONTRAST_FACTOR * delta);
  o_edges = edges;
}
