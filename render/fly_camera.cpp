#include "render/fly_camera.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

namespace bvhlab {

// ---- FlyCamera ---------------------------------------------------------------

void FlyCamera::setCamera(const Camera& c) {
  const glm::vec3 dir = c.target - c.eye;
  const float upLen = glm::length(c.up), dirLen = glm::length(dir);
  if (!(upLen > 0.0f) || !std::isfinite(upLen) || !(dirLen > 0.0f) || !std::isfinite(dirLen) ||
      !std::isfinite(c.fovDeg))
    throw std::invalid_argument("camera needs a finite eye != target, a non-zero up and a finite fov");
  up_ = c.up / upLen;
  // Any horizontal reference direction will do; -Z (or +X when up is near Z) keeps yaw 0 = "into the
  // screen" for the usual +Y-up scenes.
  glm::vec3 a = std::abs(up_.z) < 0.9f ? glm::vec3(0, 0, -1) : glm::vec3(1, 0, 0);
  north_ = glm::normalize(a - glm::dot(a, up_) * up_);
  east_ = glm::cross(north_, up_);
  const glm::vec3 f = dir / dirLen;
  pitchDeg_ = glm::degrees(std::asin(std::clamp(glm::dot(f, up_), -1.0f, 1.0f)));
  const glm::vec3 h = f - glm::dot(f, up_) * up_;
  yawDeg_ = glm::dot(h, h) > 0.0f ? glm::degrees(std::atan2(glm::dot(h, east_), glm::dot(h, north_))) : 0.0f;
  camera_ = c;  // verbatim: no round trip through yaw/pitch until the camera moves
}

glm::vec3 FlyCamera::forward() const {
  const float yaw = glm::radians(yawDeg_), pitch = glm::radians(pitchDeg_);
  return std::cos(pitch) * (std::cos(yaw) * north_ + std::sin(yaw) * east_) + std::sin(pitch) * up_;
}

glm::vec3 FlyCamera::right() const {
  const float yaw = glm::radians(yawDeg_);
  return std::cos(yaw) * east_ - std::sin(yaw) * north_;
}

void FlyCamera::updatePose() {
  camera_.target = camera_.eye + forward();
  camera_.up = up_;
}

void FlyCamera::move(glm::vec3 local, float distance) {
  if (local == glm::vec3(0.0f) || distance == 0.0f) return;
  camera_.eye += distance * (local.x * right() + local.y * up_ + local.z * forward());
  updatePose();
}

void FlyCamera::turn(float yawDeg, float pitchDeg) {
  if (yawDeg == 0.0f && pitchDeg == 0.0f) return;
  yawDeg_ = std::remainder(yawDeg_ + yawDeg, 360.0f);
  pitchDeg_ = std::clamp(pitchDeg_ + pitchDeg, -kMaxPitchDeg, kMaxPitchDeg);
  updatePose();
}

void FlyCamera::setFov(float fovDeg) { camera_.fovDeg = fovDeg; }

// ---- camera paths -------------------------------------------------------------

namespace {

// Shortest text that reads back to the same float/double (std::to_chars round-trip guarantee), so a
// saved path replays to bit-identical poses.
template <typename T>
std::string exact(T v) {
  char buf[32];
  auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, end);
}

std::string vec3Text(glm::vec3 v) { return exact(v.x) + " " + exact(v.y) + " " + exact(v.z); }

// Reads "eye X Y Z target X Y Z [up X Y Z] [fov F] [t T]" keys from `in` until the end of the line.
// `allowT`: the key "t" (camera paths) is accepted. Returns which keys were seen.
struct PoseKeys {
  bool eye = false, target = false, up = false, fov = false, t = false;
};
PoseKeys readPose(std::istream& in, const std::string& where, bool allowT, Camera& pose, double& seconds) {
  PoseKeys seen;
  auto number = [&](auto& v, const std::string& what) {
    if (!(in >> v) || !std::isfinite(v)) throw InputError(where + "expected a number for " + what);
  };
  std::string key;
  while (in >> key) {
    bool* flag = key == "eye" ? &seen.eye : key == "target" ? &seen.target : key == "up" ? &seen.up
               : key == "fov" ? &seen.fov : (key == "t" && allowT) ? &seen.t : nullptr;
    if (!flag)
      throw InputError(where + "unknown pose key '" + key + "' (eye, target, up, fov" + (allowT ? ", t)" : ")"));
    if (*flag) throw InputError(where + "'" + key + "' given twice");
    *flag = true;
    if (key == "fov") number(pose.fovDeg, "fov");
    else if (key == "t") number(seconds, "t");
    else {
      glm::vec3& v = key == "eye" ? pose.eye : key == "target" ? pose.target : pose.up;
      for (int i = 0; i < 3; ++i) number(v[i], key);
    }
  }
  if (seen.eye && seen.target && pose.eye == pose.target) throw InputError(where + "eye equals target");
  if (seen.up && pose.up == glm::vec3(0.0f)) throw InputError(where + "up is the zero vector");
  if (seen.fov && !(pose.fovDeg > 0.0f && pose.fovDeg < 180.0f))
    throw InputError(where + "fov must be in (0, 180) degrees");
  return seen;
}

}  // namespace

