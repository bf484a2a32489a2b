// The file parsers a user feeds files to, by name, for the libFuzzer targets (tests/fuzz/fuzz_*.cpp)
// and for the regression replay (tests/test_fuzz_regressions.cpp), so both exercise exactly the same
// entry points. parseAs() returns normally when the input parsed and its result is well formed, throws
// bvhlab::InputError when the parser rejected it (both are correct behaviour), and aborts with a
// message when a parsed result breaks an invariant the rest of bvhlab relies on. Any other exception
// leaves parseAs(): the caller decides (the fuzz targets accept std::runtime_error, see fuzz_common.hpp).
#pragma once
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

#include "datasets/mesh_io.hpp"
#include "datasets/scene.hpp"
#include "datasets/scene_io.hpp"
#include "experiments/config.hpp"
#include "datasets/toml_guard.hpp"
#include "render/fly_camera.hpp"

namespace bvhlab::fuzz {

// Parser names: the fuzz target fuzz_NAME, the regression folder tests/fuzz/regressions/NAME/.
inline const std::vector<std::string>& parserNames() {
  static const std::vector<std::string> names = {"obj",  "off", "ply", "stl", "gltf", "glb", "dae", "ac", "3ds", "fbx",
                                                 "scene", "config", "camera_path", "viewer_script"};
  return names;
}

[[noreturn]] inline void invariantBroken(const std::string& parser, const std::string& what) {
  std::fprintf(stderr, "fuzz_%s: parsed result breaks an invariant: %s\n", parser.c_str(), what.c_str());
  std::abort();
}

inline bool finite(glm::vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

inline void checkMesh(const std::string& parser, const Mesh& m, bool fromFile = true) {
  if (fromFile && m.triangles.empty()) invariantBroken(parser, "a mesh file without triangles loaded");
  for (const glm::uvec3& t : m.triangles)
    for (int k = 0; k < 3; ++k)
      if (t[k] >= m.positions.size()) invariantBroken(parser, "triangle index out of range");
  for (const glm::vec3& p : m.positions)
    if (!finite(p)) invariantBroken(parser, "non-finite vertex position");
  if (!m.normals.empty() && m.normals.size() != m.positions.size())
    invariantBroken(parser, "normals given for some vertices only");
  if (!m.uvs.empty() && m.uvs.size() != m.positions.size()) invariantBroken(parser, "uvs given for some vertices only");
}

inline void writeFile(const std::filesystem::path& path, std::string_view data) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(data.data(), std::streamsize(data.size()));
  if (!out) invariantBroken("harness", "cannot write " + path.string());
}

// Parses `data` as `parser`. Parsers that read a file get it at dir/input.EXT (rewritten each call, EXT
// the parser's name for the mesh formats, so loadMesh picks the reader by extension as for a user's file);
// `dir` must exist and should be empty apart from that (relative references in a scene or config
// then name nothing).
// The mesh formats: OpenMesh or our own readers (obj off ply stl), assimp (the rest, mesh_io_assimp.cpp).
inline bool isMeshFormat(const std::string& parser) {
  for (const char* ext : {"obj", "off", "ply", "stl", "gltf", "glb", "dae", "ac", "3ds", "fbx"})
    if (parser == ext) return true;
  return false;
}

inline void parseAs(const std::string& parser, std::string_view data, const std::filesystem::path& dir) {
  if (isMeshFormat(parser)) {
    const std::filesystem::path file = dir / ("input." + parser);
    writeFile(file, data);
    checkMesh(parser, loadMesh(file));
  } else if (parser == "scene") {
    const std::filesystem::path file = dir / "input.toml";
    writeFile(file, data);
    const Scene s = loadScene(file);
    for (const Mesh& m : s.meshes) checkMesh(parser, m, false);
  } else if (parser == "config") {
    // In memory, with the names registered in this build (what `bvhlab run` validates against).
    static const KnownNames names = registeredNames();
    const ExperimentConfig c = parseExperimentConfig(data, dir / "input.toml", names);
    for (size_t i = 0; i < c.runs.size(); ++i)
      if (c.runs[i].index != i) invariantBroken(parser, "runs[i].index != i");
  } else if (parser == "camera_path") {
    const CameraPath path = parseCameraPath(std::string(data), (dir / "input.txt").string());
    for (const CameraPathPose& p : path)
      if (!std::isfinite(p.seconds) || !finite(p.camera.eye) || !finite(p.camera.target) || !finite(p.camera.up) ||
          !std::isfinite(p.camera.fovDeg))
        invariantBroken(parser, "non-finite pose");
  } else if (parser == "viewer_script") {
    const ViewerScript script = parseViewerScript(std::string(data), (dir / "input.script").string());
    if (script.lastFrame() < 0) invariantBroken(parser, "negative last frame");
  } else {
    invariantBroken("harness", "unknown parser '" + parser + "'");
  }
}

}  // namespace bvhlab::fuzz
