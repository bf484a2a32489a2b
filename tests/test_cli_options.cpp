// What the command line says about the options a user gives: a directory as input, --bins and
// --leaf-size against what the builder does with them, the path `render` wrote, --help's defaults,
// and whether a render ran on a GPU (EGL falls back to Mesa's software renderer without one).
#include <cmath>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "builders/builder.hpp"
#include "cli_run.hpp"
#include "require.hpp"
#include "render/gl_context.hpp"

namespace {

using namespace bvhlab::clitest;
using nlohmann::json;

[[maybe_unused]] ::testing::Environment* const kRemoveTestDir = ::testing::AddGlobalTestEnvironment(new RemoveTestDir);

// A 16 x 16 grid of quads as OFF text (512 triangles): enough for leaves to fill up.
fs::path gridMesh() {
  std::ostringstream off;
  const int n = 16;
  off << "OFF\n" << (n + 1) * (n + 1) << " " << 2 * n * n << " 0\n";
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x) off << x << " " << y << " " << ((x * 7 + y * 3) % 5) * 0.1 << "\n";
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const int a = y * (n + 1) + x, b = a + 1, c = a + n + 1, d = c + 1;
      off << "3 " << a << " " << b << " " << d << "\n3 " << a << " " << d << " " << c << "\n";
    }
  return writeTemp("grid.off", off.str());
}

TEST(CliOptions, ADirectoryAsInputIsNamedAsOne) {
  const std::string dir = (fs::path(BVHLAB_SOURCE_DIR) / "datasets/scenes").string();
  for (const std::string& args : {"render " + dir, "build --mesh " + dir, "run " + dir}) {
    Result r = run(args);
    EXPECT_NE(r.code, 0) << args;
    EXPECT_NE(r.err.find(dir + " is a directory"), std::string::npos) << args << ": " << r.err;
  }
}

TEST(CliOptions, BadBinsAreRefusedBeforeTheMeshIsRead) {
  // The mesh does not exist: the option error must come first.
  for (const char* bins : {"-1", "1", "257"}) {
    Result r = run(std::string("build --mesh no_such_mesh.off --bins ") + bins);
    EXPECT_NE(r.code, 0) << bins;
    EXPECT_NE(r.err.find("--bins"), std::string::npos) << bins << ": " << r.err;
    EXPECT_EQ(r.err.find("no_such_mesh"), std::string::npos) << bins << ": " << r.err;
  }
}

