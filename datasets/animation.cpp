// Keyframe tracks (datasets/animation.hpp): rigid poses by lerp / slerp between integer-frame keys,
// clamped outside them, and the camera path.
#include "datasets/animation.hpp"

#include <algorithm>

#include <glm/gtc/matrix_transform.hpp>

namespace bvhlab {

const char* deformKindName(DeformKind kind) {
  switch (kind) {
    case DeformKind::None: return "none";
    case DeformKind::Wave: return "wave";
    case DeformKind::Twist: return "twist";
    case DeformKind::Breathe: return "breathe";
    case DeformKind::Explode: return "explode";
  }
  return "?";
}

glm::dmat4 RigidPose::matrix() const {
  const glm::dmat4 I(1.0);
  return glm::translate(I, position) * glm::mat4_cast(rotation) * glm::scale(I, scale);
}

namespace {

// The segment [keys[i], keys[i + 1]] holding `frame` and the fraction along it; i = -1 before the first
// key, i = last at or after the last key (the caller then takes that key as it is).
template <class Key>
std::pair<size_t, double> locate(const std::vector<Key>& keys, double frame) {
  // The first key whose frame is greater than `frame` (none for a NaN frame: then the last key holds).
  const auto next = std::upper_bound(keys.begin(), keys.end(), frame,
                                     [](double f, const Key& k) { return f < double(k.frame); });
  if (next == keys.begin()) return {0, 0.0};
  if (next == keys.end()) return {keys.size() - 1, 0.0};
  const size_t i = size_t(next - keys.begin()) - 1;
  const double span = double(keys[i + 1].frame - keys[i].frame);  // >= 1: frames strictly increase
  return {i, (frame - double(keys[i].frame)) / span};
}

}  // namespace

RigidPose samplePose(const std::vector<RigidKey>& keys, double frame) {
  RigidPose pose;
  if (keys.empty()) return pose;
  const auto [i, a] = locate(keys, frame);
  const RigidKey& k0 = keys[i];
  // At a key (a == 0, also every clamped frame) the key's own values, bit for bit.
  if (!(a > 0.0) || i + 1 >= keys.size()) {
    pose.position = k0.position;
    pose.rotation = k0.rotation;
    pose.scale = k0.scale;
    return pose;
  }
  const RigidKey& k1 = keys[i + 1];
  pose.position = glm::mix(k0.position, k1.position, a);
  pose.rotation = glm::normalize(glm::slerp(k0.rotation, k1.rotation, a));
  pose.scale = glm::mix(k0.scale, k1.scale, a);
  return pose;
}

Camera sampleCamera(const std::vector<CameraKey>& keys, double frame, const Camera& base) {
  Camera c = base;
  if (keys.empty()) return c;
  const auto [i, a] = locate(keys, frame);
  const CameraKey& k0 = keys[i];
  if (!(a > 0.0) || i + 1 >= keys.size()) {
    c.eye = glm::vec3(k0.eye);
    c.target = glm::vec3(k0.target);
    c.fovDeg = k0.fovDeg;
    return c;
  }
  const CameraKey& k1 = keys[i + 1];
  c.eye = glm::vec3(glm::mix(k0.eye, k1.eye, a));
  c.target = glm::vec3(glm::mix(k0.target, k1.target, a));
  c.fovDeg = float(double(k0.fovDeg) + (double(k1.fovDeg) - double(k0.fovDeg)) * a);
  return c;
}

}  // namespace bvhlab
