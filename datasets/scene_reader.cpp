// The TOML scene reader (scene_io.hpp's loadScene, docs/scene-format.md): every key validated, every
// error one line "FILE:LINE: message". Positions are read in double and stored relative to
// Scene::origin; mesh files are read in double (loadMeshData) and baked to world space in double.
// Typed value reads live in toml_fields.hpp; a [clip]'s keys and deformations are read by
// animation_reader.cpp and evaluated by datasets/animation.hpp (the loaded scene is frame 0).
#include <algorithm>
#include <cmath>
#include <fstream>
#include <initializer_list>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <tuple>

#include <glm/gtc/matrix_transform.hpp>
#include <toml++/toml.h>

#include "datasets/animation_reader.hpp"
#include "datasets/bench_generators.hpp"
#include "datasets/image_io.hpp"
#include "datasets/mesh_io.hpp"
#include "datasets/procedural.hpp"
#include "datasets/scene_io.hpp"
#include "datasets/toml_fields.hpp"
#include "datasets/toml_guard.hpp"

namespace bvhlab {
namespace fs = std::filesystem;

namespace {

using namespace toml_fields;

constexpr std::string_view kBuiltinPrefix = "builtin:";
constexpr int kBuiltinTextureSize = 512;
constexpr int kMaxImageSide = 16384;
constexpr int kMaxDepth = 32;

// Reads one TOML scene file into a Scene; all validation and error formatting lives here.
class SceneReader : toml_fields::TomlFields {
 public:
  explicit SceneReader(const fs::path& file) : TomlFields(file), dir_(file.parent_path()), anim_(file) {}

  Scene read() {
    std::error_code ec;
    if (!fs::exists(file_, ec)) throw FileError(file_.string() + ": scene file not found");
    std::ifstream in(file_, std::ios::binary);
    if (!in) throw FileError(file_.string() + ": cannot open the scene file");
    std::ostringstream bytes;
    bytes << in.rdbuf();
    const std::string text = bytes.str();
    // Code points toml++ 3.3.0 cannot parse without undefined behaviour (datasets/toml_guard.hpp).
    if (const std::optional<TomlTextHazard> h = findTomlTextHazard(text))
      throw InputError(file_.string() + ':' + std::to_string(h->line) + ':' + std::to_string(h->column) + ": " +
                       h->message);
    toml::table root;
    try {
      root = toml::parse(text, file_.string());
    } catch (const toml::parse_error& e) {
      failAt(e.source().begin.line, "TOML syntax error: " + std::string(e.description()));
    }
    scene_.source = file_;
    checkKeys(root, {"description", "clip", "camera", "render", "world", "light", "material", "object"}, "the top level");
    if (auto* d = root.get("description"); d && !d->is_string()) fail(*d, "description must be a string");

    const toml::table* camera = tableAt(root, "camera");
    if (!camera) failAt(1, "missing [camera] section (eye and target are required)");
    // A [clip] makes the scene animated (datasets/animation.hpp); keys and deformations need one.
    if (const toml::table* t = tableAt(root, "clip")) {
      animation_ = std::make_shared<SceneAnimation>();
      animation_->clip = anim_.readClip(*t);
    }
    readCamera(*camera);
    if (const toml::table* t = tableAt(root, "render")) readRender(*t);
    if (const toml::table* t = tableAt(root, "world")) readWorld(*t);
    for (const toml::table* t : tableArray(root, "light")) readLight(*t);
    for (const toml::table* t : tableArray(root, "material")) readMaterial(*t);
    const auto objects = tableArray(root, "object");
    if (objects.empty()) failAt(1, "scene has no [[object]]");
    for (const toml::table* t : objects) readObject(*t);
    if (animation_) {
      scene_.animation = animation_;
      checkAnimatedMeshes(objects);
      setFrame(scene_, 0);  // the loaded scene is frame 0: animated meshes and transforms written here
    }
    return std::move(scene_);
  }

