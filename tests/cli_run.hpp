// Running the bvhlab binary from a test: exit code, stdout and stderr captured, one scratch directory
// per test process (CTest runs the cases of a file in parallel processes, which must not share files).
#pragma once
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <sys/wait.h>
#include <unistd.h>  // getpid

#include <gtest/gtest.h>

namespace bvhlab::clitest {

namespace fs = std::filesystem;

struct Result {
  int code;
  std::string out, err;
};

inline fs::path testDir() {
  static const fs::path dir = fs::temp_directory_path() / ("bvhlab_cli_test_" + std::to_string(::getpid()));
  return dir;
}

// Removes testDir() when the test program ends.
struct RemoveTestDir : ::testing::Environment {
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(testDir(), ec);
  }
};

// `bvhlab ARGS` (ARGS as a shell would split them), after `prefix` (e.g. "xvfb-run -a ").
inline Result run(const std::string& args, const std::string& prefix = "") {
  fs::path dir = testDir();
  fs::create_directories(dir);
  fs::path out = dir / "stdout", err = dir / "stderr";
  std::string cmd = prefix + BVHLAB_BINARY + " " + args + " >" + out.string() + " 2>" + err.string();
  int status = std::system(cmd.c_str());
  auto slurp = [](const fs::path& p) {
    std::ifstream in(p);
    return std::string((std::istreambuf_iterator<char>(in)), {});
  };
  return {WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status), slurp(out), slurp(err)};
}

inline fs::path scene(const std::string& name) { return fs::path(BVHLAB_SOURCE_DIR) / "datasets/scenes" / name; }

inline fs::path writeTemp(const std::string& name, const std::string& text) {
  fs::path p = testDir() / name;
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
  return p;
}

}  // namespace bvhlab::clitest
