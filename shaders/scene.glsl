// scene.glsl — the scene's analytic objects, materials and lights (one UBO), and the two queries
// every ray uses: closest hit and any hit. Meshes go through the traversal kernel's traceClosest /
// traceAny (only when the scene has a mesh). C++ mirror: shaders/tracer.hpp.

#define KIND_SPHERE 0
#define KIND_BOX 1
#define KIND_CYLINDER 2
#define KIND_CONE 3
#define KIND_TORUS 4
#define KIND_PLANE 5

struct ObjectData {
  vec4 worldToObject0;  // rows of the affine world -> object map
  vec4 worldToObject1;
  vec4 worldToObject2;
  vec4 params;          // torus: (major, minor); plane: z = 1 if infinite
  ivec4 info;           // (kind, material, 0, 0)
};

struct MaterialData {
  vec4 color;     // rgb base colour, w = texture layer (-1: none)
  vec4 lighting;  // diffuse, ambient, specular, shininess
  vec4 optics;    // reflectivity, transparency, ior, 0
  vec4 emission;  // rgb, 0
  vec4 uvScale;   // xy
};

struct LightData {
  vec4 position;  // point: position, w = 0; directional: direction the light travels, w = 1
  vec4 radiance;  // rgb colour * intensity
};

layout(std140, binding = 0) uniform SceneBlock {
  ObjectData u_objects[OBJECT_ARRAY_SIZE];
  MaterialData u_materials[MATERIAL_ARRAY_SIZE];
  LightData u_lights[LIGHT_ARRAY_SIZE];
  vec4 u_ambient;  // world ambient colour
};

#ifdef PRIMARY_ID_OUT
// The primary ray's hit id (Hit::id; -1: miss), set by radiance() and written by main.glsl for
// SMAA's geometry edges (render/smaa.hpp).
int g_primaryId = -1;
#endif

struct Hit {
  float t;
  vec3 normal;      // unit shading normal, outward
  vec3 geomNormal;  // unit geometric normal, outward: decides entering vs leaving
  vec2 uv;
  int material;
  int id;           // analytic object index, or NUM_OBJECTS + original triangle id
#ifdef TEXTURE_LOD
  vec3 dpdu;        // world-space uv parametrisation at the hit (texture_lod.glsl)
  vec3 dpdv;
  float curvature;  // mean curvature, positive where the surface bulges along the outward normal
#endif
};

vec3 objectPoint(ObjectData o, vec3 p) {
  vec4 h = vec4(p, 1.0);
  return vec3(dot(o.worldToObject0, h), dot(o.worldToObject1, h), dot(o.worldToObject2, h));
}

vec3 objectVector(ObjectData o, vec3 v) {
  return vec3(dot(o.worldToObject0.xyz, v), dot(o.worldToObject1.xyz, v), dot(o.worldToObject2.xyz, v));
}

// Normals go back with the transpose of the world -> object linear part.
vec3 worldNormal(ObjectData o, vec3 n) {
  return n.x * o.worldToObject0.xyz + n.y * o.worldToObject1.xyz + n.z * o.worldToObject2.xyz;
}

// One analytic object; only the kinds this scene has are compiled in.
bool intersectObject(ObjectData o, Ray r, float tMax, out float t, out vec3 n, out vec2 uv) {
  int kind = o.info.x;
  t = tMax;
  n = vec3(0.0, 1.0, 0.0);
  uv = vec2(0.0);
#ifdef HAS_SPHERE
  if (kind == KIND_SPHERE) return intersectSphere(r, 0.0, tMax, t, n, uv);
#endif
#ifdef HAS_BOX
  if (kind == KIND_BOX) return intersectBox(r, 0.0, tMax, t, n, uv);
#endif
#ifdef HAS_CYLINDER
  if (kind == KIND_CYLINDER) return intersectCylinder(r, 0.0, tMax, t, n, uv);
#endif
#ifdef HAS_CONE
  if (kind == KIND_CONE) return intersectCone(r, 0.0, tMax, t, n, uv);
#endif
#ifdef HAS_TORUS
  if (kind == KIND_TORUS) return intersectTorus(r, o.params.xy, 0.0, tMax, t, n, uv);
#endif
#ifdef HAS_PLANE
  if (kind == KIND_PLANE) return intersectPlane(r, o.params.z > 0.5, 0.0, tMax, t, n, uv);
#endif
  return false;
}

#ifdef HAS_MESH
// Through the triangle format's loadTriangleIds (traversal/triangles_*.glsl).
int triangleId(int tri) {
  uint primitive, material, mesh;
  loadTriangleIds(tri, primitive, material, mesh);
  return int(primitive);
}
int triangleMaterial(int tri) {
  uint primitive, material, mesh;
  loadTriangleIds(tri, primitive, material, mesh);
  return int(material);
}
#endif

