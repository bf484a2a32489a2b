#include "render/fly_camera.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

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

nlohmann::json vec3Json(glm::vec3 v) { return nlohmann::json::array({v.x, v.y, v.z}); }

glm::vec3 vec3From(const nlohmann::json& j, const std::string& where) {
  if (!j.is_array() || j.size() != 3) throw InputError(where + ": expected an array of 3 numbers");
  glm::vec3 v;
  for (int i = 0; i < 3; ++i) {
    if (!j[i].is_number()) throw InputError(where + ": expected an array of 3 numbers");
    v[i] = j[i].get<float>();
    if (!std::isfinite(v[i])) throw InputError(where + ": not finite");
  }
  return v;
}

}  // namespace

void saveCameraPath(const std::filesystem::path& path, const CameraPath& poses) {
  nlohmann::json list = nlohmann::json::array();
  for (const CameraPathPose& p : poses)
    list.push_back({{"t", p.seconds},
                    {"eye", vec3Json(p.camera.eye)},
                    {"target", vec3Json(p.camera.target)},
                    {"up", vec3Json(p.camera.up)},
                    {"fov", p.camera.fovDeg}});
  nlohmann::json doc = {{"format", "bvhlab-camera-path"}, {"version", 1}, {"poses", list}};
  if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
  std::ofstream out(path);
  // max_digits10 floats: a path replays to bit-identical poses.
  out << doc.dump(1) << '\n';
  if (!out) throw InputError(path.string() + ": cannot write the camera path");
}

CameraPath loadCameraPath(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path.string() + ": cannot open the camera path");
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    throw InputError(path.string() + ": not JSON (" + e.what() + ")");
  }
  const std::string file = path.string();
  if (!doc.is_object() || doc.value("format", "") != "bvhlab-camera-path")
    throw InputError(file + ": not a camera path (\"format\" must be \"bvhlab-camera-path\")");
  if (doc.value("version", 0) != 1) throw InputError(file + ": unsupported camera path \"version\" (want 1)");
  if (!doc.contains("poses") || !doc["poses"].is_array()) throw InputError(file + ": \"poses\" must be an array");
  CameraPath poses;
  for (size_t i = 0; i < doc["poses"].size(); ++i) {
    const nlohmann::json& p = doc["poses"][i];
    const std::string where = file + ": poses[" + std::to_string(i) + "]";
    if (!p.is_object()) throw InputError(where + ": expected an object");
    for (const char* key : {"t", "eye", "target", "up", "fov"})
      if (!p.contains(key)) throw InputError(where + ": missing \"" + key + "\"");
    CameraPathPose pose;
    if (!p["t"].is_number() || !p["fov"].is_number()) throw InputError(where + ": \"t\" and \"fov\" must be numbers");
    pose.seconds = p["t"].get<double>();
    pose.camera.eye = vec3From(p["eye"], where + ".eye");
    pose.camera.target = vec3From(p["target"], where + ".target");
    pose.camera.up = vec3From(p["up"], where + ".up");
    pose.camera.fovDeg = p["fov"].get<float>();
    if (!(pose.camera.fovDeg > 0.0f && pose.camera.fovDeg < 180.0f))
      throw InputError(where + ".fov: must be in (0, 180) degrees");
    if (pose.camera.eye == pose.camera.target) throw InputError(where + ": eye equals target");
    if (pose.camera.up == glm::vec3(0.0f)) throw InputError(where + ".up: zero vector");
    poses.push_back(pose);
  }
  return poses;
}

// ---- scripts ------------------------------------------------------------------

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
    } else if (action == "mouse") {
      e.kind = ScriptEvent::Kind::Mouse;
      number(e.delta.x, "mouse dx");
      number(e.delta.y, "mouse dy");
    } else if (action == "scroll") {
      e.kind = ScriptEvent::Kind::Scroll;
      number(e.delta.y, "scroll");
    } else if (action == "pose") {
      e.kind = ScriptEvent::Kind::Pose;
      bool seen[4] = {false, false, false, false};
      std::string key;
      while (in >> key) {
        glm::vec3* v = key == "eye" ? &e.pose.eye : key == "target" ? &e.pose.target : key == "up" ? &e.pose.up : nullptr;
        if (v) {
          for (int i = 0; i < 3; ++i) number((*v)[i], key.c_str());
          seen[key == "eye" ? 0 : key == "target" ? 1 : 2] = true;
        } else if (key == "fov") {
          number(e.pose.fovDeg, "fov");
          seen[3] = true;
        } else {
          throw InputError(where + "unknown pose key '" + key + "' (eye, target, up, fov)");
        }
      }
      if (!seen[0] || !seen[1]) throw InputError(where + "pose needs at least 'eye X Y Z target X Y Z'");
      if (e.pose.eye == e.pose.target) throw InputError(where + "pose eye equals target");
      if (e.pose.up == glm::vec3(0.0f)) throw InputError(where + "pose up is zero");
      if (!(e.pose.fovDeg > 0.0f && e.pose.fovDeg < 180.0f)) throw InputError(where + "fov must be in (0, 180)");
      if (!seen[3]) e.pose.fovDeg = -1.0f;  // keep the current FOV
    } else if (action == "screenshot") {
      e.kind = ScriptEvent::Kind::Screenshot;
      if (!(in >> e.path)) throw InputError(where + "screenshot needs a file name");
    } else if (action == "quit") {
      e.kind = ScriptEvent::Kind::Quit;
    } else {
      throw InputError(where + "unknown action '" + action + "' (key, hold, mouse, scroll, pose, screenshot, quit)");
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
  if (!in) throw InputError(path.string() + ": cannot open the viewer script");
  std::stringstream text;
  text << in.rdbuf();
  return parseViewerScript(text.str(), path.string());
}

}  // namespace bvhlab
