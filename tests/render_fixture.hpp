// Shared helpers for tests that render: one GL context per test process, scene discovery, and
// image comparison with the tolerance the project states for GLSL vs the C++ mirror.
#pragma once
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <map>
#include <vector>

#include <unistd.h>  // getpid

#include <gtest/gtest.h>

#include "datasets/scene_io.hpp"
#include "render/gl_context.hpp"
#include "require.hpp"
#include "render/gpu_renderer.hpp"
#include "shaders/tracer.hpp"
#include "traversal/kernels.hpp"

namespace bvhlab::test {

inline std::filesystem::path sourceDir() { return BVHLAB_SOURCE_DIR; }

inline GlContext& glContext() {
  static std::unique_ptr<GlContext> ctx = createContext(Backend::OSMesa);
  return *ctx;
}

inline std::vector<std::filesystem::path> shippedScenes() {
  std::vector<std::filesystem::path> out;
  for (const auto& e : std::filesystem::directory_iterator(sourceDir() / "datasets/scenes"))
    if (e.path().extension() == ".toml") out.push_back(e.path());
  std::sort(out.begin(), out.end());
  return out;
}

// Scenes that need fetched data are skipped with a message when the cache is missing.
inline bool datasetsPresent() { return std::filesystem::exists(sourceDir() / "datasets/cache/meshes/bunny00.off"); }
// BVHLAB_REQUIRE_ALL=1 (CI) makes the skip a failure (tests/require.hpp).
#define BVHLAB_REQUIRE_DATASETS()                                                                \
  if (!bvhlab::test::datasetsPresent())                                                          \
  BVHLAB_SKIP_OR_FAIL("datasets missing: run `bash datasets/fetch.sh` (or `bash setup.sh test`)")

// Default tracer options for a prepared scene: its max depth, a BVH stack sized to its tree.
inline ShaderOptions tracerOptions(const PreparedScene& p) {
  ShaderOptions o;
  o.maxDepth = p.scene.settings.maxDepth;
  o.bvhStackSize = stackSizeFor(std::max<uint32_t>(1, p.packed.depth));
  return o;
}

// A scene written as TOML text (docs/scene-format.md), loaded through the real loader and prepared
// with the default builder. The file goes to a per-process temp folder and is removed again.
inline std::unique_ptr<PreparedScene> prepareToml(const std::string& toml, const std::string& name = "scene") {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("bvhlab_render_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::filesystem::path file = dir / (name + ".toml");
  { std::ofstream(file) << toml; }
  Scene s = loadScene(file);
  std::error_code ec;
  std::filesystem::remove_all(dir, ec);
  return prepareScene(std::move(s), "sah-binned", BuildOptions{});
}

struct Rendered {
  std::vector<uint8_t> rgba;
  std::vector<glm::uvec4> stats;
  std::string source;
  std::vector<uint32_t> boxTests;  // per pixel, with countStats
};

inline FrameOptions smallFrame(const Scene& s, int width, int height) {
  FrameOptions f;
  f.width = width;
  f.height = height;
  f.camera = s.camera;
  f.exposure = s.settings.exposure;
  return f;
}

inline Rendered renderGpu(const PreparedScene& p, const ShaderOptions& o, const FrameOptions& f) {
  glContext();
  GpuRenderer r(p, o, f);
  r.drawFrame();
  Rendered out{r.readColor(), {}, r.shader().source, {}};
  if (o.countStats) out.stats = r.readStats(), out.boxTests = r.readBoxTests();
  return out;
}

struct ImageDiff {
  double meanAbs = 0.0;       // mean |a-b| over RGB channels, in 8-bit steps
  double within3 = 0.0;       // fraction of pixels whose max channel difference <= 3
  int maxDiff = 0;
};

inline ImageDiff compareRgba(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b) {
  ImageDiff d;
  size_t pixels = a.size() / 4, ok = 0;
  double sum = 0.0;
  for (size_t i = 0; i < pixels; ++i) {
    int m = 0;
    for (int c = 0; c < 3; ++c) {
      int diff = std::abs(int(a[4 * i + c]) - int(b[4 * i + c]));
      sum += diff;
      m = std::max(m, diff);
    }
    d.maxDiff = std::max(d.maxDiff, m);
    ok += m <= 3;
  }
  d.meanAbs = sum / double(3 * pixels);
  d.within3 = double(ok) / double(pixels);
  return d;
}

}  // namespace bvhlab::test