 private:
  fs::path dir_;
  Scene scene_;
  std::map<std::string, int> imageIndex_;     // canonical path or builtin name -> Scene::images
  std::map<std::string, MeshData> meshCache_; // canonical path -> object-space mesh (double positions)
  std::map<std::string, int> materialIndex_;  // name -> Scene::materials
  AnimationReader anim_;
  std::shared_ptr<SceneAnimation> animation_;  // null: no [clip]
  // (mesh data, fit, unwelded) -> SceneAnimation::localMeshes: instances of one mesh share their rest mesh.
  std::map<std::tuple<const MeshData*, double, bool>, int> localMeshIndex_;
  const Clip* clip() const { return animation_ ? &animation_->clip : nullptr; }

  // The `mesh` node of a mesh object (a missing one is reported, never dereferenced).
  const toml::node& requireMeshNode(const toml::table& t, const std::string& where) const {
    const toml::node* n = t.get("mesh");
    if (!n) failAt(t.source().begin.line, where + ": missing required key 'mesh' (or 'generate')");
    return *n;
  }
  // A position, read in double precision and stored relative to the scene's origin (Scene::origin), so
  // a scene far from the world origin keeps the float precision of the same scene near it.
  std::optional<glm::vec3> getPoint(const toml::table& t, std::string_view key, const std::string& where) const {
    const toml::node* n = t.get(key);
    if (!n) return std::nullopt;
    return glm::vec3(pointOf(*n, where + "." + std::string(key)) - scene_.origin);
  }
  // ---- files ----
  fs::path resolve(const std::string& relative) const { return (dir_ / relative).lexically_normal(); }

  // A readable message for a file the scene names that is not there.
  [[noreturn]] void failMissing(const toml::node& n, const std::string& what, const std::string& given,
                                const fs::path& resolved) const {
    std::string msg = what + " '" + given + "' not found (looked for " + resolved.string() + ")";
    std::error_code ec;
    if (resolved.string().find("datasets/cache") != std::string::npos && !fs::is_directory(resolved.parent_path(), ec))
      msg += "; the dataset cache is missing: run `bash datasets/fetch.sh`";
    fail(n, msg);
  }

  int imageFor(const toml::node& n, const std::string& spec, const std::string& what) {
    std::string key;
    fs::path path;
    if (spec.rfind(kBuiltinPrefix, 0) == 0) {
      key = spec;
      if (spec != "builtin:logo" && spec != "builtin:checker")
        fail(n, what + ": unknown builtin image '" + spec + "' (builtin:logo, builtin:checker)");
    } else {
      if (spec.empty()) fail(n, what + " path is empty");
      path = resolve(spec);
      std::error_code ec;
      if (!fs::is_regular_file(path, ec)) failMissing(n, what, spec, path);
      key = fs::weakly_canonical(path, ec).string();
    }
    if (auto it = imageIndex_.find(key); it != imageIndex_.end()) return it->second;
    Image img;
    if (key == "builtin:logo") img = makeLogoTexture(kBuiltinTextureSize);
    else if (key == "builtin:checker") img = makeCheckerTexture(kBuiltinTextureSize, 8);
    else {
      try {
        img = loadImage(path);
      } catch (const InputError& e) {
        fail(n, what + ": " + e.what());
      }
    }
    scene_.images.push_back(std::move(img));
    const int index = int(scene_.images.size()) - 1;
    imageIndex_[key] = index;
    return index;
  }

  const MeshData& meshFor(const toml::node& n, const std::string& spec) {
    if (spec.empty()) fail(n, "mesh path is empty");
    const fs::path path = resolve(spec);
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) failMissing(n, "mesh", spec, path);
    const std::string key = fs::weakly_canonical(path, ec).string();
    if (auto it = meshCache_.find(key); it != meshCache_.end()) return it->second;
    try {
      return meshCache_.emplace(key, loadMeshData(path)).first->second;
    } catch (const InputError& e) {
      fail(n, std::string("mesh: ") + e.what());
    }
  }

