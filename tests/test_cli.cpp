// The command line as a user meets it: JSON contract, backends, and bad input (one clear line,
// non-zero exit, no partial output file).
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_run.hpp"
#include "require.hpp"
#include "datasets/image_io.hpp"
#include "render/gl_context.hpp"

namespace {

using namespace bvhlab::clitest;

[[maybe_unused]] ::testing::Environment* const kRemoveTestDir = ::testing::AddGlobalTestEnvironment(new RemoveTestDir);

// A bumpy N x N height field over [-1, 1]^2 as OFF text: 2 N^2 triangles, enough for a BVH of many
// levels (the JSON's traversal counters are only meaningful when rays walk a tree).
std::string heightFieldOff(int n) {
  std::ostringstream off;
  off << "OFF\n" << (n + 1) * (n + 1) << " " << 2 * n * n << " 0\n";
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const double x = 2.0 * i / n - 1.0, z = 2.0 * j / n - 1.0;
      off << x << " " << 0.2 * std::sin(3.0 * x) * std::cos(4.0 * z) << " " << z << "\n";
    }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      off << "3 " << a << " " << c << " " << b << "\n3 " << b << " " << c << " " << d << "\n";
    }
  return off.str();
}

// The contract keys, on a mesh (a scene without one walks no tree and would report 0 visits whatever
// the counters did), and the counters consistent with each other and with the tree.
TEST(Cli, RenderJsonHasTheContractKeys) {
  constexpr int kN = 24, kTriangles = 2 * kN * kN, kW = 64, kH = 36;
  const fs::path mesh = writeTemp("heightfield.off", heightFieldOff(kN));
  fs::path png = testDir() / "mesh.png";
  fs::remove(png);
  Result r = run("render " + mesh.string() + " -o " + png.string() + " --json --width " + std::to_string(kW) +
                 " --height " + std::to_string(kH) + " --frames 2 --warmup 1 --builder sah-binned --leaf-size 4");
  ASSERT_EQ(r.code, 0) << r.err;
  auto j = nlohmann::json::parse(r.out);
  for (const char* key : {"frame_ms", "frame_ms_min", "frames", "width", "height", "depth", "backend", "renderer",
                          "builder", "kernel", "leaf_size", "build_ms", "sah_cost", "node_visits_per_ray",
                          "triangle_tests_per_ray", "mesh_rays", "ray_cost", "nodes", "leaves", "triangles",
                          "node_visits_p95", "triangle_tests_p95", "box_tests_per_ray", "box_tests_p95"})
    ASSERT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["frames"], 2);
  EXPECT_EQ(j["width"], kW);
  EXPECT_TRUE(fs::exists(png));

  EXPECT_EQ(j["triangles"].get<int>(), kTriangles);
  const double nodes = j["nodes"].get<double>(), leaves = j["leaves"].get<double>();
  EXPECT_GE(leaves, double(kTriangles) / 4.0) << "leaves hold at most leaf_size = 4 triangles";
  EXPECT_EQ(nodes, 2.0 * leaves - 1.0) << "a binary tree";
  EXPECT_GT(j["sah_cost"].get<double>(), 0.0);
  // Every pixel's primary ray is traced into the mesh BVH (plus shadow rays towards the lights).
  const double rays = j["mesh_rays"].get<double>();
  EXPECT_GE(rays, double(kW * kH));
  const double visits = j["node_visits_per_ray"].get<double>(), tests = j["triangle_tests_per_ray"].get<double>();
  EXPECT_GT(visits, 1.0) << "rays into a multi-level tree visit more than its root";
  EXPECT_LE(visits, nodes);
  EXPECT_GT(tests, 0.0);
  EXPECT_LE(tests, double(kTriangles));
  EXPECT_LE(tests, 4.0 * visits) << "at most leaf_size tests per visited node";
  EXPECT_NEAR(j["ray_cost"].get<double>(), visits + tests, 1e-9 * (visits + tests)) << "Ct = Ci = 1";
  EXPECT_GT(j["node_visits_p95"].get<double>(), 0.0);
  EXPECT_GT(j["triangle_tests_p95"].get<double>(), 0.0);
  // v1's stack-ordered tests the boxes of the nodes it meets: at least one per ray, at most two per visit.
  const double boxes = j["box_tests_per_ray"].get<double>();
  EXPECT_GE(boxes, 1.0);
  EXPECT_LE(boxes, 2.0 * visits);
  EXPECT_EQ(j["stack_overflow_pixels"].get<int>(), 0);
  EXPECT_EQ(j["nonfinite_pixels"].get<int>(), 0);
  std::printf("[ measured ] %d-triangle height field: %g nodes, %g leaves, %g mesh rays, %.2f node visits and %.2f"
              " triangle tests per ray, ray_cost %.2f\n", kTriangles, nodes, leaves, rays, visits, tests,
              j["ray_cost"].get<double>());
}

