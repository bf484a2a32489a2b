// The viewer's pieces that need no window: a first-person camera, camera paths (a recorded
// fly-through, one pose per line of text) and scripted input (docs/viewer.md). Kept apart from
// viewer.cpp so tests and experiment configs can use them without GLFW.
#pragma once
#include <filesystem>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "datasets/scene.hpp"

namespace bvhlab {

// A fly camera: position, yaw/pitch about the world up axis, vertical FOV. setCamera keeps the given
// pose verbatim until the camera is moved, so a scripted or replayed pose renders exactly like
// `bvhlab render --eye --target --up --fov`.
class FlyCamera {
 public:
  FlyCamera() { setCamera(Camera{}); }
  explicit FlyCamera(const Camera& c) { setCamera(c); }

  void setCamera(const Camera& c);
  const Camera& camera() const { return camera_; }

  glm::vec3 forward() const;  // unit view direction from yaw/pitch
  glm::vec3 right() const;    // unit, horizontal
  float yawDeg() const { return yawDeg_; }
  float pitchDeg() const { return pitchDeg_; }

  // Moves by `local` (x right, y world up, z forward) times `distance`.
  void move(glm::vec3 local, float distance);
  // Mouse look: turns by the given angles (positive yaw turns right, positive pitch looks up).
  void turn(float yawDeg, float pitchDeg);
  void setFov(float fovDeg);

  // Pitch stays this far from straight up/down so cross(forward, up) never degenerates.
  static constexpr float kMaxPitchDeg = 89.0f;

 private:
  void updatePose();
  glm::vec3 up_{0, 1, 0}, north_{0, 0, -1}, east_{1, 0, 0};  // orthonormal frame around the world up
  float yawDeg_ = 0.0f, pitchDeg_ = 0.0f;
  Camera camera_;
};

// A recorded fly-through: one pose per rendered frame, with the time since recording started.
struct CameraPathPose {
  double seconds = 0.0;
  Camera camera;
};
using CameraPath = std::vector<CameraPathPose>;

// Text, one pose per line: "t T eye X Y Z target X Y Z up X Y Z fov F" (keys in any order, all
// required; '#' starts a comment, blank lines are skipped). Numbers are written in their shortest
// round-trip form, so a saved path loads back to bit-identical poses.
void saveCameraPath(const std::filesystem::path& path, const CameraPath& poses);
// Throws InputError "FILE:LINE: what is wrong" (also for a file without poses).
CameraPath loadCameraPath(const std::filesystem::path& path);
CameraPath parseCameraPath(const std::string& text, const std::string& file);

// One line of a viewer script: "FRAME ACTION ARGS...".
struct ScriptEvent {
  enum class Kind { Key, Hold, Mouse, Scroll, Pose, Set, Screenshot, WindowScreenshot, Quit };
  int frame = 0;
  Kind kind = Kind::Key;
  std::string key;      // Key/Hold: key name as in docs/viewer.md ("B", "SHIFT+B", "F1", "LBRACKET");
                        // Set: the setting (one of scriptSettings())
  std::string value;    // Set: the new value, e.g. "smaa-high" (checked by the viewer)
  int holdFrames = 0;   // Hold
  glm::vec2 delta{0};   // Mouse: pixels; Scroll: y in .y
  Camera pose;          // Pose
  std::string path;     // Screenshot (the render) / WindowScreenshot (the window as displayed)
  int line = 0;         // for messages
};
struct ViewerScript {
  std::string file;
  std::vector<ScriptEvent> events;  // sorted by frame (stable: same-frame events keep file order)
  int lastFrame() const;            // the frame after which the script has nothing more to do
};
// Settings a script's "FRAME set SETTING VALUE" line can change.
const std::vector<std::string>& scriptSettings();
// Throws InputError "FILE:LINE: message" for anything it cannot read.
ViewerScript loadViewerScript(const std::filesystem::path& path);
ViewerScript parseViewerScript(const std::string& text, const std::string& file);

}  // namespace bvhlab