  // A procedural mesh (datasets/bench_generators.hpp) instead of a file: generate = "NAME",
  // triangles = N (required), seed = S (default 1). Cached like files, by (name, triangles, seed).
  const MeshData& generatedMeshFor(const toml::table& t, const std::string& w) {
    const toml::node& gen = *t.get("generate");
    if (t.get("mesh")) fail(gen, w + ": give either mesh = \"FILE\" or generate = \"NAME\", not both");
    const std::string name = *getString(t, "generate", w);
    bool known = false;
    for (const BenchGenerator& g : benchGenerators()) known = known || g.name == name;
    if (!known) fail(gen, w + ".generate: unknown generator \"" + name + "\" (known: " + benchGeneratorNames() + ")");
    const toml::node* tri = t.get("triangles");
    if (!tri) fail(gen, w + ": generate = \"" + name + "\" needs triangles = N");
    if (!tri->is_integer()) fail(*tri, w + ".triangles must be an integer");
    const int64_t count = tri->value<int64_t>().value_or(0);
    uint64_t seed = 1;
    if (const toml::node* sn = t.get("seed")) {
      if (!sn->is_integer() || sn->value<int64_t>().value_or(-1) < 0)
        fail(*sn, w + ".seed must be a non-negative integer");
      seed = uint64_t(sn->value<int64_t>().value_or(1));
    }
    try {
      checkBenchRequest(name, count);
    } catch (const InputError& e) {
      fail(*tri, w + ".triangles: " + e.what());
    }
    const std::string key = "generate:" + name + ":" + std::to_string(count) + ":" + std::to_string(seed);
    if (auto it = meshCache_.find(key); it != meshCache_.end()) return it->second;
    Mesh mesh = generateBenchMesh(name, count, seed);
    MeshData data;
    data.name = key;
    data.positions.assign(mesh.positions.begin(), mesh.positions.end());  // float -> double is exact
    mesh.positions = {};
    data.normals = std::move(mesh.normals);
    data.uvs = std::move(mesh.uvs);
    data.triangles = std::move(mesh.triangles);
    return meshCache_.emplace(key, std::move(data)).first->second;
  }

  // ---- sections ----
  void readCamera(const toml::table& t) {
    const std::string w = "camera";
    checkKeys(t, {"eye", "target", "up", "fov", "keys"}, "[camera]");
    Camera& c = scene_.camera;
    if (const toml::node* keys = t.get("keys")) {
      readCameraPath(t, *keys);
      return;
    }
    if (!t.get("eye")) failAt(t.source().begin.line, w + ": missing required key 'eye'");
    if (!t.get("target")) failAt(t.source().begin.line, w + ": missing required key 'target'");
    // Camera-relative coordinates for far scenes: every position is stored relative to the eye (the
    // subtraction in double precision). Below kRebaseDistance the origin stays at 0, so scenes near the
    // world origin keep their coordinates exactly; beyond it, float spacing (>= 2^-13 = 1.2e-4 at 1024)
    // reaches the tracer's secondary-ray offsets and rounding of positions would show in the image.
    const glm::dvec3 eye = pointOf(*t.get("eye"), w + ".eye");
    if (glm::any(glm::greaterThanEqual(glm::abs(eye), glm::dvec3(kRebaseDistance)))) scene_.origin = eye;
    c.eye = *getPoint(t, "eye", w);
    c.target = *getPoint(t, "target", w);
    readCameraLens(t);
    if (const char* problem = cameraProblem(c)) failAt(t.source().begin.line, std::string("camera: ") + problem);
  }

  void readCameraLens(const toml::table& t) {
    Camera& c = scene_.camera;
    c.up = getVec3(t, "up", "camera").value_or(glm::vec3(0, 1, 0));
    c.fovDeg = getFloat(t, "fov", "camera", c.fovDeg, Range{0.0, 180.0, true, true});
    if (!(glm::length(c.up) > 0.0f)) fail(*t.get("up"), "camera.up must not be zero");
  }