// Without a GPU, EGL lands on Mesa's llvmpipe like OSMesa, and this only shows the two context paths
// feed the same renderer (said in the output). On a GPU the images come from different rasterisers:
// they must agree as the GLSL-vs-mirror comparisons do (mean <= 0.5 steps, 99% within 3 steps).
TEST(Cli, EglAndOsmesaGiveTheSameImage) {
  fs::path a = testDir() / "osmesa.png";
  fs::path b = testDir() / "egl.png";
  Result ra = run("render " + scene("shadows.toml").string() + " -o " + a.string() + " --width 64 --height 36 --frames 1 --warmup 0");
  ASSERT_EQ(ra.code, 0) << ra.err;
  Result rb = run("render " + scene("shadows.toml").string() + " -o " + b.string() +
                  " --width 64 --height 36 --frames 1 --warmup 0 --backend egl --json");
  if (rb.code != 0 && rb.err.find("egl:") != std::string::npos) BVHLAB_SKIP_OR_FAIL("no EGL here: " << rb.err);
  ASSERT_EQ(rb.code, 0) << rb.err;
  const nlohmann::json j = nlohmann::json::parse(rb.out);
  const std::string renderer = j["renderer"].get<std::string>();
  const bvhlab::ImageRgba8 ia = bvhlab::loadImageRgba8(a), ib = bvhlab::loadImageRgba8(b);
  ASSERT_EQ(ia.rgba.size(), ib.rgba.size());
  if (bvhlab::isSoftwareRenderer(renderer)) {
    std::printf("EGL ran on %s (no GPU): EGL and OSMesa are both llvmpipe here, so the images must be identical\n",
                renderer.c_str());
    EXPECT_EQ(j["gpu"], false);
    EXPECT_NE(rb.err.find("found no GPU"), std::string::npos) << rb.err;
    EXPECT_EQ(ia.rgba, ib.rgba);
  } else {
    std::printf("EGL ran on %s: comparing a GPU image with llvmpipe's\n", renderer.c_str());
    EXPECT_EQ(j["gpu"], true);
    double sum = 0.0;
    size_t within = 0;
    for (size_t i = 0; i < ia.rgba.size(); ++i) {
      const int d = std::abs(int(ia.rgba[i]) - int(ib.rgba[i]));
      sum += d;
      within += d <= 3;
    }
    EXPECT_LE(sum / double(ia.rgba.size()), 0.5);
    EXPECT_GE(double(within), 0.99 * double(ia.rgba.size()));
  }
}

TEST(Cli, UnknownNamesListTheValidOnes) {
  Result r = run("render " + scene("sphere.toml").string() + " --builder nope");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("sah-binned"), std::string::npos) << r.err;
  r = run("render " + scene("sphere.toml").string() + " --kernel nope");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("stackless"), std::string::npos) << r.err;
  r = run("render " + scene("sphere.toml").string() + " --backend nope");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("osmesa"), std::string::npos) << r.err;
}

struct BadInput {
  std::string name, text, expect;
};

class CliBadInput : public ::testing::TestWithParam<BadInput> {};

