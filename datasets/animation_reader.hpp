// The animation keys of a scene file (docs/scene-format.md, "Animation"): [clip], [[camera.keys]],
// [[object.keys]] and [object.deform]. Used by the scene reader (scene_reader.cpp); every refusal is
// one InputError line "FILE:LINE: message" naming the key.
#pragma once
#include <string>
#include <vector>

#include "datasets/animation.hpp"
#include "datasets/toml_fields.hpp"

namespace bvhlab {

// A camera key as written: positions in world coordinates (the scene reader rebases them), and the
// source line of the key for messages about the path between keys.
struct CameraKeyInput {
  CameraKey key;
  size_t line = 0;
};

class AnimationReader : public toml_fields::TomlFields {
 public:
  using TomlFields::TomlFields;

  // [clip]: frames (required, integer >= 1), fps (> 0, default 30).
  Clip readClip(const toml::table& t) const;
  // [[camera.keys]]: frame, eye, target, fov; `clip` null when the scene has no [clip] (an error).
  std::vector<CameraKeyInput> readCameraKeys(const toml::node& keys, const Clip* clip, float fovDeg) const;
  // [[object.keys]] of object `where`: frame, position, rotation, scale; positions relative to `origin`.
  std::vector<RigidKey> readObjectKeys(const toml::node& keys, const Clip* clip, const glm::dvec3& origin,
                                       const std::string& where) const;
  // [object.deform] of object `where`.
  Deform readDeform(const toml::node& deform, const Clip* clip, const std::string& where) const;

 private:
  const toml::array& keyArray(const toml::node& keys, const Clip* clip, const std::string& name) const;
  int keyFrame(const toml::table& key, const Clip& clip, const std::string& name, int previous) const;
  glm::dquat rotationOf(const toml::node& n, const std::string& name) const;
};

}  // namespace bvhlab
