// The viewer: its window-free parts in process, and `bvhlab view` end to end as a subprocess under
// an X server (xvfb-run when DISPLAY is unset; skipped with a message when neither is there).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <set>
#include <sstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <sys/wait.h>
#include <unistd.h>

#include "builders/builder.hpp"
#include "datasets/image_io.hpp"
#include "render/fly_camera.hpp"
#include "render/viewer.hpp"
#include "traversal/kernels.hpp"

namespace fs = std::filesystem;
using namespace bvhlab;

namespace {

fs::path tempDir() {
  fs::path d = fs::temp_directory_path() / ("bvhlab_test_viewer_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

void writeFile(const fs::path& p, const std::string& text) {
  std::ofstream(p) << text;
}

void expectCameraEq(const Camera& a, const Camera& b) {
  EXPECT_EQ(a.eye, b.eye);
  EXPECT_EQ(a.target, b.target);
  EXPECT_EQ(a.up, b.up);
  EXPECT_EQ(a.fovDeg, b.fovDeg);
}

struct Result {
  int rc = -1;
  std::string out, err;
};

Result shell(const std::string& command) {
  const fs::path errFile = tempDir() / "stderr.txt";
  Result r;
  FILE* pipe = ::popen((command + " 2>" + errFile.string()).c_str(), "r");
  if (!pipe) return r;
  char buf[4096];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, pipe)) > 0) r.out.append(buf, n);
  int status = ::pclose(pipe);
  r.rc = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  std::ifstream in(errFile);
  std::stringstream s;
  s << in.rdbuf();
  r.err = s.str();
  return r;
}

// A unit cube as OBJ: 12 triangles, framed by loadMeshScene's default camera.
fs::path cubeMesh() {
  fs::path p = tempDir() / "cube.obj";
  writeFile(p,
            "v -0.5 -0.5 -0.5\nv 0.5 -0.5 -0.5\nv 0.5 0.5 -0.5\nv -0.5 0.5 -0.5\n"
            "v -0.5 -0.5 0.5\nv 0.5 -0.5 0.5\nv 0.5 0.5 0.5\nv -0.5 0.5 0.5\n"
            "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\n"
            "f 4 7 3\nf 4 8 7\nf 1 5 8\nf 1 8 4\nf 2 3 7\nf 2 7 6\n");
  return p;
}

// "xvfb-run -a " when there is no display, "" with one; nullopt (skip) when neither works.
std::optional<std::string> displayPrefix() {
  const char* d = std::getenv("DISPLAY");
  if (d && *d) return std::string();
  if (shell("command -v xvfb-run >/dev/null").rc == 0) return std::string("xvfb-run -a ");
  return std::nullopt;
}

#define REQUIRE_VIEWER(prefix)                                                                             \
  if (!viewerAvailable()) GTEST_SKIP() << "built without GLFW/Dear ImGui (BVHLAB_VIEWER unset in CMake)";    \
  if (shell(std::string(BVHLAB_BINARY) + " view --help >/dev/null").rc != 0)                                \
    GTEST_SKIP() << "this bvhlab has no `view` subcommand";                                                \
  std::optional<std::string> prefix = displayPrefix();                                                     \
  if (!prefix) GTEST_SKIP() << "no DISPLAY and no xvfb-run (apt-get install xvfb)"

std::string view(const std::string& prefix, const std::string& args) {
  return prefix + BVHLAB_BINARY + " view " + cubeMesh().string() + " --width 96 --height 64 " + args;
}

}  // namespace

// ---- window-free parts -------------------------------------------------------------

TEST(FlyCamera, KeepsAGivenPoseVerbatimAndMovesInItsFrame) {
  Camera c;
  c.eye = {1, 2, 3};
  c.target = {1, 2, 2};  // looking down -Z
  c.up = {0, 1, 0};
  c.fovDeg = 40;
  FlyCamera fly(c);
  expectCameraEq(fly.camera(), c);
  EXPECT_NEAR(fly.yawDeg(), 0.0f, 1e-5f);
  EXPECT_NEAR(fly.pitchDeg(), 0.0f, 1e-5f);

  fly.move({0, 0, 1}, 2.0f);  // forward 2
  EXPECT_NEAR(fly.camera().eye.z, 1.0f, 1e-5f);
  fly.move({1, 0, 0}, 1.0f);  // right of -Z with +Y up is +X
  EXPECT_NEAR(fly.camera().eye.x, 2.0f, 1e-5f);
  fly.turn(90.0f, 0.0f);      // turn right: now looking down +X
  glm::vec3 f = glm::normalize(fly.camera().target - fly.camera().eye);
  EXPECT_NEAR(f.x, 1.0f, 1e-5f);
  fly.turn(0.0f, 500.0f);     // pitch is clamped short of straight up
  EXPECT_FLOAT_EQ(fly.pitchDeg(), FlyCamera::kMaxPitchDeg);
}