TEST_P(CliBadInput, OneLineErrorNonZeroExitNoOutputFile) {
  const BadInput& b = GetParam();
  fs::path input = writeTemp(b.name, b.text);
  fs::path png = testDir() / "should_not_exist.png";
  fs::remove(png);
  Result r = run("render " + input.string() + " -o " + png.string() + " --width 32 --height 18");
  EXPECT_EQ(r.code, 2) << "bad content is a usage error: " << r.err;
  EXPECT_EQ(r.err.rfind("bvhlab: error: ", 0), 0u) << r.err;
  EXPECT_FALSE(fs::exists(png));
  EXPECT_NE(r.err.find(b.expect), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
}

INSTANTIATE_TEST_SUITE_P(
    Cases, CliBadInput,
    ::testing::Values(BadInput{"unknown_key.toml", "[camera]\neye = [0,0,5]\nfocus = 3\n", "focus"},
                      BadInput{"wrong_type.toml", "[camera]\neye = [0,0,5]\ntarget = [0,0,0]\nfov = \"wide\"\n", "fov"},
                      BadInput{"truncated.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n", "truncated.off"},
                      BadInput{"nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", "nan.obj"},
                      BadInput{"range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", "range.obj"},
                      BadInput{"empty.obj", "# nothing\n", "empty.obj"},
                      BadInput{"mesh.xyz", "1 2 3\n", "mesh.xyz"},
                      BadInput{"radius.toml", "[camera]\neye = [0,0,5]\ntarget = [0,0,0]\n[[object]]\nkind = \"torus\"\nminor_radius = -1\n", "minor_radius"},
                      BadInput{"ior.toml", "[camera]\neye = [0,0,5]\ntarget = [0,0,0]\n[[material]]\nname = \"g\"\nior = 0\n", "ior"},
                      BadInput{"nan.toml", "[camera]\neye = [0,nan,5]\ntarget = [0,0,0]\n", "NaN"},
                      BadInput{"nomat.toml", "[camera]\neye = [0,0,5]\ntarget = [0,0,0]\n[[object]]\nkind = \"sphere\"\nmaterial = \"x\"\n", "unknown material"},
                      BadInput{"nofile.toml", "[camera]\neye = [0,0,5]\ntarget = [0,0,0]\n[[object]]\nkind = \"mesh\"\nmesh = \"missing.obj\"\n", "missing.obj"}),
    [](const auto& info) {
      std::string s = info.param.name;
      for (char& c : s)
        if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
      return s;
    });

TEST(Cli, MissingInputNamesThePath) {
  Result r = run("render /nonexistent/scene.toml");
  EXPECT_EQ(r.code, 1) << "a missing file is a runtime failure: " << r.err;
  EXPECT_NE(r.err.find("/nonexistent/scene.toml"), std::string::npos) << r.err;
}

}  // namespace

namespace {

TEST(Cli, SmaaIsTimedAndChangesOnlyEdgePixels) {
  fs::path none = testDir() / "aa_none.png";
  fs::path smaa = testDir() / "aa_smaa.png";
  std::string common = " --width 96 --height 54 --frames 1 --warmup 1 --json";
  Result a = run("render " + scene("shadows.toml").string() + " -o " + none.string() + common);
  Result b = run("render " + scene("shadows.toml").string() + " -o " + smaa.string() + common + " --aa smaa");
  ASSERT_EQ(a.code, 0) << a.err;
  ASSERT_EQ(b.code, 0) << b.err;
  auto j = nlohmann::json::parse(b.out);
  EXPECT_EQ(j["aa"], "smaa");
  EXPECT_GT(j["aa_ms"].get<double>(), 0.0);
  bvhlab::ImageRgba8 ia = bvhlab::loadImageRgba8(none), ib = bvhlab::loadImageRgba8(smaa);
  ASSERT_EQ(ia.rgba.size(), ib.rgba.size());
  size_t changed = 0, pixels = ia.rgba.size() / 4;
  for (size_t i = 0; i < pixels; ++i)
    changed += ia.rgba[4 * i] != ib.rgba[4 * i] || ia.rgba[4 * i + 1] != ib.rgba[4 * i + 1] ||
               ia.rgba[4 * i + 2] != ib.rgba[4 * i + 2];
  EXPECT_GT(changed, 0u) << "SMAA changed nothing";
  EXPECT_LT(changed, pixels / 4) << "SMAA should touch edge pixels only, not most of the image";
  Result bad = run("render " + scene("shadows.toml").string() + " --aa ssaa64");
  EXPECT_NE(bad.code, 0);
  EXPECT_NE(bad.err.find("ssaa16"), std::string::npos) << "the error lists the valid modes: " << bad.err;
}

}  // namespace

