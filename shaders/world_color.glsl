// world_color.glsl — a constant background colour.
uniform vec3 u_worldColor;

vec3 worldColor(vec3 dir) { return u_worldColor; }
