// The command line's one error style (render/exit_status.hpp): every failure is "bvhlab: error: ..."
// on stderr naming the flag, file or key at fault, with exit status 2 for a usage error and 1 for a
// runtime failure; no CLI11 status (100 and up) reaches the shell, and --help still exits 0.
// None of these cases gets as far as a GL context.
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cli_run.hpp"

namespace {

using namespace bvhlab::clitest;

[[maybe_unused]] ::testing::Environment* const kRemoveTestDir = ::testing::AddGlobalTestEnvironment(new RemoveTestDir);

constexpr int kUsage = 2, kRuntime = 1;

// The status, the prefix on stderr's first line, and that the message names `named`; returns the result.
Result expectError(const std::string& args, int status, const std::string& named) {
  SCOPED_TRACE("bvhlab " + args);
  const Result r = run(args);
  EXPECT_EQ(r.code, status) << r.err;
  EXPECT_EQ(r.err.rfind("bvhlab: error: ", 0), 0u) << r.err;
  EXPECT_NE(r.err.find(named), std::string::npos) << "does not name '" << named << "': " << r.err;
  EXPECT_EQ(r.err.find("Run with --help"), std::string::npos) << "CLI11's own message leaked: " << r.err;
  return r;
}

// A one-triangle mesh: a valid input for every command that reads one.
std::string triangle() { return writeTemp("tri.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n").string(); }

TEST(CliErrors, UnknownCommandIsAUsageError) {
  expectError("rendr " + triangle(), kUsage, "unknown command 'rendr'");
  expectError("", kUsage, "no command given");
  expectError("--frobnicate render " + triangle(), kUsage, "--frobnicate");
}

// The commands `bvhlab --help` lists (the lines under "Subcommands:").
std::vector<std::string> listedCommands() {
  std::istringstream help(run("--help").out);
  std::vector<std::string> names;
  bool inList = false;
  for (std::string line; std::getline(help, line);) {
    if (line.rfind("Subcommands:", 0) == 0) {
      inList = true;
    } else if (inList) {
      std::istringstream words(line);
      std::string name;
      if (!(words >> name)) break;  // the blank line after the list
      names.push_back(name);
    }
  }
  return names;
}

// Every command --help lists, each with the arguments it requires, plus a flag none of them has.
TEST(CliErrors, UnknownFlagIsAUsageErrorInEveryCommand) {
  const std::string mesh = triangle(), dir = testDir().string();
  const std::map<std::string, std::string> required = {{"render", mesh},
                                                        {"trace", mesh},
                                                        {"measure", "group.json"},
                                                        {"build", "--mesh " + mesh},
                                                        {"run", "cfg.toml"},
                                                        {"merge", dir + " --out " + dir + "/merged"},
                                                        {"report", dir},
                                                        {"findings", dir},
                                                        {"view", mesh},
                                                        {"hard-cases", ""},
                                                        {"builders", ""},
                                                        {"kernels", ""},
                                                        {"layouts", ""}};
  const std::vector<std::string> names = listedCommands();
  EXPECT_GE(names.size(), required.size()) << "--help lists fewer commands than this test knows";
  for (const std::string& name : names) {
    const auto it = required.find(name);
    if (it == required.end()) {
      ADD_FAILURE() << "a command this test does not cover: " << name;
      continue;
    }
    const Result r = expectError(name + " " + it->second + " --frobnicate", kUsage, "--frobnicate");
    EXPECT_NE(r.err.find("bvhlab " + name + " --help"), std::string::npos) << "its help not named: " << r.err;
  }
}

TEST(CliErrors, BadFlagValueIsAUsageError) {
  const std::string mesh = triangle();
  expectError("render " + mesh + " --width abc", kUsage, "--width");           // CLI11 cannot convert it
  expectError("build --mesh " + mesh + " --leaf-size x", kUsage, "--leaf-size");
  expectError("render " + mesh + " --leaf-size 0", kUsage, "--leaf-size");      // refused after parsing
  expectError("build --mesh " + mesh + " --leaf-size 0", kUsage, "--leaf-size");
  expectError("trace " + mesh + " --layout nope", kUsage, "'nope'");
  expectError("render " + mesh + " --backend nope", kUsage, "'nope'");
  expectError("render " + mesh + " --width 0", kUsage, "--width");
  expectError("run cfg.toml --replicates 0", kUsage, "--replicates");           // a CLI11 range check
  expectError("run cfg.toml --shard 3", kUsage, "--shard");
  expectError("hard-cases --robust nope", kUsage, "'nope'");
}

TEST(CliErrors, MissingArgumentIsAUsageError) {
  expectError("render", kUsage, "input is required");
  expectError("build", kUsage, "--mesh is required");
  expectError("merge " + testDir().string(), kUsage, "--out is required");
  expectError("render " + triangle() + " --width", kUsage, "--width");  // a flag without its value
}

// The content of a file the user wrote: an unknown key, a wrong type, a path in it that names no file.
TEST(CliErrors, BadConfigOrSceneKeyIsAUsageError) {
  triangle();
  const fs::path unknownKey = writeTemp("unknown_key.toml", "[render]\nwidht = 3\n[axes]\nscenes = \"tri.off\"\n");
  expectError("run " + unknownKey.string() + " --out " + (testDir() / "o1").string(), kUsage,
              "unknown_key.toml:2: render.widht");
  const fs::path badValue = writeTemp("bad_value.toml", "[axes]\nscenes = \"tri.off\"\nleaf_sizes = \"many\"\n");
  expectError("run " + badValue.string() + " --out " + (testDir() / "o2").string(), kUsage, "axes.leaf_sizes");
  const fs::path badAxis = writeTemp("bad_axis.toml", "[axes]\nscenes = \"tri.off\"\nbogus_axis = 1\n");
  expectError("run " + badAxis.string() + " --out " + (testDir() / "o3").string(), kUsage, "axes.bogus_axis");
  const fs::path noMesh = writeTemp("no_mesh.toml", "[axes]\nscenes = \"absent.off\"\n");
  expectError("run " + noMesh.string() + " --out " + (testDir() / "o4").string(), kUsage, "absent.off");
  const fs::path scene = writeTemp("scene_key.toml", "[camera]\neye = [0,0,5]\nfocus = 3\n");
  expectError("render " + scene.string(), kUsage, "focus");
  const fs::path mesh = writeTemp("truncated.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n");
  expectError("build --mesh " + mesh.string(), kUsage, "truncated.off");
  EXPECT_FALSE(fs::exists(testDir() / "o1")) << "a refused config wrote its output directory";
}

// A file given on the command line that is not there or cannot be written is a runtime failure.
TEST(CliErrors, MissingOrUnwritableFileIsARuntimeFailure) {
  const std::string missing = (testDir() / "absent").string();
  expectError("render " + missing + ".obj", kRuntime, missing + ".obj");
  expectError("render " + missing + ".toml", kRuntime, missing + ".toml");
  expectError("trace " + missing + ".off", kRuntime, missing + ".off");
  expectError("build --mesh " + missing + ".off", kRuntime, missing + ".off");
  expectError("run " + missing + ".toml", kRuntime, missing + ".toml");
  expectError("measure " + missing + ".json", kRuntime, missing + ".json");
  expectError("report " + missing, kRuntime, missing);
  expectError("render " + triangle() + " --camera-path " + missing + ".txt", kRuntime, missing + ".txt");
  // -o under a regular file: the directory cannot be made (rendered by the C++ mirror: no GL context).
  const std::string mesh = triangle();
  expectError("render " + mesh + " --cpu --width 8 --height 8 --frames 1 --warmup 0 -o " + mesh + "/image.png",
              kRuntime, mesh + "/image.png");
}

TEST(CliErrors, HelpAndVersionExitZeroAndHelpStatesTheRule) {
  const Result help = run("--help");
  EXPECT_EQ(help.code, 0) << help.err;
  EXPECT_TRUE(help.err.empty()) << help.err;
  EXPECT_NE(help.out.find("bvhlab: error: ..."), std::string::npos) << help.out;
  EXPECT_NE(help.out.find("2 usage error"), std::string::npos) << help.out;
  EXPECT_NE(help.out.find("1 runtime failure"), std::string::npos) << help.out;
  for (const char* args : {"-h", "render --help", "run --help", "layouts --help", "--version"}) {
    const Result r = run(args);
    EXPECT_EQ(r.code, 0) << args << ": " << r.err;
    EXPECT_FALSE(r.out.empty()) << args;
  }
  EXPECT_NE(run("render --help").out.find("--width"), std::string::npos) << "render --help is not render's help";
}

}  // namespace