  // Why the camera has no view basis, or null.
  static const char* cameraProblem(const Camera& c) {
    const glm::vec3 view = c.target - c.eye;
    // Relative tolerances: a view vector shorter than 1e-6 of the eye's magnitude, or an up vector
    // within ~0.06 degrees of it, leaves the camera basis undefined or numerically meaningless.
    const float scale = std::max({1.0f, glm::length(c.eye), glm::length(c.target)});
    if (!(glm::length(view) > 1e-6f * scale)) return "eye and target coincide";
    if (!(glm::length(glm::cross(glm::normalize(view), glm::normalize(c.up))) > 1e-3f))
      return "up is parallel to the view direction";
    return nullptr;
  }

  // [[camera.keys]]: the camera path (datasets/animation.hpp); the origin follows the first key's eye.
  void readCameraPath(const toml::table& t, const toml::node& keys) {
    for (const char* k : {"eye", "target"})
      if (const toml::node* n = t.get(k))
        fail(*n, "camera: give either eye and target or [[camera.keys]], not both (the keys hold the eye and target)");
    readCameraLens(t);
    const std::vector<CameraKeyInput> in = anim_.readCameraKeys(keys, clip(), scene_.camera.fovDeg);
    const glm::dvec3 eye = in.front().key.eye;
    if (glm::any(glm::greaterThanEqual(glm::abs(eye), glm::dvec3(kRebaseDistance)))) scene_.origin = eye;
    std::vector<CameraKey>& path = animation_->camera;
    for (CameraKeyInput k : in) {
      k.key.eye -= scene_.origin;
      k.key.target -= scene_.origin;
      path.push_back(k.key);
    }
    // Every frame of the clip must have a camera basis, between keys too.
    size_t key = 0;
    for (int f = 0; f < animation_->clip.frames; ++f) {
      while (key + 1 < in.size() && in[key + 1].key.frame <= f) ++key;
      if (const char* problem = cameraProblem(sampleCamera(path, double(f), scene_.camera)))
        failAt(in[key].line, "camera.keys: at frame " + std::to_string(f) + " " + problem);
    }
    scene_.camera = sampleCamera(path, 0.0, scene_.camera);
  }

  void readRender(const toml::table& t) {
    const std::string w = "render";
    checkKeys(t, {"width", "height", "max_depth", "exposure", "tonemap"}, "[render]");
    RenderSettings& r = scene_.settings;
    r.width = getInt(t, "width", w, r.width, 1, kMaxImageSide);
    r.height = getInt(t, "height", w, r.height, 1, kMaxImageSide);
    r.maxDepth = getInt(t, "max_depth", w, r.maxDepth, 1, kMaxDepth);
    r.exposure = getFloat(t, "exposure", w, r.exposure, kPositive);
    if (auto tm = getString(t, "tonemap", w)) {
      if (*tm == "none") r.reinhard = false;
      else if (*tm == "reinhard") r.reinhard = true;
      else fail(*t.get("tonemap"), "render.tonemap must be \"none\" or \"reinhard\" (got \"" + *tm + "\")");
    }
  }

