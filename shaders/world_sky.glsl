// world_sky.glsl — procedural sky: ground below the horizon, zenith-to-horizon gradient above.
uniform vec3 u_skyZenith;
uniform vec3 u_skyHorizon;
uniform vec3 u_skyGround;

vec3 worldSky(vec3 dir) {
  float y = dir.y / length(dir);
  return y < 0.0 ? mix(u_skyHorizon, u_skyGround, min(-y * 4.0, 1.0))
                 : mix(u_skyHorizon, u_skyZenith, sqrt(y));
}
