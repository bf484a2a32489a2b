// world.glsl — what a ray that leaves the scene sees. Only the scene's world kind is compiled in,
// except in the uber shader, which switches at run time.
uniform float u_worldIntensity;
#ifdef UBER
uniform int u_worldKind;  // 0 colour, 1 sky, 2 map (WorldKind order)
#endif

vec3 worldRadiance(vec3 dir) {
#if defined(UBER)
  vec3 c = u_worldKind == 0 ? worldColor(dir) : (u_worldKind == 1 ? worldSky(dir) : worldMap(dir));
#elif defined(WORLD_COLOR)
  vec3 c = worldColor(dir);
#elif defined(WORLD_SKY)
  vec3 c = worldSky(dir);
#else
  vec3 c = worldMap(dir);
#endif
  return c * u_worldIntensity;
}

#ifdef TEXTURE_LOD
// worldRadiance for a ray whose cone has spread angle `spread`: only the map has texels to filter.
vec3 worldRadianceCone(vec3 dir, float spread) {
#if defined(UBER)
  vec3 c = u_worldKind == 0 ? worldColor(dir) : (u_worldKind == 1 ? worldSky(dir) : worldMapCone(dir, spread));
  return c * u_worldIntensity;
#elif defined(WORLD_MAP)
  return worldMapCone(dir, spread) * u_worldIntensity;
#else
  return worldRadiance(dir);
#endif
}
#endif
