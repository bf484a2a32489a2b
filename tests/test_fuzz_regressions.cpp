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

#include "datasets/image_io.hpp"
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

// The seeds of the image and JSON targets are valid inputs: each must parse to a well-formed result
// (an InputError here means the harness never gets past the reader's first check, and the fuzzer
// would mutate from a dead end). Every target has at least one.
class FuzzSeeds : public ::testing::TestWithParam<std::string> {};

TEST_P(FuzzSeeds, EverySeedParses) {
  const std::string parser = GetParam();
  ScratchDir dir;
  std::error_code ec;
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(fs::path(BVHLAB_SOURCE_DIR) / "tests/fuzz/seeds" / parser, ec))
    if (e.is_regular_file()) files.push_back(e.path());
  ASSERT_FALSE(files.empty()) << "no seeds for " << parser;
  for (const fs::path& file : files) {
    SCOPED_TRACE(file.string());
    EXPECT_NO_THROW(fuzz::parseAs(parser, readBytes(file), dir.path));
  }
}

INSTANTIATE_TEST_SUITE_P(ImageAndJsonTargets, FuzzSeeds,
                         ::testing::Values("png", "jpeg", "exr", "hdr", "group", "merge"),
                         [](const ::testing::TestParamInfo<std::string>& i) { return i.param; });

// Every folder is a known parser, so a misspelt folder cannot silently replay nothing.
// The EXR whose tiles were larger than its image is refused by name, before any pixel is read (not
// merely read by a machine with the memory for it).
TEST(FuzzRegressionsExr, TilesLargerThanTheImageAreRefusedNamingBothSizes) {
  const fs::path file = kRegressions / "exr/tiles-of-8257552x16-in-a-20x18-image-allocated-14gb.exr";
  try {
    loadImage(file);
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("tiles larger than the image (8257552x16 tiles of a 20x18 image)"),
              std::string::npos)
        << e.what();
  }
}

// OpenEXR's C++ reader allocates an attribute at its declared size: 1.9 GB for this 368-byte file before
// it failed. The headers are walked first, and the attribute is refused by name.
TEST(FuzzRegressionsExr, AnAttributeLargerThanTheFileIsRefusedNamingIt) {
  const fs::path file = kRegressions / "exr/string-attribute-declaring-1.8gb-in-a-368-byte-file.exr";
  ASSERT_EQ(fs::file_size(file), 368u);
  try {
    loadImage(file);
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("OpenEXR header: attribute 'capDate' (string) declares"), std::string::npos)
        << e.what();
  }
}

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
  // assimp falls back to its COLLADA reader when the glTF reader refuses the content: a .gltf must now
  // be glTF JSON before assimp sees it, so the COLLADA inside never reaches that reader.
  const std::string named = loadError(kRegressions / "gltf/collada-instance-chain-named-gltf.gltf");
  EXPECT_NE(named.find("glTF: not valid JSON"), std::string::npos) << named;
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