  void readWorld(const toml::table& t) {
    const std::string w = "world";
    checkKeys(t, {"kind", "color", "zenith", "horizon", "ground", "map", "rotation", "intensity", "ambient"}, "[world]");
    World& world = scene_.world;
    const std::string kind = getString(t, "kind", w).value_or("sky");
    if (kind == "sky") world.kind = WorldKind::Sky;
    else if (kind == "color") world.kind = WorldKind::Color;
    else if (kind == "map") world.kind = WorldKind::Map;
    else fail(*t.get("kind"), "world.kind must be \"sky\", \"color\" or \"map\" (got \"" + kind + "\")");
    rejectForeignKeys(t, w, kind, {{"color", "color"}, {"zenith", "sky"}, {"horizon", "sky"}, {"ground", "sky"},
                                   {"map", "map"}, {"rotation", "map"}});
    world.color = getVec3(t, "color", w, kNonNegative).value_or(world.color);
    world.zenith = getVec3(t, "zenith", w, kNonNegative).value_or(world.zenith);
    world.horizon = getVec3(t, "horizon", w, kNonNegative).value_or(world.horizon);
    world.ground = getVec3(t, "ground", w, kNonNegative).value_or(world.ground);
    world.intensity = getFloat(t, "intensity", w, world.intensity, kNonNegative);
    world.rotationDeg = getFloat(t, "rotation", w, world.rotationDeg);
    world.ambient = getVec3(t, "ambient", w, kNonNegative).value_or(world.ambient);
    if (world.kind == WorldKind::Map) {
      auto map = getString(t, "map", w);
      if (!map) failAt(t.source().begin.line, "world: kind = \"map\" needs map = \"FILE\" (or \"builtin:...\")");
      world.image = imageFor(*t.get("map"), *map, "world map");
    }
  }

  void readLight(const toml::table& t) {
    const std::string w = "light " + std::to_string(scene_.lights.size() + 1);
    checkKeys(t, {"kind", "position", "direction", "color", "intensity"}, "[[light]]");
    Light l;
    const std::string kind = requireString(t, "kind", w);
    if (kind != "point" && kind != "directional")
      fail(*t.get("kind"), w + ": kind must be \"point\" or \"directional\" (got \"" + kind + "\")");
    rejectForeignKeys(t, w, kind, {{"position", "point"}, {"direction", "directional"}});
    if (kind == "point") {
      l.kind = LightKind::Point;
      if (!t.get("position")) failAt(t.source().begin.line, w + ": missing required key 'position'");
      l.position = *getPoint(t, "position", w);
    } else {
      l.kind = LightKind::Directional;
      l.direction = requireVec3(t, "direction", w);
      if (!(glm::length(l.direction) > 0.0f)) fail(*t.get("direction"), w + ": direction must not be zero");
      l.direction = glm::normalize(l.direction);
    }
    l.color = getVec3(t, "color", w, kNonNegative).value_or(l.color);
    l.intensity = getFloat(t, "intensity", w, l.intensity, kNonNegative);
    scene_.lights.push_back(l);
  }

  void readMaterial(const toml::table& t) {
    checkKeys(t, {"name", "color", "texture", "uv_scale", "diffuse", "ambient", "specular", "shininess",
                  "reflectivity", "transparency", "ior", "emission"},
              "[[material]]");
    Material m;
    m.name = requireString(t, "name", "material " + std::to_string(scene_.materials.size() + 1));
    if (m.name.empty()) fail(*t.get("name"), "material name is empty");
    const std::string w = "material '" + m.name + "'";
    if (materialIndex_.count(m.name)) fail(*t.get("name"), "duplicate material name '" + m.name + "'");
    m.color = getVec3(t, "color", w, kUnit).value_or(m.color);
    if (auto tex = getString(t, "texture", w)) m.texture = imageFor(*t.get("texture"), *tex, w + " texture");
    if (const toml::node* n = t.get("uv_scale")) m.uvScale = scalarOrVec<2>(*n, w + ".uv_scale", kPositive);
    m.diffuse = getFloat(t, "diffuse", w, m.diffuse, kUnit);
    m.ambient = getFloat(t, "ambient", w, m.ambient, kUnit);
    m.specular = getFloat(t, "specular", w, m.specular, kUnit);
    m.shininess = getFloat(t, "shininess", w, m.shininess, Range{0.0, 1.0e4, true, false});
    m.reflectivity = getFloat(t, "reflectivity", w, m.reflectivity, kUnit);
    m.transparency = getFloat(t, "transparency", w, m.transparency, kUnit);
    m.ior = getFloat(t, "ior", w, m.ior, kPositive);
    m.emission = getVec3(t, "emission", w, kNonNegative).value_or(m.emission);
    if (m.reflectivity + m.transparency > 1.0f) {
      const toml::node* n = t.get("transparency") ? t.get("transparency") : t.get("reflectivity");
      fail(*n, w + ": reflectivity + transparency must be <= 1 (got " + fmt(m.reflectivity) + " + " +
                   fmt(m.transparency) + ")");
    }
    materialIndex_[m.name] = int(scene_.materials.size());
    scene_.materials.push_back(m);
  }