// Closest hit with 0 < t < tMax (callers offset secondary origins, see offsetRayOrigin).
bool intersectScene(Ray ray, float tMax, out Hit hit) {
  hit.t = tMax;
  hit.normal = vec3(0.0, 1.0, 0.0);
  hit.geomNormal = hit.normal;
  hit.uv = vec2(0.0);
  hit.material = 0;
  hit.id = -1;
#ifdef TEXTURE_LOD
  hit.dpdu = vec3(0.0);
  hit.dpdv = vec3(0.0);
  hit.curvature = 0.0;
  vec3 objectNormal = vec3(0.0, 1.0, 0.0);  // the closest object's, in its own space
#endif
  bool found = false;
  for (int i = 0; i < NUM_OBJECTS; ++i) {
    ObjectData o = u_objects[i];
    Ray r = Ray(objectPoint(o, ray.origin), objectVector(o, ray.dir));
    float t;
    vec3 n;
    vec2 uv;
    if (intersectObject(o, r, hit.t, t, n, uv)) {
      found = true;
      hit.t = t;
      hit.normal = normalize(worldNormal(o, n));
      hit.geomNormal = hit.normal;
      hit.uv = uv;
      hit.material = o.info.y;
      hit.id = i;
#ifdef TEXTURE_LOD
      objectNormal = n;
#endif
    }
  }
#ifdef TEXTURE_LOD
  if (found) {  // the closest object's parametrisation, mapped to world space
    ObjectData o = u_objects[hit.id];
    Ray r = Ray(objectPoint(o, ray.origin), objectVector(o, ray.dir));
    vec3 q = r.origin + hit.t * r.dir;
    objectSurface(o.info.x, o.params.xy, q, objectNormal, hit.dpdu, hit.dpdv, hit.curvature);
    mat3 objectToWorld = inverse(transpose(mat3(o.worldToObject0.xyz, o.worldToObject1.xyz, o.worldToObject2.xyz)));
    hit.dpdu = objectToWorld * hit.dpdu;
    hit.dpdv = objectToWorld * hit.dpdv;
    // Curvature is 1/length: divided by the object's mean scale (the cube root of the volume scale).
    hit.curvature *= pow(abs(determinant(objectToWorld)), -1.0 / 3.0);
  }
#endif
#ifdef HAS_MESH
  if (MESH_PRESENT) {  // constant true unless the uber shader runs a scene without a mesh
    g_meshRays++;
    MeshHit mh;
    if (traceClosest(ray, 0.0, hit.t, mh)) {
      found = true;
      vec3 v0, v1, v2;
      loadTriangle(mh.tri, v0, v1, v2);
      vec3 shadingNormal;
      vec2 uv;
      loadAttributes(mh.tri, mh.bary, shadingNormal, uv);
#ifdef TWO_LEVEL
      // The BLAS's triangle and normal are in its instance's object space (traversal/two_level.glsl):
      // the vertices placed in the world as the flat tree stores them, so the geometric normal (its
      // orientation included, under a mirroring transform too) is the flat tree's; the shading normal
      // by the inverse transpose. The instance's material (a shared BLAS holds one instance's), and
      // an id telling instances of one mesh apart (SMAA's geometry edges, the ids view).
      v0 = instancePointToWorld(g_instance, v0);
      v1 = instancePointToWorld(g_instance, v1);
      v2 = instancePointToWorld(g_instance, v2);
      shadingNormal = instanceNormalToWorld(g_instance, shadingNormal);
#endif
      vec3 geomNormal = normalize(cross(v1 - v0, v2 - v0));
      hit.t = mh.t;
      hit.geomNormal = geomNormal;
      // A shading normal on the other side of the surface than the geometric one is not usable.
      hit.normal = dot(shadingNormal, geomNormal) > 0.0 ? normalize(shadingNormal) : geomNormal;
      hit.uv = uv;
#ifdef TWO_LEVEL
      hit.material = int(instanceMaterial(g_instance));
      hit.id = NUM_OBJECTS + int((uint(triangleId(mh.tri)) + instanceId(g_instance) * 0x9E3779B9u) & 0x7FFFFFFFu);
#else
      hit.material = triangleMaterial(mh.tri);
      hit.id = NUM_OBJECTS + triangleId(mh.tri);
#endif
#ifdef TEXTURE_LOD
      meshSurface(mh.tri, v0, v1, v2, hit.dpdu, hit.dpdv, hit.curvature);
#endif
    }
  }
#endif
  return found;
}

// Any hit with 0 < t < tMax: shadow rays.
bool occluded(Ray ray, float tMax) {
  for (int i = 0; i < NUM_OBJECTS; ++i) {
    ObjectData o = u_objects[i];
    Ray r = Ray(objectPoint(o, ray.origin), objectVector(o, ray.dir));
    float t;
    vec3 n;
    vec2 uv;
    if (intersectObject(o, r, tMax, t, n, uv)) return true;
  }
#ifdef HAS_MESH
  if (MESH_PRESENT) {
    g_meshRays++;
    if (traceAny(ray, 0.0, tMax)) return true;
  }
#endif
  return false;
}
