// shade.glsl — local shading at a hit: emission + ambient + Lambert/Blinn-Phong from every light
// with a hard shadow ray. Secondary-ray origins are offset here. C++ mirror: shaders/tracer.hpp.

// Secondary rays start a small distance off the surface so they do not re-hit it ("acne").
// A hit point p = o + t d carries rounding error of a few ulps of the magnitudes it was computed
// from, max|o| + t |d| (>= max|p|), plus the intersection's own error in t, a few hundred ulps of
// the same: whatever the scene's scale, the error is relative to this magnitude. So the offset is
// 1e-4 of it: far above 2^-23 ~ 1.2e-7 relative spacing, far below any feature the scenes have at
// their scale. (An absolute term such as 1e-4 * (1 + max|p|) breaks scenes scaled to 1e-4.)
#define RAY_OFFSET_SCALE 1e-4

float hitMagnitude(Ray ray, float t) {
  return max(max(abs(ray.origin.x), abs(ray.origin.y)), abs(ray.origin.z)) + t * length(ray.dir);
}

vec3 offsetRayOrigin(vec3 p, vec3 towards, float magnitude) {
#ifdef RAY_OFFSET_ULP
  return offsetRayOriginUlp(p, towards, magnitude);  // --robust *ulp*: Waechter & Binder's ULP offset
#else
  return p + towards * (RAY_OFFSET_SCALE * magnitude);
#endif
}

vec3 surfaceAlbedo(MaterialData m, vec2 uv) {
  vec3 albedo = m.color.rgb;
#ifdef HAS_TEXTURES
  if (m.color.w >= 0.0) albedo *= textureLod(u_textures, vec3(uv * m.uvScale.xy, m.color.w), 0.0).rgb;
#endif
  return albedo;
}

#ifdef TEXTURE_LOD
// surfaceAlbedo with the level chosen by the ray cone of width w at the hit (texture_lod.glsl).
vec3 surfaceAlbedoCone(MaterialData m, Hit h, vec3 dir, float w) {
  vec3 albedo = m.color.rgb;
#ifdef HAS_TEXTURES
  if (m.color.w >= 0.0) {
    vec2 texSize = vec2(textureSize(u_textures, 0).xy) * m.uvScale.xy;
    vec3 at = vec3(h.uv * m.uvScale.xy, m.color.w);
#if TEXTURE_LOD_ANISO
    vec2 g1, g2;
    coneEllipse(w, dir, h.normal, h.dpdu, h.dpdv, g1, g2);
    AnisoTaps taps = anisoTaps(g1 * m.uvScale.xy, g2 * m.uvScale.xy, vec2(textureSize(u_textures, 0).xy));
#ifdef LOD_VIEW
    recordLod(taps.lod);
#endif
    vec3 sum = vec3(0.0);
    for (int i = 0; i < taps.count; ++i) {
      vec2 offset = ((float(i) + 0.5) / float(taps.count) - 0.5) * taps.major;
      sum += textureLod(u_textures, at + vec3(offset, 0.0), taps.lod).rgb;
    }
    albedo *= sum / float(taps.count);
#else
    float lod = coneLodIsotropic(w, dot(dir, h.normal), h.dpdu, h.dpdv, texSize);
#ifdef LOD_VIEW
    recordLod(lod);
#endif
    albedo *= textureLod(u_textures, at, lod).rgb;
#endif
  }
#endif
  return albedo;
}
#endif

