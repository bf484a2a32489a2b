// Replays every file under tests/fuzz/regressions/PARSER/ through that parser (tests/fuzz/parsers.hpp,
// the same entry points the libFuzzer targets call). Each file is an input that once crashed, hung,
// ran out of memory or tripped ASan/UBSan; now it must parse to a well-formed result or be rejected
// with an InputError (another std::runtime_error is accepted, as by the fuzz targets). Runs in the normal Release build (no clang, no sanitizers needed).
//
// A file whose name ends in ".pending" reproduces a bug that is not fixed yet (its README line says
// where): it is listed, not replayed, so an unfixed hang or OOM cannot take the suite down. Drop the
// suffix in the commit that fixes the bug.
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "datasets/mesh_io.hpp"
#include "fuzz/parsers.hpp"

namespace fs = std::filesystem;
using namespace bvhlab;

namespace {

const fs::path kRegressions = fs::path(BVHLAB_SOURCE_DIR) / "tests/fuzz/regressions";

std::string readBytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<fs::path> filesOf(const std::string& parser) {
  std::vector<fs::path> files;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(kRegressions / parser, ec))
    if (e.is_regular_file() && e.path().filename() != "README.md") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  return files;
}

struct ScratchDir {
  fs::path path = fs::temp_directory_path() / ("bvhlab-fuzzreg-" + std::to_string(::getpid()));
  ScratchDir() { fs::create_directories(path); }
  ~ScratchDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

}  // namespace

class FuzzRegressions : public ::testing::TestWithParam<std::string> {};

TEST_P(FuzzRegressions, EveryFileParsesOrIsAnInputError) {
  const std::string parser = GetParam();
  ScratchDir dir;
  int replayed = 0;
  std::vector<std::string> pending;
  for (const fs::path& file : filesOf(parser)) {
    if (file.extension() == ".pending") {
      pending.push_back(file.filename().string());
      continue;
    }
    SCOPED_TRACE(file.string());
    ++replayed;
    try {
      fuzz::parseAs(parser, readBytes(file), dir.path);
    } catch (const InputError& e) {
      const std::string msg = e.what();
      EXPECT_EQ(msg.find('\n'), std::string::npos) << "an InputError is one line: " << msg;
    } catch (const std::runtime_error&) {
      // accepted, as by the fuzz targets (fuzz_common.hpp): a clean, reported error
    } catch (const std::exception& e) {
      ADD_FAILURE() << "neither an InputError nor a std::runtime_error: " << e.what();
    }
  }
  std::string list;
  for (const std::string& p : pending) list += " " + p;
  if (!pending.empty())
    std::printf("%s: %zu pending reproducer(s) not replayed (bugs not fixed yet):%s\n", parser.c_str(),
                pending.size(), list.c_str());
  RecordProperty("replayed", replayed);
}

// Every folder is a known parser, so a misspelt folder cannot silently replay nothing.
TEST(FuzzRegressionsLayout, FoldersNameKnownParsers) {
  const auto& names = fuzz::parserNames();
  for (const auto& e : fs::directory_iterator(kRegressions)) {
    if (e.is_directory()) {
      EXPECT_NE(std::find(names.begin(), names.end(), e.path().filename().string()), names.end()) << e.path();
    }
  }
}

// The guards in front of assimp (datasets/mesh_io_prechecks.cpp) refuse with their own message, before
// assimp expands anything: each of these files crashed assimp (cycle: stack overflow) or would have
// made it allocate 2^40 nodes. A model that instances nodes within the limit still loads.
namespace {
std::string loadError(const fs::path& file) {
  try {
    loadMesh(file);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(loaded)";
}
}  // namespace

TEST(ImporterGuards, ColladaInstancingIsBoundedBeforeAssimp) {
  const fs::path dae = kRegressions / "dae";
  EXPECT_NE(loadError(dae / "instance-node-chain-doubles-40-times.dae").find("(kMaxColladaNodes)"), std::string::npos);
  EXPECT_NE(loadError(dae / "instance-node-cycle.dae").find("<instance_node> cycle: node 'n0'"), std::string::npos);
  // assimp falls back to its COLLADA reader when the glTF reader refuses the content.
  EXPECT_NE(loadError(kRegressions / "gltf/collada-instance-chain-named-gltf.gltf").find("(kMaxColladaNodes)"),
            std::string::npos);
  // Two instances of a two-triangle quad, one of them through a nested node.
  const Mesh m = loadMesh(fs::path(BVHLAB_SOURCE_DIR) / "tests/fuzz/seeds/dae/instanced_quad.dae");
  EXPECT_EQ(m.triangles.size(), 4u);
}

// The fuzz_ac findings. A line surface without refs, on which assimp 5.2.5 writes past a face array
// (the damage shows only in some heaps, so the file alone need not crash under ASan: the guard's
// message is checked): the fuzzer's file (refused first at its out-of-range 'mat') and the same file
// with that index fixed, which valgrind showed writing past the array. And a 'kids' count that assimp
// reads where our pass once skipped it as a row of 'refs'.
TEST(ImporterGuards, Ac3dFindingsAreRefusedBeforeAssimp) {
  const fs::path ac = kRegressions / "ac";
  std::string e = loadError(ac / "assimp-ac3d-line-surface-without-refs-bad-free.ac");
  EXPECT_NE(e.find(":34: mat 1: the file defines 1 MATERIAL(s)"), std::string::npos) << e;
  e = loadError(ac / "assimp-ac3d-line-surface-without-refs-writes-past-faces.ac");
  EXPECT_NE(e.find(":39: SURF without a 'refs' line"), std::string::npos) << e;
  e = loadError(ac / "fuzzer-found-kids-count-inside-refs-rows-reserves-212gb.ac");
  EXPECT_NE(e.find(":23: kids 666666666666 but only 16 non-blank lines follow"), std::string::npos) << e;
}

TEST(ImporterGuards, AZipArchiveIsNotReadAsAModel) {
  ScratchDir dir;
  const fs::path zip = dir.path / "packed.glb";
  std::ofstream(zip, std::ios::binary) << std::string("PK\x03\x04", 4) << std::string(60, '\0');
  EXPECT_NE(loadError(zip).find("a zip archive"), std::string::npos) << loadError(zip);
}

INSTANTIATE_TEST_SUITE_P(Parsers, FuzzRegressions, ::testing::ValuesIn(fuzz::parserNames()),
                         [](const ::testing::TestParamInfo<std::string>& i) { return i.param; });
