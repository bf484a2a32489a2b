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

#ifdef TEXTURE_LOD
// The map seen through a cone of spread angle `spread` (texture_lod.glsl). A texel spans 2pi/W in
// longitude (times cos(latitude) as an angle) and pi/H in latitude; cos(latitude) is floored at pi/H,
// the angular height of the polar row, so the footprint stays finite at the poles.
vec3 worldMapCone(vec3 dir, float spread) {
  vec2 size = vec2(textureSize(u_worldMap, 0));
  float cosLat = max(sqrt(max(1.0 - dir.y * dir.y / dot(dir, dir), 0.0)), PI / size.y);
  vec2 uv = equirectUv(dir);
#if TEXTURE_LOD_ANISO
  AnisoTaps taps = anisoTaps(vec2(abs(spread) / (2.0 * PI * cosLat), 0.0), vec2(0.0, abs(spread) / PI), size);
#ifdef LOD_VIEW
  recordLod(taps.lod);
#endif
  vec3 sum = vec3(0.0);
  for (int i = 0; i < taps.count; ++i)
    sum += textureLod(u_worldMap, uv + ((float(i) + 0.5) / float(taps.count) - 0.5) * taps.major, taps.lod).rgb;
  return sum / float(taps.count);
#else
  float texel = sqrt(2.0 * PI * cosLat / size.x * PI / size.y);  // a texel's angular width (geometric mean)
  float lod = abs(spread) > 0.0 ? log2(abs(spread) / texel) : 0.0;
#ifdef LOD_VIEW
  recordLod(lod);
#endif
  return textureLod(u_worldMap, uv, lod).rgb;
#endif
}
#endif