// n faces the incoming ray (the caller flips it); p is the hit point, magnitude its hitMagnitude.
vec3 shadeLocal(MaterialData m, vec3 albedo, vec3 p, float magnitude, vec3 n, vec3 viewDir) {
  vec3 color = m.emission.rgb + albedo * m.lighting.y * u_ambient.rgb;
#ifdef HAS_LIGHTS
  for (int i = 0; i < NUM_LIGHTS; ++i) {
    LightData light = u_lights[i];
    vec3 toLight;
    float distance;
    if (light.position.w > 0.5) {
      toLight = -light.position.xyz;
      distance = INF;
    } else {
      vec3 d = light.position.xyz - p;
      distance = length(d);
      toLight = d / distance;
    }
    float nDotL = dot(n, toLight);
    if (nDotL > 0.0) {
#ifdef HAS_SHADOWS
      vec3 origin = offsetRayOrigin(p, n, magnitude);
      // The shadow ray stops at the light; origin moved by the offset, so measure from it.
      float tLight = light.position.w > 0.5 ? INF : length(light.position.xyz - origin);
      if (occluded(Ray(origin, toLight), tLight)) continue;
#endif
      vec3 h = normalize(toLight - viewDir);
      float spec = m.lighting.z > 0.0 ? m.lighting.z * pow(max(dot(n, h), 0.0), m.lighting.w) : 0.0;
      color += light.radiance.rgb * (albedo * m.lighting.x * nDotL + vec3(spec));
    }
  }
#endif
  return color;
}

// Schlick's approximation; F0 from the IOR ratio (the report's eq. 5-6). cosTheta is the cosine on
// the side of the optically thinner medium, which is what makes the approximation hold on exit too.
float schlickFresnel(float cosTheta, float ior) {
  float r0 = (ior - 1.0) / (ior + 1.0);
  r0 = r0 * r0;
  float m = clamp(1.0 - cosTheta, 0.0, 1.0);
  return r0 + (1.0 - r0) * m * m * m * m * m;
}

// How a surface splits an incoming ray: weights of its local shading, reflection and refraction,
// and the refracted direction (valid when kt > 0).
struct Scatter {
  float kLocal;
  float kr;
  float kt;
  vec3 refracted;
  vec3 n;         // normal facing the incoming ray
  bool entering;
};

Scatter scatterAt(MaterialData m, Hit h, vec3 dir) {
  Scatter s;
  s.entering = dot(dir, h.geomNormal) < 0.0;
  s.n = s.entering ? h.normal : -h.normal;
  float reflectivity = m.optics.x;
  float transparency = m.optics.y;
  float opaque = 1.0 - transparency;
  s.kLocal = opaque * (1.0 - reflectivity);
  s.kr = opaque * reflectivity;
  s.kt = 0.0;
  s.refracted = vec3(0.0);
#ifdef HAS_REFRACTION
  if (transparency > 0.0) {
    float ior = m.optics.z;
    float eta = s.entering ? 1.0 / ior : ior;
    float cosI = min(-dot(dir, s.n), 1.0);
    float sin2T = eta * eta * max(1.0 - cosI * cosI, 0.0);
    float fresnel = 1.0;  // total internal reflection
    if (sin2T < 1.0) {
      float cosT = sqrt(1.0 - sin2T);
      s.refracted = eta * dir + (eta * cosI - cosT) * s.n;
      fresnel = schlickFresnel(s.entering ? cosI : cosT, ior);
    }
    s.kr += transparency * fresnel;
    s.kt = transparency * (1.0 - fresnel);
  }
#endif
  return s;
}

#ifdef TEXTURE_LOD
// The cones (width, spread) of the rays leaving a hit, from the incoming cone at the hit (coneAt).
// Curvature is taken against the normal facing the incoming ray (texture_lod.glsl's sign).
vec2 reflectedCone(Hit h, Scatter s, vec2 cone) {
  float kappa = s.entering ? h.curvature : -h.curvature;
  return vec2(cone.x, coneSpreadAfter(cone.y, cone.x, kappa, true, 1.0, 1.0, 1.0));
}
vec2 refractedCone(MaterialData m, Hit h, Scatter s, vec3 dir, vec2 cone) {
  float kappa = s.entering ? h.curvature : -h.curvature;
  float eta = s.entering ? 1.0 / m.optics.z : m.optics.z;
  float cosI = min(-dot(dir, s.n), 1.0);
  float cosT = -dot(s.refracted, s.n);
  return vec2(cone.x, coneSpreadAfter(cone.y, cone.x, kappa, false, eta, cosI, cosT));
}
#endif