// The fuzz_glb findings: files assimp's glTF 2 reader refuses while probing them (then every other
// reader is tried, and two read past the buffer), or whose JSON chunk length made it allocate
// gigabytes. Each is refused by the GLB and glTF JSON checks, naming what is wrong; a well-formed file
// written by assimp still loads (AssimpFormats.BinaryFormatsWrittenByAssimpReadBack).
TEST(ImporterGuards, GlbContainerAndGltfJsonAreCheckedBeforeAssimp) {
  const fs::path glb = kRegressions / "glb";
  std::string e = loadError(glb / "fuzzer-found-json-chunk-past-the-end-overreads-in-another-reader.glb");
  EXPECT_NE(e.find("binary glTF header length 1932 but the file has 98 bytes"), std::string::npos) << e;
  e = loadError(glb / "fuzzer-found-bad-version-overreads-in-another-reader.glb");
  EXPECT_NE(e.find("binary glTF version 126627839 (only version 2 is read)"), std::string::npos) << e;

  ScratchDir dir;
  auto le32 = [](uint32_t v) { return std::string{char(v), char(v >> 8), char(v >> 16), char(v >> 24)}; };
  const std::string json = R"({"asset":{"version":"2.0"}})";  // 27 bytes, padded to 28
  auto writeGlb = [&](const std::string& name, uint32_t jsonLength, const std::string& tail) {
    const std::string body = le32(jsonLength) + "JSON" + json + " " + tail;
    std::ofstream(dir.path / name, std::ios::binary) << "glTF" << le32(2) << le32(uint32_t(12 + body.size())) << body;
    return loadError(dir.path / name);
  };
  // A JSON chunk that claims 4 GB (assimp 5.2.5 resizes a buffer to it first).
  e = writeGlb("huge-json.glb", 0xFFFFFFF0u, "");
  EXPECT_NE(e.find("binary glTF JSON chunk of 4294967280 bytes but 28 follow its header"), std::string::npos) << e;
  // A BIN chunk that claims more than the file holds (assimp allocates its length).
  e = writeGlb("huge-bin.glb", 27, le32(1u << 30) + std::string("BIN\0", 4) + "abcd");
  EXPECT_NE(e.find("binary glTF BIN chunk of 1073741824 bytes but 4 follow its header"), std::string::npos) << e;
  e = writeGlb("bad-bin-type.glb", 27, le32(4) + "XYZ!" + "abcd");
  EXPECT_NE(e.find("the second chunk is not of type BIN"), std::string::npos) << e;
  // The JSON itself: not an object, no asset version 2, nested past the bound, not JSON at all.
  auto writeGltf = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir.path / name) << text;
    return loadError(dir.path / name);
  };
  e = writeGltf("array.gltf", "[1, 2]");
  EXPECT_NE(e.find("glTF: the JSON is not an object"), std::string::npos) << e;
  e = writeGltf("v1.gltf", R"({"asset": {"version": "1.0"}})");
  EXPECT_NE(e.find("asset.version is not \"2.x\""), std::string::npos) << e;
  e = writeGltf("deep.gltf", R"({"asset": {"version": "2.0"}, "extras": )" + std::string(300, '[') + std::string(300, ']') + "}");
  EXPECT_NE(e.find("JSON nested deeper than 256 levels"), std::string::npos) << e;
  e = writeGltf("prose.gltf", "glTF is a format");
  EXPECT_NE(e.find("glTF: not valid JSON"), std::string::npos) << e;
  // A LINE_LOOP whose first segment assimp drops (an index past the vertices; or a loop of 1 vertex):
  // assimp 5.2.5 then closes the loop through a null pointer. The fuzzer's .glb (index in its BIN
  // chunk), and .gltf files with the indices in a buffer file beside them and in a data: URI.
  e = loadError(glb / "fuzzer-found-line-loop-index-past-vertices-segv.glb");
  EXPECT_NE(e.find("meshes[0].primitives[0]: a LINE_LOOP whose index 0 is 63 but it has 4 vertices"), std::string::npos) << e;
  std::ofstream(dir.path / "idx.bin", std::ios::binary) << le32(7) << le32(1);
  const std::string loop = R"({"asset": {"version": "2.0"}, "buffers": [{"uri": "URI", "byteLength": 8}],
      "bufferViews": [{"buffer": 0, "byteLength": 8}],
      "accessors": [{"bufferView": 0, "componentType": 5125, "count": 2, "type": "SCALAR"},
                    {"componentType": 5126, "count": COUNT, "type": "VEC3"}],
      "meshes": [{"primitives": [{"mode": 2, "attributes": {"POSITION": 1}INDICES}]}]})";
  auto loopFile = [&](const std::string& uri, const std::string& count, const std::string& indices) {
    std::string t = loop;
    for (const auto& [key, value] : {std::pair<std::string, std::string>{"URI", uri}, {"COUNT", count}, {"INDICES", indices}})
      t.replace(t.find(key), key.size(), value);
    return t;
  };
  e = writeGltf("loop-file.gltf", loopFile("idx.bin", "4", R"(, "indices": 0)"));
  EXPECT_NE(e.find("glTF: meshes[0].primitives[0]: a LINE_LOOP whose index 0 is 7 but it has 4 vertices"), std::string::npos) << e;
  e = writeGltf("loop-data-uri.gltf", loopFile("data:application/octet-stream;base64,AAAAAAEAAAA=", "4", R"(, "indices": 0)"));
  EXPECT_NE(e.find("a LINE_LOOP whose index 0 cannot be read"), std::string::npos) << e;
  e = writeGltf("loop-one-vertex.gltf", loopFile("idx.bin", "1", ""));
  EXPECT_NE(e.find("a LINE_LOOP of 1 vertices (needs 2)"), std::string::npos) << e;
  // A fan without attributes (the fuzzer's third file): 0 - 2 faces, in unsigned arithmetic.
  e = loadError(glb / "fuzzer-found-fan-of-0-vertices-allocates-64gb.glb");
  EXPECT_NE(e.find("meshes[0].primitives[0]: a TRIANGLE_FAN of 0 vertices (needs 3)"), std::string::npos) << e;
  // Without POSITION (the fuzzer's second file: a misspelt attribute name) the loop has 0 vertices.
  e = loadError(glb / "fuzzer-found-line-loop-without-position-segv.glb");
  EXPECT_NE(e.find("a LINE_LOOP whose index 0 is 0 but it has 0 vertices"), std::string::npos) << e;
  // Within range, the loop passes the check and assimp reads it (the file has no triangles).
  e = writeGltf("loop-ok.gltf", loopFile("idx.bin", "8", R"(, "indices": 0)"));
  EXPECT_EQ(e.find("LINE_LOOP"), std::string::npos) << e;
  e = writeGltf("loop-bad-member.gltf", loopFile("idx.bin", "\"four\"", R"(, "indices": 0)"));
  EXPECT_NE(e.find("glTF: malformed mesh, accessor or buffer"), std::string::npos) << e;
  // Brackets inside strings do not count as nesting, and a NUL ends the text as it does for assimp.
  e = writeGltf("strings.gltf", R"({"asset": {"version": "2.0", "generator": ")" + std::string(300, '[') + "\"}}" +
                                    std::string(1, '\0') + "garbage");
  EXPECT_EQ(e.find("JSON"), std::string::npos) << e;
}

