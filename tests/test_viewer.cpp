// `bvhlab view` end to end, as a subprocess under an X server (xvfb-run when DISPLAY is unset;
// skipped with a message when neither is there, a failure under BVHLAB_REQUIRE_ALL=1). The viewer's window-free parts (fly camera, camera
// paths, scripts) are tested in process in test_viewer_parts.cpp.
#include <algorithm>
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
#include "layout/layouts.hpp"
#include "render/fly_camera.hpp"
#include "render/viewer.hpp"
#include "traversal/kernels.hpp"
#include "require.hpp"
#include "viewer_test_util.hpp"

namespace fs = std::filesystem;
using namespace bvhlab;
using bvhlab::testing::expectCameraEq;
using bvhlab::testing::tempDir;

namespace {

void writeFile(const fs::path& p, const std::string& text) {
  std::ofstream(p) << text;
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

std::string view(const std::string& prefix, const std::string& args) {
  return prefix + BVHLAB_BINARY + " view " + cubeMesh().string() + " --width 96 --height 64 " + args;
}

// The camera every end-to-end test uses: as a script line and as `render` flags.
const char* kPoseLine = "0 pose eye 1.3 0.9 1.7 target 0 0.1 0 up 0 1 0 fov 42\n";
const char* kPoseFlags = " --eye 1.3,0.9,1.7 --target 0,0.1,0 --up 0,1,0 --fov 42";

// `bvhlab render` of the cube from kPoseFlags; the image goes to `out`.
Result renderHeadless(const fs::path& out, const std::string& args, int width = 96, int height = 64) {
  return shell(std::string(BVHLAB_BINARY) + " render " + cubeMesh().string() + " --width " + std::to_string(width) +
               " --height " + std::to_string(height) + kPoseFlags + " --frames 1 --warmup 0 " + args + " -o " +
               out.string());
}

struct ImageDiff {
  double offFraction = 1.0;  // pixels whose largest channel difference exceeds the tolerance
  double meanAbs = 255.0;    // mean |difference| over R, G, B
  size_t changed = 0;        // pixels that differ at all
};

// RGB only: a window's default framebuffer need not store alpha.
ImageDiff diffImages(const ImageRgba8& a, const ImageRgba8& b, int tolerance) {
  ImageDiff d;
  if (a.width != b.width || a.height != b.height || a.rgba.size() != b.rgba.size()) return d;
  size_t off = 0, pixels = a.rgba.size() / 4;
  double sum = 0.0;
  for (size_t i = 0; i < pixels; ++i) {
    int m = 0;
    for (int c = 0; c < 3; ++c) {
      int diff = std::abs(int(a.rgba[4 * i + c]) - int(b.rgba[4 * i + c]));
      m = std::max(m, diff);
      sum += diff;
    }
    off += m > tolerance;
    d.changed += m > 0;
  }
  d.offFraction = double(off) / double(pixels);
  d.meanAbs = sum / double(3 * pixels);
  return d;
}
ImageDiff diffImages(const fs::path& a, const fs::path& b, int tolerance) {
  return diffImages(loadImageRgba8(a), loadImageRgba8(b), tolerance);
}

// "Same pixels within the renderer's tolerance": at most 0.1% of pixels off by more than 3 steps of
// 255 (the project's cross-driver tolerance) and a small mean difference. Both sides are llvmpipe
// here, so in practice the images are identical.
void expectSameImage(const fs::path& a, const fs::path& b) {
  ASSERT_TRUE(fs::exists(a)) << a;
  ASSERT_TRUE(fs::exists(b)) << b;
  ImageDiff d = diffImages(a, b, 3);
  EXPECT_LE(d.offFraction, 0.001) << a << " vs " << b;
  EXPECT_LT(d.meanAbs, 0.5) << a << " vs " << b;
}

}  // namespace

// ---- `bvhlab view` end to end -------------------------------------------------------

TEST(ViewCommand, NoDisplayIsAClearErrorNotACrash) {
  if (shell(std::string(BVHLAB_BINARY) + " view --help >/dev/null").rc != 0)
    BVHLAB_SKIP_OR_FAIL("this bvhlab has no `view` subcommand");
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
  expectSameImage(dir / "view.png", dir / "render.png");
  ImageRgba8 a = loadImageRgba8(dir / "view.png");
  const size_t pixels = a.rgba.size() / 4;
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

// `--layout`: refused as `bvhlab render` refuses it (before any window), and every layout's scripted
// frame equals the headless render of that layout; K cycles through the layout's own kernels.
TEST(ViewCommand, LayoutOptionRefusesLikeRenderAndDrawsEveryLayoutLikeRender) {
  if (shell(std::string(BVHLAB_BINARY) + " view --help >/dev/null").rc != 0)
    BVHLAB_SKIP_OR_FAIL("this bvhlab has no `view` subcommand");
  auto errorLine = [](const std::string& err) {  // the "bvhlab: error: ..." line
    const size_t at = err.find("error:");
    return at == std::string::npos ? err : err.substr(at, err.find('\n', at) - at);
  };
  for (const char* bad : {"--layout bvh9", "--layout bvh2-cb --kernel stackless"}) {
    SCOPED_TRACE(bad);
    Result v = shell("env -u DISPLAY -u WAYLAND_DISPLAY " + std::string(BVHLAB_BINARY) + " view " +
                     cubeMesh().string() + " " + bad);
    Result r = shell(std::string(BVHLAB_BINARY) + " render " + cubeMesh().string() + " " + bad + " -o " +
                     (tempDir() / "refused.png").string());
    EXPECT_EQ(v.rc, r.rc) << v.err;
    EXPECT_NE(v.rc, 0);
    EXPECT_EQ(errorLine(v.err), errorLine(r.err));
    EXPECT_NE(v.err.find("bvh2-cb"), std::string::npos) << v.err;  // names the layouts / the layout's kernels
  }

  REQUIRE_VIEWER(prefix);
  const fs::path dir = tempDir();
  writeFile(dir / "layout.txt", std::string(kPoseLine) + "2 key K\n");
  for (const LayoutInfo& layout : layouts()) {
    SCOPED_TRACE(layout.name);
    const fs::path shot = dir / ("view-" + layout.name + ".png"), headless = dir / ("render-" + layout.name + ".png");
    Result v = shell(view(*prefix, "--layout " + layout.name + " --json --frames 4 --script " +
                                       (dir / "layout.txt").string() + " --screenshot " + shot.string()));
    ASSERT_EQ(v.rc, 0) << v.err;
    const nlohmann::json j = nlohmann::json::parse(v.out);
    EXPECT_EQ(j["layout"], layout.name);
    const std::vector<KernelInfo>& own = kernelsFor(layout.name);
    size_t next = 0;  // K from the layout's default kernel: the next of its own kernels
    for (size_t i = 0; i < own.size(); ++i)
      if (own[i].name == layout.defaultKernel) next = (i + 1) % own.size();
    EXPECT_EQ(j["kernel"], own[next].name);
    EXPECT_GT(j["bytes_per_triangle"].get<double>(), 0.0);
    Result r = renderHeadless(headless, "--layout " + layout.name + " --kernel " + own[next].name);
    ASSERT_EQ(r.rc, 0) << r.err;
    expectSameImage(shot, headless);
  }
}

// `--triangles`: refused as `bvhlab render` refuses it (an unknown format; precomputed with the
// default watertight test), every format's scripted frame equals the headless render with it, and a
// script may not switch a precomputed session to a watertight variant (T skips those).
TEST(ViewCommand, TrianglesOptionRefusesLikeRenderAndDrawsEveryFormatLikeRender) {
  if (shell(std::string(BVHLAB_BINARY) + " view --help >/dev/null").rc != 0)
    BVHLAB_SKIP_OR_FAIL("this bvhlab has no `view` subcommand");
  for (const char* bad : {"--triangles quads", "--triangles precomputed"}) {
    SCOPED_TRACE(bad);
    Result v = shell("env -u DISPLAY -u WAYLAND_DISPLAY " + std::string(BVHLAB_BINARY) + " view " +
                     cubeMesh().string() + " " + bad);
    Result r = shell(std::string(BVHLAB_BINARY) + " render " + cubeMesh().string() + " " + bad + " -o " +
                     (tempDir() / "refused.png").string());
    EXPECT_NE(v.rc, 0);
    EXPECT_NE(r.rc, 0);
    // Both name the formats (unknown) or the watertight test (precomputed).
    const char* says = std::string(bad).find("quads") != std::string::npos ? "indexed" : "watertight";
    EXPECT_NE(v.err.find(says), std::string::npos) << v.err;
    EXPECT_NE(r.err.find(says), std::string::npos) << r.err;
  }

  REQUIRE_VIEWER(prefix);
  const fs::path dir = tempDir();
  writeFile(dir / "pose.txt", std::string(kPoseLine));
  for (const char* format : {"raw", "precomputed", "indexed"}) {
    SCOPED_TRACE(format);
    const std::string args = std::string("--triangles ") + format + " --robust fast";
    const fs::path shot = dir / (std::string("view-") + format + ".png"), headless = dir / (std::string("render-") + format + ".png");
    Result v = shell(view(*prefix, args + " --json --frames 2 --script " + (dir / "pose.txt").string() +
                                       " --screenshot " + shot.string()));
    ASSERT_EQ(v.rc, 0) << v.err;
    const nlohmann::json j = nlohmann::json::parse(v.out);
    EXPECT_EQ(j["triangle_format"], format);
    EXPECT_GT(j["bytes_per_triangle"].get<double>(), 0.0);
    Result r = renderHeadless(headless, args);
    ASSERT_EQ(r.rc, 0) << r.err;
    expectSameImage(shot, headless);
  }
  writeFile(dir / "watertight.txt", std::string(kPoseLine) + "1 set robust watertight\n");
  Result v = shell(view(*prefix, "--triangles precomputed --robust fast --frames 2 --script " +
                                     (dir / "watertight.txt").string()));
  EXPECT_NE(v.rc, 0);
  EXPECT_NE(v.err.find("watertight.txt:2: robust 'watertight' uses the watertight triangle test, which triangle format 'precomputed' cannot run"), std::string::npos) << v.err;
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

// Ctrl+N stores the camera as bookmark N (and prints it as render flags); N flies back to it.
TEST(ViewCommand, BookmarkKeysStoreAndRecallTheCamera) {
  REQUIRE_VIEWER(prefix);
  fs::path dir = tempDir();
  writeFile(dir / "marks.txt", "0 pose eye 1.5 1 2 target 0 0 0 fov 50\n0 key CTRL+2\n1 hold W 3\n2 mouse 30 5\n"
                               "5 key 2\n6 key 3\n");
  Result v = shell(view(*prefix, "--script " + (dir / "marks.txt").string() + " --frames 7 --record " +
                                     (dir / "marks.path").string()));
  ASSERT_EQ(v.rc, 0) << v.err;
  EXPECT_NE(v.err.find("bookmark 2: --eye 1.5,1,2 --target 0,0,0"), std::string::npos) << v.err;
  const CameraPath path = loadCameraPath(dir / "marks.path");
  ASSERT_EQ(path.size(), 7u);
  EXPECT_NE(path[4].camera.eye, path[0].camera.eye) << "the flight moved away from the bookmark";
  expectCameraEq(path[5].camera, path[0].camera);  // key 2 recalls it
  expectCameraEq(path[6].camera, path[5].camera);  // bookmark 3 was never stored: nothing happens
}

TEST(ViewCommand, ScriptedAaSwitchMatchesHeadlessAa) {
  REQUIRE_VIEWER(prefix);
  fs::path dir = tempDir();
  const std::string d = dir.string() + "/";
  writeFile(dir / "aa.txt", std::string(kPoseLine) + "0 screenshot " + d + "aa_none.png\n" +
                                "1 set aa smaa-high\n1 screenshot " + d + "aa_smaa.png\n" +
                                "3 set aa ssaa4\n3 screenshot " + d + "aa_ssaa4.png\n" + "5 key M\n");
  Result v = shell(view(*prefix, "--json --frames 7 --script " + (dir / "aa.txt").string()));
  ASSERT_EQ(v.rc, 0) << v.err;
  nlohmann::json j = nlohmann::json::parse(v.out);
  EXPECT_EQ(j["aa"], "ssaa16") << "M steps to the next mode after ssaa4";
  ASSERT_EQ(j["switches"].size(), 3u);
  EXPECT_EQ(j["switches"][0]["switch"], "aa");
  EXPECT_EQ(j["switches"][0]["value"], "smaa-high");
  EXPECT_GT(j["switches"][0]["aa_ms_after"].get<double>(), 0.0) << "the SMAA passes are timed apart";
  EXPECT_EQ(j["switches"][1]["aa_ms_after"].get<double>(), 0.0) << "SSAA has no post pass";

  for (const char* mode : {"none", "smaa-high", "ssaa4"}) {
    const std::string name = std::string(mode) == "smaa-high" ? "smaa" : mode;
    Result r = renderHeadless(dir / ("aa_render_" + name + ".png"), std::string("--aa ") + mode);
    ASSERT_EQ(r.rc, 0) << r.err;
    SCOPED_TRACE(mode);
    expectSameImage(dir / ("aa_" + name + ".png"), dir / ("aa_render_" + name + ".png"));
  }
  // The switch did change the image: SMAA touches the cube's edges, not most of the frame.
  ImageDiff smaa = diffImages(dir / "aa_none.png", dir / "aa_smaa.png", 0);
  EXPECT_GT(smaa.changed, 0u);
  EXPECT_LT(smaa.changed, size_t(96 * 64 / 4));
  EXPECT_GT(diffImages(dir / "aa_none.png", dir / "aa_ssaa4.png", 0).changed, 0u);
}

// The visit heatmap in the viewer is `render --view visits` of the same kernel, and switching the kernel
// live changes it the way the headless kernels differ (the shader was reassembled, not just renamed).
TEST(ViewCommand, ScriptedHeatmapAndKernelSwitchMatchHeadlessVisits) {
  REQUIRE_VIEWER(prefix);
  fs::path dir = tempDir();
  const std::string d = dir.string() + "/";
  writeFile(dir / "heat.txt", std::string(kPoseLine) + "1 set view visits\n2 screenshot " + d + "heat_ordered.png\n" +
                                  "3 set kernel stack-unordered\n4 screenshot " + d + "heat_unordered.png\n" +
                                  "5 key V\n");
  Result v = shell(view(*prefix, "--kernel stack-ordered --leaf-size 1 --json --frames 7 --script " +
                                     (dir / "heat.txt").string()));
  ASSERT_EQ(v.rc, 0) << v.err;
  nlohmann::json j = nlohmann::json::parse(v.out);
  EXPECT_EQ(j["view"], "shaded") << "V steps from the last view (visits) back to the first";
  EXPECT_EQ(j["kernel"], "stack-unordered");
  for (const char* kernel : {"stack-ordered", "stack-unordered"}) {
    SCOPED_TRACE(kernel);
    const std::string name = std::string(kernel) == "stack-ordered" ? "ordered" : "unordered";
    Result r = renderHeadless(dir / ("heat_render_" + name + ".png"),
                              std::string("--view visits --leaf-size 1 --kernel ") + kernel);
    ASSERT_EQ(r.rc, 0) << r.err;
    expectSameImage(dir / ("heat_" + name + ".png"), dir / ("heat_render_" + name + ".png"));
  }
  EXPECT_GT(diffImages(dir / "heat_render_ordered.png", dir / "heat_render_unordered.png", 0).changed, 0u)
      << "the two kernels visit different numbers of nodes somewhere";
  EXPECT_GT(diffImages(dir / "heat_ordered.png", dir / "heat_unordered.png", 0).changed, 0u);
}

TEST(ViewCommand, ScriptedRobustnessSwitchMatchesHeadless) {
  REQUIRE_VIEWER(prefix);
  const std::vector<std::string>& names = robustnessNames();  // whatever variants traversal offers
  ASSERT_FALSE(names.empty());
  const std::string next = names[1 % names.size()], last = names.back();
  fs::path dir = tempDir();
  const std::string d = dir.string() + "/";
  writeFile(dir / "robust.txt", std::string(kPoseLine) + "1 key T\n1 screenshot " + d + "robust_next.png\n" +
                                    "3 set robust " + last + "\n3 screenshot " + d + "robust_last.png\n");
  Result v = shell(view(*prefix, "--robust " + names[0] + " --json --frames 5 --script " + (dir / "robust.txt").string()));
  ASSERT_EQ(v.rc, 0) << v.err;
  nlohmann::json j = nlohmann::json::parse(v.out);
  EXPECT_EQ(j["robust"], last);
  ASSERT_EQ(j["switches"].size(), 2u);
  EXPECT_EQ(j["switches"][0]["switch"], "robust");
  EXPECT_EQ(j["switches"][0]["value"], next) << "T steps through robustnessNames() in order";
  EXPECT_TRUE(j["switches"][0].contains("first_frame_ms")) << "the shader was reassembled";
  for (const auto& [file, variant] : {std::pair{"robust_next", next}, {"robust_last", last}}) {
    Result r = renderHeadless(dir / (std::string(file) + "_render.png"), "--robust " + variant);
    ASSERT_EQ(r.rc, 0) << r.err;
    SCOPED_TRACE(variant);
    expectSameImage(dir / (std::string(file) + ".png"), dir / (std::string(file) + "_render.png"));
  }
  Result bad = shell(view(*prefix, "--robust nope --frames 1"));
  EXPECT_EQ(bad.rc, 2) << "a refused option value is a usage error";
  EXPECT_NE(bad.err.find("bvhlab: error: "), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find(names[0]), std::string::npos) << "lists the valid variants: " << bad.err;
}

namespace {

// Bilinear upscaling with GL's texel-centre convention and clamp-to-edge: what a linear-filtered
// glBlitFramebuffer from src to a dstW x dstH window computes.
ImageRgba8 upscaleBilinear(const ImageRgba8& src, int dstW, int dstH) {
  ImageRgba8 out;
  out.width = dstW;
  out.height = dstH;
  out.rgba.resize(size_t(dstW) * size_t(dstH) * 4);
  auto texel = [&](int x, int y, int c) {
    x = std::clamp(x, 0, src.width - 1);
    y = std::clamp(y, 0, src.height - 1);
    return double(src.rgba[(size_t(y) * size_t(src.width) + size_t(x)) * 4 + size_t(c)]);
  };
  for (int y = 0; y < dstH; ++y)
    for (int x = 0; x < dstW; ++x) {
      const double u = (x + 0.5) * src.width / dstW - 0.5, v = (y + 0.5) * src.height / dstH - 0.5;
      const int x0 = int(std::floor(u)), y0 = int(std::floor(v));
      const double fx = u - x0, fy = v - y0;
      for (int c = 0; c < 4; ++c) {
        const double top = texel(x0, y0, c) * (1 - fx) + texel(x0 + 1, y0, c) * fx;
        const double bottom = texel(x0, y0 + 1, c) * (1 - fx) + texel(x0 + 1, y0 + 1, c) * fx;
        out.rgba[(size_t(y) * size_t(dstW) + size_t(x)) * 4 + size_t(c)] = uint8_t(std::lround(top * (1 - fy) + bottom * fy));
      }
    }
  return out;
}

}  // namespace

TEST(ViewCommand, DirectBlitShowsTheHeadlessRender) {
  REQUIRE_VIEWER(prefix);
  fs::path dir = tempDir();
  const std::string d = dir.string() + "/";
  auto script = [&](const std::string& tag) {
    fs::path p = dir / ("blit_" + tag + ".txt");
    writeFile(p, std::string(kPoseLine) + "1 window-screenshot " + d + "win_" + tag + ".png\n");
    return p.string();
  };
  // What the window shows (no overlay) is the render, pixel for pixel, with or without the read-back.
  Result blit = shell(view(*prefix, "--no-overlay --frames 2 --script " + script("blit")));
  ASSERT_EQ(blit.rc, 0) << blit.err;
  Result readback = shell(view(*prefix, "--no-overlay --readback-present --frames 2 --script " + script("readback")));
  ASSERT_EQ(readback.rc, 0) << readback.err;
  Result r = renderHeadless(dir / "blit_render.png", "");
  ASSERT_EQ(r.rc, 0) << r.err;
  expectSameImage(dir / "win_blit.png", dir / "blit_render.png");
  EXPECT_EQ(diffImages(dir / "win_blit.png", dir / "win_readback.png", 0).changed, 0u);

  // Half resolution: the 48x32 render, linearly upscaled to the 96x64 window by the blit.
  Result half = shell(view(*prefix, "--no-overlay --scale 0.5 --frames 2 --script " + script("half")));
  ASSERT_EQ(half.rc, 0) << half.err;
  Result small = renderHeadless(dir / "blit_render_half.png", "", 48, 32);
  ASSERT_EQ(small.rc, 0) << small.err;
  ImageRgba8 window = loadImageRgba8(dir / "win_half.png");
  ASSERT_EQ(window.width, 96);
  ASSERT_EQ(window.height, 64);
  // Tolerance 3: the blit filters in 8-bit fixed point, the reference in double.
  ImageDiff d2 = diffImages(window, upscaleBilinear(loadImageRgba8(dir / "blit_render_half.png"), 96, 64), 3);
  EXPECT_LE(d2.offFraction, 0.001);
  EXPECT_LT(d2.meanAbs, 0.5);
}
