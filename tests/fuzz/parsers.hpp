// The file parsers a user feeds files to, by name, for the libFuzzer targets (tests/fuzz/fuzz_*.cpp)
// and for the regression replay (tests/test_fuzz_regressions.cpp), so both exercise exactly the same
// entry points. parseAs() returns normally when the input parsed and its result is well formed, throws
// bvhlab::InputError when the parser rejected it (both are correct behaviour), and aborts with a
// message when a parsed result breaks an invariant the rest of bvhlab relies on. Any other exception
// leaves parseAs(): the caller decides (the fuzz targets accept std::runtime_error, see fuzz_common.hpp).
#pragma once
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "datasets/image_io.hpp"
#include "datasets/mesh_io.hpp"
#include "datasets/scene.hpp"
#include "datasets/scene_io.hpp"
#include "experiments/config.hpp"
#include "experiments/runner.hpp"
#include "datasets/toml_guard.hpp"
#include "render/fly_camera.hpp"
#include "render/group_spec.hpp"

namespace bvhlab::fuzz {

// Parser names: the fuzz target fuzz_NAME, the regression folder tests/fuzz/regressions/NAME/.
inline const std::vector<std::string>& parserNames() {
  static const std::vector<std::string> names = {"obj",  "off", "ply", "stl", "gltf", "glb", "dae", "ac", "3ds", "fbx",
                                                 "scene", "config", "camera_path", "viewer_script",
                                                 "png",  "jpeg", "exr", "hdr", "group", "merge"};
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

// The image formats a scene's textures and worlds come in, read by loadImage (OpenImageIO) from
// dir/input.EXT, EXT the parser's name: OIIO picks its reader by extension, as for a user's file.
inline bool isImageFormat(const std::string& parser) {
  for (const char* ext : {"png", "jpeg", "exr", "hdr"})
    if (parser == ext) return true;
  return false;
}

// `merge` reads a sweep directory: plan.json and runs/*.json (experiments/sweep_dir.hpp). The fuzz input
// is the directory as one text: plan.json first, then each further file after a line "--- NAME" (NAME
// runs/KEY.json, runs/KEY.rR.json for a replicate, or a top-level file such as hard_cases.json; letters,
// digits, '.', '_', '-' only). A "--- " line naming anything else is content. Writes them under `in`.
inline void writeSweepDir(std::string_view data, const std::filesystem::path& in) {
  std::filesystem::create_directories(in / "runs");
  auto validName = [](std::string_view name) {
    if (name.substr(0, 5) == "runs/") name.remove_prefix(5);
    if (name.empty() || name.size() > 64 || name.front() == '.') return false;
    for (char c : name)
      if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.' && c != '_' && c != '-') return false;
    return true;
  };
  std::string name = "plan.json", text;
  auto flush = [&] { writeFile(in / name, text); };
  size_t pos = 0;
  while (pos < data.size()) {
    size_t end = data.find('\n', pos);
    end = end == std::string_view::npos ? data.size() : end + 1;
    std::string_view line = data.substr(pos, end - pos);
    pos = end;
    std::string_view header = line;
    while (!header.empty() && (header.back() == '\n' || header.back() == '\r')) header.remove_suffix(1);
    if (header.substr(0, 4) == "--- " && validName(header.substr(4))) {
      flush();
      name = std::string(header.substr(4));
      text.clear();
    } else {
      text += line;
    }
  }
  flush();
}

inline void parseAs(const std::string& parser, std::string_view data, const std::filesystem::path& dir) {
  if (isImageFormat(parser)) {
    const std::filesystem::path file = dir / ("input." + parser);
    writeFile(file, data);
    const Image image = loadImage(file);
    if (image.width <= 0 || image.height <= 0 || image.texels.size() != size_t(image.width) * size_t(image.height))
      invariantBroken(parser, "image size does not match its texels");
    for (const glm::vec4& t : image.texels)
      if (!finite(glm::vec3(t)) || !std::isfinite(t.a)) invariantBroken(parser, "non-finite texel");
  } else if (parser == "group") {
    // What `bvhlab measure GROUP.json` reads before it loads or draws anything.
    const std::filesystem::path file = dir / "group.json";
    writeFile(file, data);
    const GroupSpec g = readGroupSpec(file.string());
    if (g.runs.empty()) invariantBroken(parser, "a group without runs");
    if (g.settings.minFrames < 1 || g.settings.maxFrames < g.settings.minFrames) invariantBroken(parser, "frame bounds");
    if (g.settings.programCopies < 1) invariantBroken(parser, "program_copies < 1");
    for (const GroupRunSpec& r : g.runs)
      if (r.key.empty()) invariantBroken(parser, "a run without a key");
  } else if (parser == "merge") {
    // `bvhlab merge IN --out OUT` on one input directory written from the fuzz input.
    const std::filesystem::path in = dir / "in", out = dir / "out";
    std::filesystem::remove_all(in);
    std::filesystem::remove_all(out);
    writeSweepDir(data, in);
    const nlohmann::json s = mergeSweeps({in}, out, false);
    const auto count = [&](const char* k) { return s.at(k).get<size_t>(); };
    if (count("ok") + count("failed") + count("pending") != count("planned"))
      invariantBroken(parser, "ok + failed + pending != planned");
  } else if (isMeshFormat(parser)) {
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