  int defaultMaterial() {
    if (auto it = materialIndex_.find("default"); it != materialIndex_.end()) return it->second;
    Material m;
    m.name = "default";
    materialIndex_[m.name] = int(scene_.materials.size());
    scene_.materials.push_back(m);
    return materialIndex_[m.name];
  }

  void readObject(const toml::table& t) {
    checkKeys(t, {"kind", "name", "material", "translate", "rotate", "scale", "major_radius", "minor_radius",
                  "infinite", "mesh", "fit", "generate", "triangles", "seed", "keys", "deform"},
              "[[object]]");
    Object o;
    const std::string ordinal = "object " + std::to_string(scene_.objects.size() + 1);
    const std::string kind = requireString(t, "kind", ordinal);
    bool known = false;
    for (int k = 0; k < kObjectKindCount; ++k)
      if (kind == objectKindName(ObjectKind(k))) {
        o.kind = ObjectKind(k);
        known = true;
      }
    if (!known)
      fail(*t.get("kind"), ordinal + ": unknown kind \"" + kind +
                               "\" (sphere, box, cylinder, cone, torus, plane, mesh)");
    o.name = getString(t, "name", ordinal).value_or(kind + std::to_string(scene_.objects.size() + 1));
    const std::string w = ordinal + " (" + o.name + ")";
    rejectForeignKeys(t, w, kind, {{"major_radius", "torus"}, {"minor_radius", "torus"}, {"infinite", "plane"},
                                   {"mesh", "mesh"}, {"fit", "mesh"}, {"generate", "mesh"}, {"triangles", "mesh"},
                                   {"seed", "mesh"}, {"deform", "mesh"}});

    if (auto name = getString(t, "material", w)) {
      auto it = materialIndex_.find(*name);
      if (it == materialIndex_.end()) {
        std::string known;
        for (const Material& m : scene_.materials) known += (known.empty() ? "" : ", ") + m.name;
        fail(*t.get("material"), w + ": unknown material '" + *name + "'" +
                                     (known.empty() ? " (no [[material]] defined before it)" : " (known: " + known + ")"));
      }
      o.material = it->second;
    } else {
      o.material = defaultMaterial();
    }
    // Animation (datasets/animation.hpp): keys replace the fixed placement; a deformation bends the mesh
    // in object space before the placement or the keys.
    ObjectAnimation anim;
    if (const toml::node* keys = t.get("keys")) {
      for (const char* k : {"translate", "rotate", "scale"})
        if (const toml::node* n = t.get(k))
          fail(*n, w + ": '" + k + "' and keys exclude each other (the keys place the object: give position, "
                   "rotation and scale in them)");
      anim.keys = anim_.readObjectKeys(*keys, clip(), scene_.origin, w);
    }
    if (const toml::node* d = t.get("deform")) anim.deform = anim_.readDeform(*d, clip(), w);

    // World = translate + R S local, so subtracting the origin from the translation rebases the object.
    // The float transform places analytic objects; mesh vertices go through the same transform in
    // double (toWorldD below), since a mesh file's own coordinates may be far from the origin.
    const glm::dvec3 translateD =
        t.get("translate") ? pointOf(*t.get("translate"), w + ".translate") - scene_.origin : -scene_.origin;
    const glm::vec3 translate(translateD);
    const glm::vec3 scale = t.get("scale") ? scalarOrVec<3>(*t.get("scale"), w + ".scale", kPositive) : glm::vec3(1.0f);
    o.transform = composeTransform(translate, glm::vec3(0.0f), scale);
    glm::dmat4 toWorldD = composeTransformD(translateD, glm::dvec3(0.0), glm::dvec3(scale));
    if (const toml::node* r = t.get("rotate")) {
      if (const toml::table* aa = r->as_table()) {
        checkKeys(*aa, {"axis", "angle"}, w + ".rotate");
        const glm::vec3 axis = requireVec3(*aa, "axis", w + ".rotate");
        if (!(glm::length(axis) > 0.0f)) fail(*aa->get("axis"), w + ".rotate.axis must not be zero");
        const toml::node* angle = aa->get("angle");
        if (!angle) fail(*aa, w + ".rotate: missing required key 'angle' (degrees)");
        const float degrees = float(number(*angle, w + ".rotate.angle"));
        o.transform = composeTransform(translate, axis, degrees, scale);
        toWorldD = composeTransformD(translateD, glm::dvec3(axis), double(degrees), glm::dvec3(scale));
      } else if (r->is_array()) {
        const glm::vec3 degrees = vecOf<3>(*r, w + ".rotate");
        o.transform = composeTransform(translate, degrees, scale);
        toWorldD = composeTransformD(translateD, glm::dvec3(degrees), glm::dvec3(scale));
      } else {
        fail(*r, w + ".rotate must be [x, y, z] degrees or { axis = [x, y, z], angle = degrees }");
      }
    }

    if (o.kind == ObjectKind::Torus) {
      o.majorRadius = getFloat(t, "major_radius", w, o.majorRadius, kPositive);
      o.minorRadius = getFloat(t, "minor_radius", w, o.minorRadius, kPositive);
      if (o.minorRadius > o.majorRadius) {
        const toml::node* n = t.get("minor_radius") ? t.get("minor_radius") : t.get("major_radius");
        fail(n ? *n : static_cast<const toml::node&>(t),
             w + ": minor_radius must be <= major_radius (a spindle torus intersects itself)");
      }
    }
    if (o.kind == ObjectKind::Plane) o.infinite = getBool(t, "infinite", w, false);
    if (o.kind == ObjectKind::Mesh) {
      const MeshData& data = t.get("generate") ? generatedMeshFor(t, w) : meshFor(requireMeshNode(t, w), requireString(t, "mesh", w));
      const glm::dmat4 placement = toWorldD;
      float fitSize = 0.0f;
      if (const toml::node* fit = t.get("fit")) {
        fitSize = float(number(*fit, w + ".fit", kPositive));
        toWorldD = toWorldD * fitTransform(data, fitSize);
      }
      if (anim.animated()) {
        anim.placement = placement;
        o.mesh = int(scene_.meshes.size());
        scene_.meshes.push_back(animatedMesh(t, data, fitSize, anim));  // positions written by setFrame
        scene_.meshes.back().material = o.material;
        scene_.objects.push_back(o);
        animation_->objects.push_back(std::move(anim));
        return;
      }
      Mesh mesh;
      try {
        mesh = bakeMesh(data, toWorldD);
      } catch (const InputError& e) {
        fail(t.get("mesh") ? *t.get("mesh") : *t.get("generate"), std::string("mesh: ") + e.what());
      }
      mesh.material = o.material;
      o.transform = glm::mat4(toWorldD);  // informational for meshes (the renderer reads the baked vertices)
      o.mesh = int(scene_.meshes.size());
      scene_.meshes.push_back(std::move(mesh));
    }
    scene_.objects.push_back(o);
    if (animation_) animation_->objects.push_back(std::move(anim));
  }