void saveCameraPath(const std::filesystem::path& path, const CameraPath& poses) {
  if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
  std::ofstream out(path);
  for (const CameraPathPose& p : poses)
    out << "t " << exact(p.seconds) << " eye " << vec3Text(p.camera.eye) << " target " << vec3Text(p.camera.target)
        << " up " << vec3Text(p.camera.up) << " fov " << exact(p.camera.fovDeg) << '\n';
  if (!out) throw FileError(path.string() + ": cannot write the camera path");
}

CameraPath parseCameraPath(const std::string& text, const std::string& file) {
  CameraPath poses;
  std::istringstream lines(text);
  std::string line;
  for (int lineNo = 1; std::getline(lines, line); ++lineNo) {
    if (size_t hash = line.find('#'); hash != std::string::npos) line.erase(hash);
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;  // blank or comment
    const std::string where = file + ":" + std::to_string(lineNo) + ": ";
    std::istringstream in(line);
    CameraPathPose pose;
    const PoseKeys seen = readPose(in, where, true, pose.camera, pose.seconds);
    for (auto [ok, key] : {std::pair{seen.t, "t"}, {seen.eye, "eye"}, {seen.target, "target"}, {seen.up, "up"},
                           {seen.fov, "fov"}})
      if (!ok) throw InputError(where + "missing '" + key + "' (a pose line is: t T eye X Y Z target X Y Z up X Y Z fov F)");
    poses.push_back(pose);
  }
  if (poses.empty()) throw InputError(file + ":1: the camera path has no poses");
  return poses;
}

CameraPath loadCameraPath(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw FileError(path.string() + ": cannot open the camera path");
  std::stringstream text;
  text << in.rdbuf();
  return parseCameraPath(text.str(), path.string());
}

// ---- scripts ------------------------------------------------------------------

const std::vector<std::string>& scriptSettings() {
  static const std::vector<std::string> names = {"builder", "kernel", "leaf_size", "depth",     "view",
                                                 "scale",   "aa",     "robust",    "update", "clip_frame"};
  return names;
}

int ViewerScript::lastFrame() const {
  int last = 0;
  for (const ScriptEvent& e : events) last = std::max(last, e.frame + (e.kind == ScriptEvent::Kind::Hold ? e.holdFrames : 0));
  return last;
}

