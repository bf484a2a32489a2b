// SMAA 1x, pass 3: neighbourhood blending (Jimenez et al. 2012). Each pixel gathers the weights of the
// four edges around it, keeps the dominant direction (horizontal or vertical pair of neighbours) and
// blends with those neighbours in linear colour; pixels without weights pass through unchanged.
// Input and output hold sRGB-encoded values (the tracer's RGBA8).

layout(binding = 0) uniform sampler2D u_color;
layout(binding = 1) uniform sampler2D u_weights;
layout(location = 0) out vec4 o_color;

vec3 smaaSrgbToLinear(vec3 c) {  // IEC 61966-2-1
  return mix(c / 12.92, pow((c + 0.055) / 1.055, vec3(2.4)), greaterThan(c, vec3(0.04045)));
}
vec3 smaaLinearToSrgb(vec3 c) {
  c = clamp(c, 0.0, 1.0);
  return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, greaterThan(c, vec3(0.0031308)));
}

vec4 smaaWeightsAt(ivec2 p, ivec2 size) {
  if (any(greaterThanEqual(p, size))) return vec4(0.0);
  return texelFetch(u_weights, p, 0);
}

void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  ivec2 size = textureSize(u_color, 0);
  vec4 c = texelFetch(u_color, p, 0);
  vec4 w = texelFetch(u_weights, p, 0);
  // How much this pixel takes from each neighbour: bottom/left from its own edges (r, b: the owner's
  // share), top/right from the neighbours' edges (g, a: the neighbour-side share).
  float fromBottom = w.r, fromLeft = w.b;
  float fromTop = smaaWeightsAt(p + ivec2(0, 1), size).g;
  float fromRight = smaaWeightsAt(p + ivec2(1, 0), size).a;
  if (fromBottom + fromLeft + fromTop + fromRight == 0.0) {
    o_color = c;
    return;
  }
  bool horizontal = max(fromLeft, fromRight) > max(fromBottom, fromTop);
  ivec2 n1 = horizontal ? p + ivec2(-1, 0) : p + ivec2(0, -1);
  ivec2 n2 = horizontal ? p + ivec2(1, 0) : p + ivec2(0, 1);
  vec2 a = horizontal ? vec2(fromLeft, fromRight) : vec2(fromBottom, fromTop);
  vec3 lc = smaaSrgbToLinear(c.rgb);
  vec3 l1 = smaaSrgbToLinear(texelFetch(u_color, clamp(n1, ivec2(0), size - 1), 0).rgb);
  vec3 l2 = smaaSrgbToLinear(texelFetch(u_color, clamp(n2, ivec2(0), size - 1), 0).rgb);
  vec2 share = a / (a.x + a.y);
  vec3 blended = share.x * mix(lc, l1, a.x) + share.y * mix(lc, l2, a.y);
  o_color = vec4(smaaLinearToSrgb(blended), c.a);
}
