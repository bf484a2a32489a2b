// Shared by the viewer's tests (test_viewer.cpp end to end, test_viewer_parts.cpp in process): this
// test process's scratch directory and camera equality.
#pragma once
#include <filesystem>

#include <gtest/gtest.h>

#include "cli_run.hpp"
#include "datasets/scene.hpp"

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

inline void expectCameraEq(const Camera& a, const Camera& b) {
  EXPECT_EQ(a.eye, b.eye);
  EXPECT_EQ(a.target, b.target);
  EXPECT_EQ(a.up, b.up);
  EXPECT_EQ(a.fovDeg, b.fovDeg);
}

}  // namespace bvhlab::testing