  // An animated mesh object's rest mesh in object space (after `fit`; shared with every object of the
  // same data, fit and piece split), its deformation's defaults from that mesh, and a copy of the rest
  // mesh as the object's scene mesh (setFrame writes its world positions).
  Mesh animatedMesh(const toml::table& t, const MeshData& data, float fitSize, ObjectAnimation& anim) {
    const bool unweld = anim.deform.kind == DeformKind::Explode && !anim.deform.componentPieces;
    const auto key = std::make_tuple(&data, double(fitSize), unweld);
    auto it = localMeshIndex_.find(key);
    if (it == localMeshIndex_.end()) {
      Mesh rest;
      try {
        rest = bakeMesh(data, fitSize > 0.0f ? fitTransform(data, fitSize) : glm::dmat4(1.0));
      } catch (const InputError& e) {
        fail(t.get("mesh") ? *t.get("mesh") : *t.get("generate"), std::string("mesh: ") + e.what());
      }
      if (unweld) rest = unweldTriangles(rest);
      it = localMeshIndex_.emplace(key, int(animation_->localMeshes.size())).first;
      animation_->localMeshes.push_back(std::move(rest));
    }
    anim.localMesh = it->second;
    const Mesh& rest = animation_->localMeshes[size_t(it->second)];
    Deform& d = anim.deform;
    if (anim.deforms()) {
      glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
      for (const glm::vec3& p : rest.positions) {
        lo = glm::min(lo, glm::dvec3(p));
        hi = glm::max(hi, glm::dvec3(p));
      }
      if (!d.centreGiven && !rest.positions.empty()) d.centre = 0.5 * lo + 0.5 * hi;
      double half = 0.0;
      for (const glm::vec3& p : rest.positions) half = std::max(half, std::abs(glm::dot(glm::dvec3(p) - d.centre, d.axis)));
      // A mesh flat across the twist axis has no height to twist over: every angle is then 0 anyway.
      anim.halfHeight = half > 0.0 ? half : 1.0;
      if (d.kind == DeformKind::Explode) prepareExplode(anim, rest);
    }
    return rest;
  }