TEST(FlyCamera, RejectsDegeneratePose) {
  Camera c;
  c.target = c.eye;
  EXPECT_THROW(FlyCamera{c}, std::invalid_argument);
}

TEST(CameraPath, RoundTripsExactly) {
  CameraPath path;
  for (int i = 0; i < 5; ++i) {
    Camera c;
    c.eye = {0.1f * i, 1.0f / 3.0f, std::sqrt(2.0f) * i};
    c.target = c.eye + glm::vec3(0.3f, -0.7f, -1.0f / 7.0f);
    c.fovDeg = 50.0f + i / 3.0f;
    path.push_back({i / 30.0, c});
  }
  fs::path file = tempDir() / "path.json";
  saveCameraPath(file, path);
  CameraPath back = loadCameraPath(file);
  ASSERT_EQ(back.size(), path.size());
  for (size_t i = 0; i < path.size(); ++i) {
    EXPECT_EQ(back[i].seconds, path[i].seconds);
    expectCameraEq(back[i].camera, path[i].camera);
  }
}

TEST(CameraPath, BadFileNamesFileAndPose) {
  fs::path file = tempDir() / "bad_path.json";
  writeFile(file, R"({"format": "bvhlab-camera-path", "version": 1, "poses": [{"t": 0, "eye": [0,0,0]}]})");
  try {
    loadCameraPath(file);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad_path.json: poses[0]: missing \"target\""), std::string::npos) << e.what();
  }
}

TEST(ViewerScript, ParsesEventsInFrameOrder) {
  ViewerScript s = parseViewerScript(
      "# comment\n5 key SHIFT+B\n0 pose eye 0 0 1 target 0 0 0\n\n2 hold W 3  # held\n3 mouse 4 -2\n9 quit\n", "s.txt");
  ASSERT_EQ(s.events.size(), 5u);
  EXPECT_EQ(s.events[0].kind, ScriptEvent::Kind::Pose);
  EXPECT_EQ(s.events[0].pose.fovDeg, -1.0f);  // no fov: keep the current one
  EXPECT_EQ(s.events[1].kind, ScriptEvent::Kind::Hold);
  EXPECT_EQ(s.events[1].holdFrames, 3);
  EXPECT_EQ(s.events[2].delta, glm::vec2(4, -2));
  EXPECT_EQ(s.events[3].key, "SHIFT+B");
  EXPECT_EQ(s.lastFrame(), 9);
}

TEST(ViewerScript, ErrorsNameFileAndLine) {
  for (const char* bad : {"0 key B\nx key B\n", "0 key B\n1 jump\n", "0 key B\n1 pose eye 0 0 0 target 0 0 0\n",
                          "0 key B\n1 hold W\n", "0 key B\n1 mouse 3 nan\n"}) {
    try {
      parseViewerScript(bad, "s.txt");
      ADD_FAILURE() << "no error for: " << bad;
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).rfind("s.txt:2: ", 0), 0u) << e.what();
    }
  }
}

// ---- `bvhlab view` end to end -------------------------------------------------------