// Peak resident memory of this process so far (VmHWM, /proc/self/status), in bytes; 0 if unknown.
namespace {
uint64_t peakResidentBytes() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::stoull(line.substr(6)) * 1024;  // "VmHWM:  1234 kB"
  return 0;
}
}  // namespace

// A 40-byte Radiance HDR file whose header claims 16000 x 16000 pixels: loadImage once decoded the
// whole image into one buffer sized from the header (3 GB allocated and zeroed, 18 s, before the
// decoder found no data). Decoded in bands now, it fails at the first band. The bound: the band is
// 4 MiB of floats and the decoder's row buffers less; the old path added 3 GB to the peak.
TEST(ImageGuards, AHeaderClaimingHugeSizeCostsWhatTheFileHolds) {
  const fs::path file = kRegressions / "hdr/header-claims-16000x16000-decoded-whole-took-3gb.hdr";
  const uint64_t before = peakResidentBytes();
  ASSERT_GT(before, 0u) << "no VmHWM in /proc/self/status";
  std::string error = "(loaded)";
  try {
    loadImage(file);
  } catch (const InputError& e) {
    error = e.what();
  }
  EXPECT_NE(error.find(file.string() + ": cannot decode image"), std::string::npos) << error;
  EXPECT_LT(peakResidentBytes(), before + (uint64_t(256) << 20)) << "peak resident memory grew past 256 MiB";
}

// A run record nested 200,000 arrays deep (400 KB, written here rather than kept as a file):
// nlohmann::json parses it without recursion but copies and prints it recursively, and `merge`
// crashed with a stack overflow (SIGSEGV). Now the record is refused when read (nested deeper than
// kMaxJsonDepth) and, like any unreadable record, ignored with a warning: its run counts as pending.
TEST(SweepGuards, ADeeplyNestedRunRecordIsIgnoredNotACrash) {
  ScratchDir dir;
  const std::string seed = readBytes(fs::path(BVHLAB_SOURCE_DIR) / "tests/fuzz/seeds/merge/tiny-sweep-3-runs.txt");
  const size_t status = seed.find("\"status\": \"ok\"");
  ASSERT_NE(status, std::string::npos);
  const int depth = 200000;
  const std::string deep = seed.substr(0, status) + "\"deep\": " + std::string(depth, '[') + std::string(depth, ']') +
                           ", " + seed.substr(status);
  fuzz::writeSweepDir(deep, dir.path / "in");
  const nlohmann::json summary = mergeSweeps({dir.path / "in"}, dir.path / "out", false);
  EXPECT_EQ(summary.at("planned"), 3);
  EXPECT_EQ(summary.at("ok"), 2);
  EXPECT_EQ(summary.at("pending"), 1);
}

TEST(ImporterGuards, AZipArchiveIsNotReadAsAModel) {
  ScratchDir dir;
  const fs::path zip = dir.path / "packed.glb";
  std::ofstream(zip, std::ios::binary) << std::string("PK\x03\x04", 4) << std::string(60, '\0');
  EXPECT_NE(loadError(zip).find("a zip archive"), std::string::npos) << loadError(zip);
}

INSTANTIATE_TEST_SUITE_P(Parsers, FuzzRegressions, ::testing::ValuesIn(fuzz::parserNames()),
                         [](const ::testing::TestParamInfo<std::string>& i) { return i.param; });
