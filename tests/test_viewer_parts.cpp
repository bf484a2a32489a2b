// The viewer's window-free parts, in process: the fly camera, camera paths (round trip, errors with
// file and line) and viewer scripts. `bvhlab view` end to end is test_viewer.cpp.
#include <cmath>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "render/fly_camera.hpp"
#include "render/viewer.hpp"
#include "viewer_test_util.hpp"

namespace fs = std::filesystem;
using namespace bvhlab;
using bvhlab::testing::expectCameraEq;
using bvhlab::testing::tempDir;

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
  fs::path file = tempDir() / "path.txt";
  saveCameraPath(file, path);
  CameraPath back = loadCameraPath(file);
  ASSERT_EQ(back.size(), path.size());
  std::ifstream in(file);
  size_t lines = 0;
  for (std::string line; std::getline(in, line);) ++lines;
  EXPECT_EQ(lines, path.size()) << "one pose per line";
  for (size_t i = 0; i < path.size(); ++i) {
    EXPECT_EQ(back[i].seconds, path[i].seconds);
    expectCameraEq(back[i].camera, path[i].camera);
  }
}

TEST(CameraPath, BadFileNamesFileAndLine) {
  const std::string good = "t 0 eye 0 0 1 target 0 0 0 up 0 1 0 fov 50\n";
  for (const char* bad : {"t 0 eye 0 0 1 up 0 1 0 fov 50\n",             // missing target
                          "t 0 eye 0 0 1 target 0 0 1 up 0 1 0 fov 50\n",  // eye == target
                          "t 0 eye 0 0 1 target 0 0 0 up 0 0 0 fov 50\n",  // zero up
                          "t 0 eye 0 0 1 target 0 0 0 up 0 1 0 fov 180\n", "t 0 eye 0 x 1 target 0 0 0 up 0 1 0 fov 5\n",
                          "t 0 eye 0 0 1 target 0 0 0 up 0 1 0 fov 50 zoom 2\n", "t 0 t 1 eye 0 0 1 target 0 0 0\n"}) {
    try {
      parseCameraPath("# comment line\n" + good + bad, "p.txt");
      ADD_FAILURE() << "no error for: " << bad;
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).rfind("p.txt:3: ", 0), 0u) << e.what();
    }
  }
  EXPECT_THROW(parseCameraPath("# no poses\n\n", "p.txt"), InputError);
  EXPECT_THROW(loadCameraPath(tempDir() / "missing.txt"), InputError);
  EXPECT_EQ(parseCameraPath(good + "\n# end\n" + good, "p.txt").size(), 2u);
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

TEST(ViewerScript, SetAndWindowScreenshot) {
  ViewerScript s = parseViewerScript("0 set aa smaa-high\n1 set robust watertight\n2 window-screenshot w.png\n", "s.txt");
  ASSERT_EQ(s.events.size(), 3u);
  EXPECT_EQ(s.events[0].kind, ScriptEvent::Kind::Set);
  EXPECT_EQ(s.events[0].key, "aa");
  EXPECT_EQ(s.events[0].value, "smaa-high");
  EXPECT_EQ(s.events[1].value, "watertight");
  EXPECT_EQ(s.events[2].kind, ScriptEvent::Kind::WindowScreenshot);
  EXPECT_EQ(s.events[2].path, "w.png");
}

TEST(ViewerScript, ErrorsNameFileAndLine) {
  for (const char* bad : {"0 key B\nx key B\n", "0 key B\n1 jump\n", "0 key B\n1 pose eye 0 0 0 target 0 0 0\n",
                          "0 key B\n1 hold W\n", "0 key B\n1 mouse 3 nan\n", "0 key B\n1 set colour red\n",
                          "0 key B\n1 set aa\n", "0 key B\n1 window-screenshot\n"}) {
    try {
      parseViewerScript(bad, "s.txt");
      ADD_FAILURE() << "no error for: " << bad;
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).rfind("s.txt:2: ", 0), 0u) << e.what();
    }
  }
}