  // Every animated mesh stays within float's range at frame 0, its key frames and the last frame: between
  // keys a rigid pose is a convex blend of the keys' (positions and scales; rotations keep lengths),
  // wave, twist and breathe are bounded by their amplitude, and explode's pieces are farthest out at
  // the end.
  void checkAnimatedMeshes(const std::vector<const toml::table*>& tables) const {
    for (size_t i = 0; i < scene_.objects.size(); ++i) {
      const ObjectAnimation& a = animation_->objects[i];
      if (scene_.objects[i].kind != ObjectKind::Mesh || a.localMesh < 0) continue;
      std::vector<int> frames = {0, animation_->clip.frames - 1};
      for (const RigidKey& k : a.keys) frames.push_back(k.frame);
      for (int f : frames) {
        try {
          worldMeshAt(scene_, int(i), f);
        } catch (const InputError& e) {
          const toml::node* n = tables[i]->get(a.deforms() ? "deform" : "keys");
          failAt(n ? n->source().begin.line : tables[i]->source().begin.line, e.what());
        }
      }
    }
  }

  // Moves the mesh's bounding box so its bottom centre is at the origin and scales it uniformly so
  // its largest extent is `size`.
  // In double: the anchor may be far from the origin (a georeferenced mesh fitted into a scene).
  static glm::dmat4 fitTransform(const MeshData& mesh, float size) {
    glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
    for (const glm::dvec3& p : mesh.positions) {
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    }
    const glm::dvec3 ext = hi - lo;
    const double largest = std::max({ext.x, ext.y, ext.z});
    const double s = largest > 0.0 ? double(size) / largest : 1.0;
    const glm::dvec3 anchor(0.5 * lo.x + 0.5 * hi.x, lo.y, 0.5 * lo.z + 0.5 * hi.z);
    return glm::scale(glm::dmat4(1.0), glm::dvec3(s)) * glm::translate(glm::dmat4(1.0), -anchor);
  }
};

}  // namespace

Scene loadScene(const fs::path& path) { return SceneReader(path).read(); }

}  // namespace bvhlab
