// world_map.glsl — an equirectangular environment map (+Y up; u wraps, v clamps; rows bottom-up,
// so v = 0 is straight down), rotated by u_worldRotation radians about +Y.
uniform sampler2D u_worldMap;
uniform float u_worldRotation;

vec2 equirectUv(vec3 dir) {
  vec3 d = normalize(dir);
  float phi = atan(d.z, d.x) + u_worldRotation;
  float theta = asin(clamp(d.y, -1.0, 1.0));
  return vec2(phi / (2.0 * PI) + 0.5, theta / PI + 0.5);
}

vec3 worldMap(vec3 dir) { return textureLod(u_worldMap, equirectUv(dir), 0.0).rgb; }
