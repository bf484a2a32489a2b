// Scene-file animation keys (animation_reader.hpp): the clip, camera and object keys, deformations.
#include "datasets/animation_reader.hpp"

#include <glm/gtc/quaternion.hpp>

namespace bvhlab {

using namespace toml_fields;

namespace {
// Up to a million frames: at 60 fps over four hours, far beyond any clip a BVH study replays.
constexpr int kMaxFrames = 1000000;
}  // namespace

Clip AnimationReader::readClip(const toml::table& t) const {
  checkKeys(t, {"frames", "fps"}, "[clip]");
  Clip clip;
  if (!t.get("frames")) failAt(t.source().begin.line, "clip: missing required key 'frames'");
  clip.frames = getInt(t, "frames", "clip", 1, 1, kMaxFrames);
  clip.fps = getFloat(t, "fps", "clip", 30.0f, kPositive);
  return clip;
}

const toml::array& AnimationReader::keyArray(const toml::node& keys, const Clip* clip, const std::string& name) const {
  const toml::array* a = keys.as_array();
  if (!a || !a->is_array_of_tables() || a->empty())
    fail(keys, name + " must be an array of tables: write [[" + name.substr(name.rfind(' ') + 1) + "]]");
  if (!clip) fail(keys, name + ": keys need a [clip] section (frames, fps)");
  return *a;
}

int AnimationReader::keyFrame(const toml::table& key, const Clip& clip, const std::string& name, int previous) const {
  const toml::node* f = key.get("frame");
  if (!f) failAt(key.source().begin.line, name + ": missing required key 'frame'");
  const int frame = getInt(key, "frame", name, 0, 0, clip.frames - 1);
  if (frame <= previous)
    fail(*f, name + ".frame must be greater than the previous key's frame (" + std::to_string(previous) + ", got " +
                 std::to_string(frame) + "): keys are in strictly increasing frame order");
  return frame;
}

glm::dquat AnimationReader::rotationOf(const toml::node& n, const std::string& name) const {
  if (const toml::table* aa = n.as_table()) {
    checkKeys(*aa, {"axis", "angle"}, name);
    const glm::vec3 axis = requireVec3(*aa, "axis", name);
    if (!(glm::length(axis) > 0.0f)) fail(*aa->get("axis"), name + ".axis must not be zero");
    const toml::node* angle = aa->get("angle");
    if (!angle) fail(*aa, name + ": missing required key 'angle' (degrees)");
    return glm::angleAxis(glm::radians(number(*angle, name + ".angle")), glm::normalize(glm::dvec3(axis)));
  }
  const toml::array* a = n.as_array();
  if (a && a->size() == 4) {
    glm::dvec4 q;
    for (size_t i = 0; i < 4; ++i) q[int(i)] = number(*a->get(i), name + "[" + std::to_string(i) + "]");
    const double len = glm::length(q);
    // A zero quaternion has no rotation; one whose squared length overflows has none we can normalise.
    if (!(len > 0.0) || !std::isfinite(len)) fail(n, name + " must not be a zero quaternion (write [w, x, y, z])");
    q /= len;
    return glm::dquat(q.x, q.y, q.z, q.w);  // glm::dquat(w, x, y, z)
  }
  if (a && a->size() == 3) {
    const glm::dvec3 deg(vecOf<3>(n, name));
    // R = Rz Ry Rx, as the object's rotate = [x, y, z].
    return glm::angleAxis(glm::radians(deg.z), glm::dvec3(0, 0, 1)) * glm::angleAxis(glm::radians(deg.y), glm::dvec3(0, 1, 0)) *
           glm::angleAxis(glm::radians(deg.x), glm::dvec3(1, 0, 0));
  }
  fail(n, name + " must be a quaternion [w, x, y, z], Euler angles [x, y, z] (degrees) or { axis = [x, y, z], angle = degrees }");
}

std::vector<CameraKeyInput> AnimationReader::readCameraKeys(const toml::node& keys, const Clip* clip, float fovDeg) const {
  const std::string name = "camera.keys";
  const toml::array& a = keyArray(keys, clip, name);
  std::vector<CameraKeyInput> out;
  int previous = -1;
  for (const toml::node& e : a) {
    const toml::table& t = *e.as_table();
    const std::string w = name + "[" + std::to_string(out.size()) + "]";
    checkKeys(t, {"frame", "eye", "target", "fov"}, "[[camera.keys]]");
    CameraKeyInput in;
    in.line = t.source().begin.line;
    in.key.frame = previous = keyFrame(t, *clip, w, previous);
    // The first key needs eye and target; later keys keep the previous key's values for keys they omit.
    for (const char* required : {"eye", "target"})
      if (out.empty() && !t.get(required))
        failAt(in.line, w + ": missing required key '" + std::string(required) + "' (the first key sets it)");
    in.key.eye = t.get("eye") ? pointOf(*t.get("eye"), w + ".eye") : out.back().key.eye;
    in.key.target = t.get("target") ? pointOf(*t.get("target"), w + ".target") : out.back().key.target;
    in.key.fovDeg = getFloat(t, "fov", w, out.empty() ? fovDeg : out.back().key.fovDeg, Range{0.0, 180.0, true, true});
    out.push_back(in);
  }
  return out;
}

std::vector<RigidKey> AnimationReader::readObjectKeys(const toml::node& keys, const Clip* clip, const glm::dvec3& origin,
                                                      const std::string& where) const {
  const std::string name = where + ".keys";
  const toml::array& a = keyArray(keys, clip, name);
  std::vector<RigidKey> out;
  int previous = -1;
  for (const toml::node& e : a) {
    const toml::table& t = *e.as_table();
    const std::string w = name + "[" + std::to_string(out.size()) + "]";
    checkKeys(t, {"frame", "position", "rotation", "scale"}, "[[object.keys]]");
    // Omitted values keep the previous key's (the first key's default: origin, no rotation, scale 1).
    RigidKey k = out.empty() ? RigidKey{} : out.back();
    if (out.empty()) k.position = -origin;
    k.frame = previous = keyFrame(t, *clip, w, previous);
    if (const toml::node* p = t.get("position")) k.position = pointOf(*p, w + ".position") - origin;
    if (const toml::node* r = t.get("rotation")) k.rotation = rotationOf(*r, w + ".rotation");
    if (const toml::node* s = t.get("scale")) k.scale = glm::dvec3(scalarOrVec<3>(*s, w + ".scale", kPositive));
    out.push_back(k);
  }
  return out;
}

Deform AnimationReader::readDeform(const toml::node& node, const Clip* clip, const std::string& where) const {
  const std::string name = where + ".deform";
  const toml::table* t = node.as_table();
  if (!t) fail(node, name + " must be a table: write [object.deform]");
  if (!clip) fail(node, name + ": a deformation needs a [clip] section (frames, fps)");
  Deform d;
  const std::string kind = requireString(*t, "kind", name);
  if (kind == "wave") {
    d.kind = DeformKind::Wave;
    checkKeys(*t, {"kind", "amplitude", "wavelength", "frequency", "direction", "axis", "centre"}, name + " (kind = \"wave\")");
    d.amplitude = getFloat(*t, "amplitude", name, 0.05f, kNonNegative);
    d.wavelength = getFloat(*t, "wavelength", name, 1.0f, kPositive);
  } else if (kind == "twist") {
    d.kind = DeformKind::Twist;
    checkKeys(*t, {"kind", "angle", "frequency", "axis", "centre"}, name + " (kind = \"twist\")");
    d.angleDeg = getFloat(*t, "angle", name, 45.0f);
  } else if (kind == "breathe") {
    d.kind = DeformKind::Breathe;
    checkKeys(*t, {"kind", "amplitude", "frequency", "centre"}, name + " (kind = \"breathe\")");
    // Below 1 the scale 1 + amplitude sin(...) stays positive: the mesh never turns inside out.
    d.amplitude = getFloat(*t, "amplitude", name, 0.1f, Range{0.0, 1.0, false, true});
  } else if (kind == "explode") {
    d.kind = DeformKind::Explode;
    checkKeys(*t, {"kind", "speed", "jitter", "speed_jitter", "start", "seed", "pieces", "centre"},
              name + " (kind = \"explode\")");
    d.speed = getFloat(*t, "speed", name, 1.0f, kPositive);
    // Below 1 every piece keeps moving away from the centre (animation.hpp).
    d.jitter = getFloat(*t, "jitter", name, 0.3f, Range{0.0, 1.0, false, true});
    d.speedJitter = getFloat(*t, "speed_jitter", name, 0.5f, Range{0.0, 1.0, false, true});
    d.start = getFloat(*t, "start", name, 0.0f, kNonNegative);
    if (const toml::node* s = t->get("seed")) {
      if (!s->is_integer() || s->value<int64_t>().value_or(-1) < 0) fail(*s, name + ".seed must be a non-negative integer");
      d.seed = uint64_t(s->value<int64_t>().value_or(1));
    }
    const std::string pieces = getString(*t, "pieces", name).value_or("triangles");
    if (pieces != "triangles" && pieces != "components")
      fail(*t->get("pieces"), name + ".pieces must be \"triangles\" or \"components\" (got \"" + pieces + "\")");
    d.componentPieces = pieces == "components";
  } else {
    fail(*t->get("kind"), name + ".kind: unknown deformation \"" + kind + "\" (wave, twist, breathe, explode)");
  }
  if (d.kind != DeformKind::Explode)
    d.frequency = getFloat(*t, "frequency", name, 1.0f, kNonNegative);
  for (auto [key, target] : {std::pair{"axis", &d.axis}, std::pair{"direction", &d.direction}})
    if (const toml::node* n = t->get(key)) {
      const glm::dvec3 v(vecOf<3>(*n, name + "." + key));
      if (!(glm::length(v) > 0.0)) fail(*n, name + "." + key + " must not be zero");
      *target = glm::normalize(v);
    }
  if (const toml::node* n = t->get("centre")) {
    d.centre = glm::dvec3(vecOf<3>(*n, name + ".centre"));
    d.centreGiven = true;
  }
  return d;
}

}  // namespace bvhlab
