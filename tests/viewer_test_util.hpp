// Shared by the viewer's tests (test_viewer.cpp end to end, test_viewer_parts.cpp in process): this
// test process's scratch directory and camera equality.
#pragma once
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>

#include <gtest/gtest.h>

#include "cli_run.hpp"
#include "datasets/scene.hpp"
#include "render/viewer.hpp"
#include "require.hpp"

namespace bvhlab::testing {

// cli_run.hpp's scratch directory of this process, created on first use and removed when the
// program ends (CTest runs each case in a process of its own, so each would otherwise leave one
// behind in /tmp).
[[maybe_unused]] inline ::testing::Environment* const kRemoveViewerTestDir =
    ::testing::AddGlobalTestEnvironment(new clitest::RemoveTestDir);
inline std::filesystem::path tempDir() {
  std::filesystem::create_directories(clitest::testDir());
  return clitest::testDir();
}

// "xvfb-run -a " when there is no display, "" with one; nullopt (skip) when neither works.
inline std::optional<std::string> displayPrefix() {
  const char* d = std::getenv("DISPLAY");
  if (d && *d) return std::string();
  if (std::system("command -v xvfb-run >/dev/null 2>&1") == 0) return std::string("xvfb-run -a ");
  return std::nullopt;
}

// Each reason is absent where setup.sh installed the packages: a failure under BVHLAB_REQUIRE_ALL=1.
#define REQUIRE_VIEWER(prefix)                                                                             \
  if (!viewerAvailable()) BVHLAB_SKIP_OR_FAIL("built without GLFW/Dear ImGui (BVHLAB_VIEWER unset in CMake)"); \
  if (std::system((std::string(BVHLAB_BINARY) + " view --help >/dev/null 2>&1").c_str()) != 0)             \
    BVHLAB_SKIP_OR_FAIL("this bvhlab has no `view` subcommand");                                           \
  std::optional<std::string> prefix = ::bvhlab::testing::displayPrefix();                                  \
  if (!prefix) BVHLAB_SKIP_OR_FAIL("no DISPLAY and no xvfb-run (apt-get install xvfb)")

inline void expectCameraEq(const Camera& a, const Camera& b) {
  EXPECT_EQ(a.eye, b.eye);
  EXPECT_EQ(a.target, b.target);
  EXPECT_EQ(a.up, b.up);
  EXPECT_EQ(a.fovDeg, b.fovDeg);
}

}  // namespace bvhlab::testing