TEST(CliOptions, MortonSizeBitsAreRangeCheckedReportedAndWarnedAbout) {
  // Out of range: refused before the mesh is read, naming the flag (build and render).
  for (const char* bits : {"-1", "10"}) {
    for (const std::string command : {"build --mesh", "render"}) {
      Result r = run(command + " no_such_mesh.off --builder ploc --morton-size-bits " + bits);
      EXPECT_NE(r.code, 0) << command << " " << bits;
      EXPECT_NE(r.err.find("--morton-size-bits must be in 0..9"), std::string::npos) << bits << ": " << r.err;
      EXPECT_EQ(r.err.find("no_such_mesh"), std::string::npos) << bits << ": " << r.err;
    }
  }
  const fs::path mesh = gridMesh();
  for (const std::string builder : {"ploc", "lbvh"}) {
    Result r = run("build --mesh " + mesh.string() + " --builder " + builder + " --morton-size-bits 6 --json");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;
    const json j = json::parse(r.out);
    EXPECT_EQ(j["morton_size_bits"], 6);
    EXPECT_EQ(j["ploc_radius"], 16);
  }
  Result r = run("build --mesh " + mesh.string() + " --builder sah-binned --morton-size-bits 3 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("warning: sah-binned ignores --morton-size-bits"), std::string::npos) << r.err;
}

TEST(CliOptions, MortonGridIsCheckedReportedAndWarnedAbout) {
  // An unknown grid: refused before the mesh is read, naming the flag and the valid names.
  for (const std::string command : {"build --mesh", "render"}) {
    Result r = run(command + " no_such_mesh.off --builder lbvh --morton-grid square");
    EXPECT_NE(r.code, 0) << command;
    EXPECT_NE(r.err.find("unknown --morton-grid 'square'; valid: cube, axes"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("no_such_mesh"), std::string::npos) << r.err;
  }
  const fs::path mesh = gridMesh();
  for (const std::string grid : {"cube", "axes"}) {
    Result r = run("build --mesh " + mesh.string() + " --builder lbvh --morton-grid " + grid + " --json");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;
    EXPECT_EQ(json::parse(r.out)["morton_grid"], grid);
  }
  Result r = run("build --mesh " + mesh.string() + " --json");  // the default
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(json::parse(r.out)["morton_grid"], "cube");
  r = run("build --mesh " + mesh.string() + " --builder median --morton-grid axes --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("warning: median ignores --morton-grid"), std::string::npos) << r.err;
}

TEST(CliOptions, PlocTopDownIsCheckedReportedAndWarnedAbout) {
  // Out of range: refused before the mesh is read, naming the flag and the range.
  for (const std::string command : {"build --mesh", "render", "trace"}) {
    Result r = run(command + " no_such_mesh.off --builder ploc --ploc-top-down 1025");
    EXPECT_NE(r.code, 0) << command;
    EXPECT_NE(r.err.find("--ploc-top-down must be in 0..1024 (got 1025)"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("no_such_mesh"), std::string::npos) << r.err;
  }
  const fs::path mesh = gridMesh();
  Result r = run("build --mesh " + mesh.string() + " --builder ploc --ploc-top-down 4 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;
  EXPECT_EQ(json::parse(r.out)["ploc_top_down"], 4);
  r = run("build --mesh " + mesh.string() + " --builder ploc --json");  // the default: cluster to the end
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(json::parse(r.out)["ploc_top_down"], 0);
  r = run("build --mesh " + mesh.string() + " --builder lbvh --ploc-top-down 4 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("warning: lbvh ignores --ploc-top-down"), std::string::npos) << r.err;
}

TEST(CliOptions, SbvhBudgetIsCheckedReportedAndWarnedAbout) {
  // Below 1 or not a finite number: refused before the mesh is read, naming the flag.
  for (const std::string command : {"build --mesh", "render", "trace"}) {
    for (const char* budget : {"0.5", "0", "-2", "nan", "inf"}) {
      Result r = run(command + " no_such_mesh.off --builder sbvh --sbvh-budget " + budget);
      EXPECT_NE(r.code, 0) << command << " " << budget;
      EXPECT_NE(r.err.find("--sbvh-budget"), std::string::npos) << command << " " << budget << ": " << r.err;
      EXPECT_EQ(r.err.find("no_such_mesh"), std::string::npos) << command << " " << budget << ": " << r.err;
    }
  }
  Result r = run("build --mesh no_such_mesh.off --builder sbvh --sbvh-budget 0.5");
  EXPECT_NE(r.err.find("--sbvh-budget must be a finite number >= 1"), std::string::npos) << r.err;
  // Reaches the builder: 64 long needles crossing at one point, where spatial splits pay, get extra
  // references within the default budget (2x) and none with a budget of 1; the JSON says what was used.
  std::ostringstream off;
  off << "OFF\n192 64 0\n";
  for (int k = 0; k < 64; ++k) {
    const double a = 3.14159265358979 * k / 64, c = std::cos(a), s = std::sin(a);
    off << -10 * c << " " << -10 * s << " 0\n" << 10 * c << " " << 10 * s << " 0\n"
        << 10 * c - 0.1 * s << " " << 10 * s + 0.1 * c << " 0.2\n";
  }
  for (int k = 0; k < 64; ++k) off << "3 " << 3 * k << " " << 3 * k + 1 << " " << 3 * k + 2 << "\n";
  const fs::path needles = writeTemp("needles.off", off.str());
  r = run("build --mesh " + needles.string() + " --builder sbvh --json");
  ASSERT_EQ(r.code, 0) << r.err;
  json j = json::parse(r.out);
  EXPECT_EQ(j["sbvh_budget"], 2.0);
  EXPECT_FLOAT_EQ(j["sbvh_alpha"].get<float>(), 1e-5f);
  EXPECT_EQ(j["primitives"], 64);
  EXPECT_GT(j["references"].get<int>(), 64);
  EXPECT_LE(j["references"].get<int>(), 128);
  const double sahWithSplits = j["sah_cost"];
  r = run("build --mesh " + needles.string() + " --builder sbvh --sbvh-budget 1 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;
  j = json::parse(r.out);
  EXPECT_EQ(j["sbvh_budget"], 1.0);
  EXPECT_EQ(j["references"], 64);
  EXPECT_GT(j["sah_cost"].get<double>(), sahWithSplits);
  const fs::path mesh = gridMesh();
  r = run("build --mesh " + mesh.string() + " --builder median --sbvh-budget 3 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("warning: median ignores --sbvh-budget"), std::string::npos) << r.err;
}

TEST(CliOptions, IgnoredBinsAndCappedLeavesWarnAndTheJsonSaysWhatWasUsed) {
  const fs::path mesh = gridMesh();
  Result r = run("build --mesh " + mesh.string() + " --builder median --bins 16 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("warning: median ignores --bins"), std::string::npos) << r.err;
  json j = json::parse(r.out);
  ASSERT_EQ(j["warnings"].size(), 1u);
  EXPECT_EQ(j["leaf_size"], 4);

  r = run("build --mesh " + mesh.string() + " --builder embree --leaf-size 64 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("capped to 32"), std::string::npos) << r.err;
  j = json::parse(r.out);
  EXPECT_EQ(j["leaf_size"], 32);
  EXPECT_EQ(j["leaf_size_requested"], 64);
  EXPECT_LE(j["prims_per_leaf_max"].get<int>(), 32);

  // A builder that reads --bins: no warning.
  r = run("build --mesh " + mesh.string() + " --builder sah-binned --bins 16 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;
  EXPECT_TRUE(json::parse(r.out)["warnings"].empty());

  // render reports the same in its JSON.
  r = run("render " + mesh.string() + " --builder embree --leaf-size 40 --bins 8 --json --width 16 --height 16 "
          "--frames 1 --warmup 0");
  ASSERT_EQ(r.code, 0) << r.err;
  j = json::parse(r.out);
  EXPECT_EQ(j["leaf_size"], 32);
  EXPECT_EQ(j["warnings"].size(), 2u) << j["warnings"];
}

TEST(CliOptions, ReviewNamesTheOptionsEachBuilderIgnores) {
  bvhlab::BuildOptions o;
  o.bins = 16;
  o.sbvhAlpha = 1e-3f;
  o.plocRadius = 4;
  EXPECT_TRUE(bvhlab::reviewBuildOptions("sah-binned", bvhlab::BuildOptions{}).warnings.empty());
  EXPECT_EQ(bvhlab::reviewBuildOptions("median", o).warnings.size(), 3u);
  o.mortonSizeBits = 3;  // read by ploc and lbvh only
  EXPECT_EQ(bvhlab::reviewBuildOptions("median", o).warnings.size(), 4u);
  EXPECT_EQ(bvhlab::reviewBuildOptions("lbvh", o).warnings.size(), 3u);  // bins, alpha, radius
  o.mortonSizeBits = bvhlab::kMaxMortonSizeBits + 1;
  EXPECT_THROW(bvhlab::reviewBuildOptions("ploc", o), std::invalid_argument);
  o.mortonSizeBits = 0;
  EXPECT_EQ(bvhlab::reviewBuildOptions("sbvh", o).warnings.size(), 1u);        // ploc radius
  EXPECT_EQ(bvhlab::reviewBuildOptions("ploc", o).warnings.size(), 2u);        // bins, alpha
  EXPECT_EQ(bvhlab::reviewBuildOptions("sah-binned", o).warnings.size(), 2u);  // alpha, radius
  o = {};
  o.maxLeafSize = 200;
  EXPECT_EQ(bvhlab::reviewBuildOptions("embree-low", o).leafSize, bvhlab::kEmbreeMaxLeafSize);
  EXPECT_EQ(bvhlab::reviewBuildOptions("lbvh", o).leafSize, 200u);
  o.bins = 1;
  EXPECT_THROW(bvhlab::reviewBuildOptions("lbvh", o), std::invalid_argument);
  o = {};
  o.sbvhReferenceBudget = 3.0f;  // read by sbvh only
  EXPECT_TRUE(bvhlab::reviewBuildOptions("sbvh", o).warnings.empty());
  EXPECT_EQ(bvhlab::reviewBuildOptions("sah-binned", o).warnings.size(), 1u);
}

TEST(CliOptions, RenderSaysWhatItWrote) {
  const fs::path png = testDir() / "said.png";
  Result r = run("render " + scene("sphere.toml").string() + " -o " + png.string() +
                 " --width 32 --height 24 --frames 1 --warmup 0");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("wrote " + png.string()), std::string::npos) << r.out;
  // With --json the JSON owns stdout; the note goes to stderr.
  r = run("render " + scene("sphere.toml").string() + " -o " + png.string() +
          " --width 32 --height 24 --frames 1 --warmup 0 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NO_THROW(json::parse(r.out)) << r.out;
  EXPECT_NE(r.err.find("wrote " + png.string()), std::string::npos) << r.err;
}

TEST(CliOptions, HelpShowsDefaults) {
  Result r = run("render --help");
  ASSERT_EQ(r.code, 0);
  for (const char* d : {"--frames INT=5", "--builder TEXT=sah-binned", "--leaf-size INT=4", "--robust TEXT=watertight"})
    EXPECT_NE(r.out.find(d), std::string::npos) << d << "\n" << r.out;
  r = run("build --help");
  ASSERT_EQ(r.code, 0);
  EXPECT_NE(r.out.find("--leaf-size INT=4"), std::string::npos) << r.out;
}

TEST(CliOptions, JsonSaysWhetherAGpuRendered) {
  // OSMesa is Mesa's software path: never a GPU.
  Result r = run("render " + scene("sphere.toml").string() + " --width 16 --height 16 --frames 1 --warmup 0 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  json j = json::parse(r.out);
  EXPECT_EQ(j["gpu"], false) << j["renderer"];
  EXPECT_TRUE(bvhlab::isSoftwareRenderer(j["renderer"].get<std::string>())) << j["renderer"];

  r = run("render " + scene("sphere.toml").string() + " --width 16 --height 16 --frames 1 --warmup 0 --json "
          "--backend egl");
  if (r.code != 0 && r.err.find("egl:") != std::string::npos) BVHLAB_SKIP_OR_FAIL("no EGL here: " << r.err);
  ASSERT_EQ(r.code, 0) << r.err;
  j = json::parse(r.out);
  const bool software = bvhlab::isSoftwareRenderer(j["renderer"].get<std::string>());
  EXPECT_EQ(j["gpu"], !software) << j["renderer"];
  // The fallback is said out loud, and only then.
  EXPECT_EQ(r.err.find("found no GPU") != std::string::npos, software) << r.err;
  if (software) std::printf("EGL ran on %s: no GPU here, EGL and OSMesa are both llvmpipe\n",
                            j["renderer"].get<std::string>().c_str());
}

TEST(CliOptions, SoftwareRendererNames) {
  EXPECT_TRUE(bvhlab::isSoftwareRenderer("llvmpipe (LLVM 15.0.6, 256 bits)"));
  EXPECT_TRUE(bvhlab::isSoftwareRenderer("softpipe"));
  EXPECT_FALSE(bvhlab::isSoftwareRenderer("NVIDIA H200/PCIe/SSE2"));
  EXPECT_FALSE(bvhlab::isSoftwareRenderer("AMD Radeon RX 7900 XTX (radeonsi, navi31, LLVM 15.0.7, DRM 3.54)"));
}

}  // namespace