namespace {

TEST(Cli, CameraPathTimesFramesAlongThePathAndSavesPoseZero) {
  // Three poses around shadows.toml's own view; the first is the one the saved image must show.
  const fs::path path = writeTemp("orbit.txt",
                                  "t 0 eye 0.5 3 6 target 0 0.5 0 up 0 1 0 fov 45\n"
                                  "# a comment line is not a pose\n"
                                  "t 0.033 eye 2 3 5.5 target 0 0.5 0 up 0 1 0 fov 45\n"
                                  "t 0.067 eye 4 2.5 4 target 0 0.5 0 up 0 1 0 fov 50\n");
  fs::path along = testDir() / "path_along.png";
  fs::path pose0 = testDir() / "path_pose0.png";
  const std::string common = " --width 64 --height 36 --warmup 1 ";
  Result a = run("render " + scene("shadows.toml").string() + common + "--frames 5 --json --camera-path " +
                 path.string() + " -o " + along.string());
  ASSERT_EQ(a.code, 0) << a.err;
  auto j = nlohmann::json::parse(a.out);
  EXPECT_EQ(j["camera_path"], path.string());
  std::ifstream in(path);
  int poseLines = 0;
  for (std::string line; std::getline(in, line);) poseLines += !line.empty() && line[0] != '#';
  EXPECT_EQ(j["path_poses"], poseLines);
  EXPECT_EQ(j["frames"], 5);  // the last timed frame is pose 1: the saved image must be drawn again
  EXPECT_GT(j["frame_ms"].get<double>(), 0.0);

  Result b = run("render " + scene("shadows.toml").string() + common +
                 "--frames 1 --eye 0.5,3,6 --target 0,0.5,0 --up 0,1,0 --fov 45 -o " + pose0.string());
  ASSERT_EQ(b.code, 0) << b.err;
  bvhlab::ImageRgba8 ia = bvhlab::loadImageRgba8(along), ib = bvhlab::loadImageRgba8(pose0);
  EXPECT_EQ(ia.rgba, ib.rgba) << "the saved image is pose 0's, whichever pose was timed last";
}

TEST(Cli, BadCameraPathNamesFileAndLine) {
  const fs::path path = writeTemp("bad_orbit.txt",
                                  "t 0 eye 0.5 3 6 target 0 0.5 0 up 0 1 0 fov 45\n"
                                  "t 0.033 eye 2 3 5.5 target 0 0.5 0 up 0 1 0\n");
  fs::path png = testDir() / "bad_path.png";
  fs::remove(png);
  Result r = run("render " + scene("shadows.toml").string() + " --camera-path " + path.string() + " -o " + png.string());
  EXPECT_EQ(r.code, 2) << "a camera path's bad content is a usage error";
  EXPECT_NE(r.err.find(path.string() + ":2: missing 'fov'"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(png));
  Result missing = run("render " + scene("shadows.toml").string() + " --camera-path /nonexistent/path.txt");
  EXPECT_EQ(missing.code, 1) << "a missing file is a runtime failure";
  EXPECT_NE(missing.err.find("/nonexistent/path.txt"), std::string::npos) << missing.err;
  Result both = run("render " + scene("shadows.toml").string() + " --camera-path " +
                    writeTemp("ok.txt", "t 0 eye 0.5 3 6 target 0 0.5 0 up 0 1 0 fov 45\n").string() + " --eye 1,2,3");
  EXPECT_EQ(both.code, 2);
  EXPECT_NE(both.err.find("--camera-path"), std::string::npos) << both.err;
}

// A far scene is stored relative to its eye (camera-relative loading); --eye/--target still take world
// coordinates, parsed in double: giving the file's own camera reproduces the file's image exactly.
TEST(Cli, EyeAndTargetOfAFarSceneAreWorldCoordinates) {
  const fs::path far = fs::path(BVHLAB_SOURCE_DIR) / "datasets/hard/far_1e6.toml";
  const fs::path dir = testDir();
  fs::create_directories(dir);
  const fs::path a = dir / "far_file_camera.png", b = dir / "far_flag_camera.png";
  Result r1 = run("render " + far.string() + " --width 64 --height 40 -o " + a.string());
  ASSERT_EQ(r1.code, 0) << r1.err;
  Result r2 = run("render " + far.string() + " --width 64 --height 40 --eye 1e6,500002.2,-999993.5 "
                  "--target 1e6,500000.5,-1e6 -o " + b.string());
  ASSERT_EQ(r2.code, 0) << r2.err;
  EXPECT_EQ(bvhlab::loadImageRgba8(a).rgba, bvhlab::loadImageRgba8(b).rgba);
}

}  // namespace

// -o writes the format its extension names (through OpenImageIO) or is refused before anything is
// rendered; the files read back as the same picture.
TEST(Cli, OutputFormatFollowsTheExtensionOrIsRefused) {
  const fs::path dir = testDir() / "formats";
  fs::create_directories(dir);
  const std::string input = scene("sphere.toml").string();
  Result png = run("render " + input + " --width 40 --height 24 --frames 1 -o " + (dir / "a.png").string());
  ASSERT_EQ(png.code, 0) << png.err;
  const bvhlab::ImageRgba8 reference = bvhlab::loadImageRgba8(dir / "a.png");
  for (const char* name : {"a.tif", "a.TIFF", "a.jpg", "a.jpeg"}) {
    SCOPED_TRACE(name);
    Result r = run("render " + input + " --width 40 --height 24 --frames 1 -o " + (dir / name).string());
    ASSERT_EQ(r.code, 0) << r.err;
    std::ifstream f(dir / name, std::ios::binary);
    std::array<unsigned char, 4> magic{};
    f.read(reinterpret_cast<char*>(magic.data()), 4);
    const bool jpeg = std::string(name).find("jp") != std::string::npos;
    if (jpeg) {
      EXPECT_EQ(magic[0], 0xFF);  // JPEG SOI marker FF D8
      EXPECT_EQ(magic[1], 0xD8);
    } else {
      EXPECT_TRUE((magic[0] == 'I' && magic[1] == 'I') || (magic[0] == 'M' && magic[1] == 'M'));  // TIFF byte order
    }
    const bvhlab::ImageRgba8 back = bvhlab::loadImageRgba8(dir / name);
    ASSERT_EQ(back.width, reference.width);
    ASSERT_EQ(back.height, reference.height);
    double diff = 0.0;
    for (size_t i = 0; i < back.rgba.size(); i += 4)
      for (int c = 0; c < 3; ++c) diff += std::abs(int(back.rgba[i + c]) - int(reference.rgba[i + c]));
    diff /= 3.0 * double(back.rgba.size() / 4);
    EXPECT_LT(diff, jpeg ? 3.0 : 1e-9) << "mean |difference| over RGB";
  }
  for (const char* name : {"a.exr", "a.gif", "a.txt"}) {
    SCOPED_TRACE(name);
    Result r = run("render " + input + " --width 40 --height 24 --frames 1 -o " + (dir / name).string());
    EXPECT_NE(r.code, 0);
    EXPECT_NE(r.err.find(name), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(".png"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / name));
  }
}

TEST(Cli, UnknownOrMissingCommandListsTheCommandsAndVersionPrintsTheCommit) {
  Result typo = run("rendr scene.toml");
  EXPECT_EQ(typo.code, 2);
  EXPECT_NE(typo.err.find("unknown command 'rendr'"), std::string::npos) << typo.err;
  for (const char* c : {"render", "build", "run", "measure", "report"})
    EXPECT_NE(typo.err.find(c), std::string::npos) << c << " not listed: " << typo.err;
  Result none = run("");
  EXPECT_EQ(none.code, 2);
  EXPECT_NE(none.err.find("no command given"), std::string::npos) << none.err;
  Result version = run("--version");
  EXPECT_EQ(version.code, 0) << version.err;
  EXPECT_EQ(version.out.rfind("bvhlab ", 0), 0u) << version.out;
  EXPECT_NE(version.out.find("(commit "), std::string::npos) << version.out;
}

TEST(Cli, ReplicatesOutOfRangeAreRefusedAndMergeReplicatesNeedsANewDirectory) {
  const fs::path dir = testDir() / "replicates";
  fs::create_directories(dir);
  std::ofstream(dir / "cfg.toml") << "[axes]\nscenes = \"a.off\"\n";
  Result zero = run("run " + (dir / "cfg.toml").string() + " --out " + (dir / "out").string() + " --replicates 0");
  EXPECT_EQ(zero.code, 2);
  EXPECT_NE(zero.err.find("--replicates"), std::string::npos) << zero.err;
  EXPECT_FALSE(fs::exists(dir / "out"));
  // An existing sweep as --out: merging replicates into it would count them twice.
  fs::create_directories(dir / "old");
  std::ofstream(dir / "old" / "plan.json") << "{}";
  Result into = run("merge --replicates " + (dir / "a").string() + " --out " + (dir / "old").string());
  EXPECT_EQ(into.code, 2);
  EXPECT_NE(into.err.find("new directory"), std::string::npos) << into.err;
}