ViewerScript parseViewerScript(const std::string& text, const std::string& file) {
  ViewerScript script;
  script.file = file;
  std::istringstream lines(text);
  std::string line;
  for (int lineNo = 1; std::getline(lines, line); ++lineNo) {
    if (size_t hash = line.find('#'); hash != std::string::npos) line.erase(hash);
    std::istringstream in(line);
    std::string action;
    ScriptEvent e;
    e.line = lineNo;
    const std::string where = file + ":" + std::to_string(lineNo) + ": ";
    if (!(in >> e.frame)) {
      if (line.find_first_not_of(" \t\r") == std::string::npos) continue;  // blank line
      throw InputError(where + "expected 'FRAME ACTION ...' with FRAME an integer");
    }
    if (e.frame < 0) throw InputError(where + "frame must be >= 0");
    if (!(in >> action)) throw InputError(where + "missing action after the frame number");
    auto number = [&](float& v, const char* what) {
      if (!(in >> v) || !std::isfinite(v)) throw InputError(where + "expected a number for " + what);
    };
    if (action == "key" || action == "hold") {
      e.kind = action == "key" ? ScriptEvent::Kind::Key : ScriptEvent::Kind::Hold;
      if (!(in >> e.key)) throw InputError(where + action + " needs a key name");
      if (e.kind == ScriptEvent::Kind::Hold && (!(in >> e.holdFrames) || e.holdFrames < 1))
        throw InputError(where + "hold needs a key name and a frame count >= 1");
      // FRAME + COUNT is the script's last frame (ViewerScript::lastFrame): it must fit an int.
      if (e.kind == ScriptEvent::Kind::Hold && e.holdFrames > std::numeric_limits<int>::max() - e.frame)
        throw InputError(where + "hold ends after frame " + std::to_string(std::numeric_limits<int>::max()));
    } else if (action == "mouse") {
      e.kind = ScriptEvent::Kind::Mouse;
      number(e.delta.x, "mouse dx");
      number(e.delta.y, "mouse dy");
    } else if (action == "scroll") {
      e.kind = ScriptEvent::Kind::Scroll;
      number(e.delta.y, "scroll");
    } else if (action == "pose") {
      e.kind = ScriptEvent::Kind::Pose;
      double unused = 0.0;
      const PoseKeys seen = readPose(in, where, false, e.pose, unused);
      if (!seen.eye || !seen.target) throw InputError(where + "pose needs at least 'eye X Y Z target X Y Z'");
      if (!seen.fov) e.pose.fovDeg = -1.0f;  // keep the current FOV
    } else if (action == "set") {
      e.kind = ScriptEvent::Kind::Set;
      if (!(in >> e.key >> e.value))
        throw InputError(where + "set needs a setting and a value, e.g. 'set aa smaa-high'");
      const std::vector<std::string>& settings = scriptSettings();
      if (std::find(settings.begin(), settings.end(), e.key) == settings.end()) {
        std::string valid;
        for (const std::string& s : settings) valid += (valid.empty() ? "" : ", ") + s;
        throw InputError(where + "unknown setting '" + e.key + "' (" + valid + ")");
      }
    } else if (action == "screenshot") {
      e.kind = ScriptEvent::Kind::Screenshot;
      if (!(in >> e.path)) throw InputError(where + "screenshot needs a file name");
    } else if (action == "window-screenshot") {
      e.kind = ScriptEvent::Kind::WindowScreenshot;
      if (!(in >> e.path)) throw InputError(where + "window-screenshot needs a file name");
    } else if (action == "quit") {
      e.kind = ScriptEvent::Kind::Quit;
    } else {
      throw InputError(where + "unknown action '" + action +
                       "' (key, hold, mouse, scroll, pose, set, screenshot, window-screenshot, quit)");
    }
    std::string extra;
    if (in >> extra) throw InputError(where + "unexpected '" + extra + "' at the end of the line");
    script.events.push_back(e);
  }
  std::stable_sort(script.events.begin(), script.events.end(),
                   [](const ScriptEvent& a, const ScriptEvent& b) { return a.frame < b.frame; });
  return script;
}

ViewerScript loadViewerScript(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw FileError(path.string() + ": cannot open the viewer script");
  std::stringstream text;
  text << in.rdbuf();
  return parseViewerScript(text.str(), path.string());
}

}  // namespace bvhlab