TEST(ViewCommand, NoDisplayIsAClearErrorNotACrash) {
  if (shell(std::string(BVHLAB_BINARY) + " view --help >/dev/null").rc != 0)
    GTEST_SKIP() << "this bvhlab has no `view` subcommand";
  Result r = shell("env -u DISPLAY -u WAYLAND_DISPLAY " + std::string(BVHLAB_BINARY) + " view " + cubeMesh().string());
  EXPECT_EQ(r.rc, 1) << r.err;  // an ordinary error exit, not a signal
  if (viewerAvailable()) {
    EXPECT_NE(r.err.find("bvhlab render"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("X server"), std::string::npos) << r.err;
  }
  Result bad = shell("env DISPLAY=:9876 " + std::string(BVHLAB_BINARY) + " view " + cubeMesh().string());
  EXPECT_EQ(bad.rc, 1) << bad.err;
}

TEST(ViewCommand, ScriptedScreenshotEqualsHeadlessRender) {
  REQUIRE_VIEWER(prefix);
  fs::path dir = tempDir();
  writeFile(dir / "pose.txt", "0 pose eye 1.3 0.9 1.7 target 0 0.1 0 up 0 1 0 fov 42\n");
  Result v = shell(view(*prefix, "--script " + (dir / "pose.txt").string() + " --frames 2 --screenshot " +
                                     (dir / "view.png").string()));
  ASSERT_EQ(v.rc, 0) << v.err;
  Result r = shell(std::string(BVHLAB_BINARY) + " render " + cubeMesh().string() +
                   " --width 96 --height 64 --eye 1.3,0.9,1.7 --target 0,0.1,0 --up 0,1,0 --fov 42 -o " +
                   (dir / "render.png").string());
  ASSERT_EQ(r.rc, 0) << r.err;
  ImageRgba8 a = loadImageRgba8(dir / "view.png"), b = loadImageRgba8(dir / "render.png");
  ASSERT_EQ(a.width, b.width);
  ASSERT_EQ(a.height, b.height);
  ASSERT_EQ(a.rgba.size(), b.rgba.size());
  // Same shader, same camera, both llvmpipe here: expected identical. The tolerance (3 steps of 255) is
  // the one the project uses across GL drivers, for a viewer on a GPU.
  size_t off = 0, pixels = a.rgba.size() / 4;
  double sum = 0.0;
  for (size_t i = 0; i < pixels; ++i) {
    int m = 0;
    for (int c = 0; c < 3; ++c) {
      int d = std::abs(int(a.rgba[4 * i + c]) - int(b.rgba[4 * i + c]));
      m = std::max(m, d);
      sum += d;
    }
    off += m > 3;
  }
  EXPECT_LE(double(off) / double(pixels), 0.001) << off << " pixels differ by more than 3";
  EXPECT_LT(sum / double(3 * pixels), 0.5);
  // ...and the image is not trivially equal: the cube covers part of the frame, the sky the rest.
  std::set<uint32_t> colors;
  for (size_t i = 0; i < pixels; ++i) colors.insert(a.rgba[4 * i] << 16 | a.rgba[4 * i + 1] << 8 | a.rgba[4 * i + 2]);
  EXPECT_GT(colors.size(), 10u);
}

TEST(ViewCommand, ScriptedKeysSwitchBuilderAndKernel) {
  REQUIRE_VIEWER(prefix);
  fs::path dir = tempDir();
  writeFile(dir / "keys.txt", "1 key B\n2 key K\n3 key L\n");
  Result v = shell(view(*prefix, "--builder sah-binned --kernel stack-ordered --leaf-size 4 --json --frames 5 "
                                 "--script " + (dir / "keys.txt").string()));
  ASSERT_EQ(v.rc, 0) << v.err;
  nlohmann::json j = nlohmann::json::parse(v.out);
  auto next = [](const auto& list, const std::string& cur) {
    for (size_t i = 0; i < list.size(); ++i)
      if (list[i].name == cur) return list[(i + 1) % list.size()].name;
    return std::string("?");
  };
  EXPECT_EQ(j["builder"], next(builders(), "sah-binned"));
  EXPECT_EQ(j["kernel"], next(kernels(), "stack-ordered"));
  EXPECT_EQ(j["leaf_size"], 8);
  EXPECT_EQ(j["frames"], 5);
  ASSERT_EQ(j["switches"].size(), 3u);
  EXPECT_EQ(j["switches"][0]["switch"], "builder");
  EXPECT_TRUE(j["switches"][0].contains("build_ms"));
  EXPECT_EQ(j["switches"][1]["switch"], "kernel");
  EXPECT_EQ(j["switches"][1]["frame"], 2);
}

TEST(ViewCommand, RecordedPathReplaysToSamePoses) {
  REQUIRE_VIEWER(prefix);
  fs::path dir = tempDir();
  writeFile(dir / "fly.txt", "0 pose eye 1.5 1 2 target 0 0 0 fov 50\n1 hold W 3\n3 mouse 25 -8\n5 hold D 2\n6 key F\n");
  Result rec = shell(view(*prefix, "--script " + (dir / "fly.txt").string() + " --frames 8 --record " +
                                       (dir / "a.json").string()));
  ASSERT_EQ(rec.rc, 0) << rec.err;
  Result rep = shell(view(*prefix, "--replay " + (dir / "a.json").string() + " --record " + (dir / "b.json").string()));
  ASSERT_EQ(rep.rc, 0) << rep.err;
  CameraPath a = loadCameraPath(dir / "a.json"), b = loadCameraPath(dir / "b.json");
  ASSERT_EQ(a.size(), 8u);
  ASSERT_EQ(b.size(), a.size());
  for (size_t i = 0; i < a.size(); ++i) expectCameraEq(b[i].camera, a[i].camera);
  // The flight moved, turned and zoomed: the path is not one pose repeated.
  EXPECT_NE(a.front().camera.eye, a.back().camera.eye);
  EXPECT_NE(a.front().camera.fovDeg, a.back().camera.fovDeg);
  EXPECT_NE(glm::normalize(a.front().camera.target - a.front().camera.eye),
            glm::normalize(a.back().camera.target - a.back().camera.eye));
}
