// `bvhlab view` playing an animated scene (render/viewer_clip.cpp), end to end under an X server: the
// clip advances one frame per scripted frame, the update strategy switches live (U, `set update`),
// Space pauses, and every clip frame's tree is the one the strategy gives in process (its SAH, exactly);
// and the refusals (static scene, bad spec, a clip frame past the clip).
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "builders/update.hpp"
#include "cli_run.hpp"
#include "datasets/animation.hpp"
#include "datasets/image_io.hpp"
#include "datasets/scene_io.hpp"
#include "layout/layout.hpp"
#include "viewer_test_util.hpp"

namespace bvhlab {
namespace {

using clitest::writeTemp;
using nlohmann::json;

// A terrain patch (2000 triangles) flying apart from frame 1 (t = 0.1 s): every frame rearranges it,
// so refit and rebuild give different trees from the first update on.
std::string explodingScene() {
  return writeTemp("explode.toml",
                   "[clip]\nframes = 12\nfps = 10\n"
                   "[camera]\neye = [0, 2.5, 4]\ntarget = [0, 0, 0]\n[render]\nwidth = 48\nheight = 32\n"
                   "[[object]]\nkind = \"mesh\"\ngenerate = \"terrain\"\ntriangles = 2000\nfit = 2\n"
                   "[object.deform]\nkind = \"explode\"\nspeed = 2\njitter = 0.5\nstart = 0.05\n")
      .string();
}

clitest::Result view(const std::string& prefix, const std::string& args) {
  return clitest::run("view " + args + " --width 48 --height 32 --no-overlay", prefix);
}

// The SAH the strategy `spec` gives at each of `frames` (clip frames, visited in order) starting
// fresh at the first, as the viewer's playback makes it.
std::vector<double> strategySah(const Scene& loaded, const std::string& spec, const std::vector<int>& frames) {
  UpdateOptions options;  // the viewer's defaults: sah-binned, leaf size 4
  std::unique_ptr<UpdateStrategy> strategy = makeUpdateStrategy(spec, options);
  std::vector<double> sah;
  Scene scene = loaded;
  for (int f : frames) {
    setFrame(scene, f);
    const TriangleSoup soup = gatherTriangles(scene);
    strategy->update(FrameTriangles{soup.v0, soup.v1, soup.v2});
    sah.push_back(computeStats(strategy->tree(), options.build.cost).sahCost);
  }
  return sah;
}

TEST(ViewClip, PlaysTheClipWithTheStrategySwitchedLiveAndPauses) {
  REQUIRE_VIEWER(prefix);
  const std::string scene = explodingScene();
  // Frames 0-2 rebuild (the default), frame 3 switches to refit (a fresh strategy: it builds there),
  // frame 5 presses U (refit -> the next of the U list: refit+rebuild:4), frame 7 pauses.
  const std::string script =
      writeTemp("play.txt", "3 set update refit\n5 key U\n7 key SPACE\n").string();
  const clitest::Result r = view(*prefix, scene + " --script " + script + " --frames 9 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["clip_frames"], 12);
  EXPECT_EQ(j["update"], "refit+rebuild:4");
  EXPECT_FALSE(j["playing"].get<bool>());
  // Paused at frame 7 before it advanced: clip frames 0..6 were made, and frames 7 and 8 show frame 6.
  const json& clip = j["clip"];
  ASSERT_EQ(clip.size(), 7u) << clip.dump();
  EXPECT_EQ(j["clip_frame"], 6);
  const std::vector<std::string> specs = {"rebuild", "rebuild", "rebuild", "refit", "refit", "refit+rebuild:4",
                                          "refit+rebuild:4"};
  const std::vector<bool> rebuilt = {true, true, true, true, false, true, false};
  for (size_t i = 0; i < clip.size(); ++i) {
    SCOPED_TRACE(i);
    EXPECT_EQ(clip[i]["clip_frame"], int(i));
    EXPECT_EQ(clip[i]["update"], specs[i]);
    EXPECT_EQ(clip[i]["rebuilt"], rebuilt[i]);
    for (const char* k : {"update_ms", "upload_ms", "trace_ms"}) {
      ASSERT_TRUE(clip[i].contains(k)) << k;
      EXPECT_GE(clip[i][k].get<double>(), 0.0) << k;
    }
  }
  // The trees are the strategies' own: the same SAH as in process, frame by frame.
  const Scene loaded = loadInput(scene);
  const std::vector<double> rebuild = strategySah(loaded, "rebuild", {0, 1, 2});
  const std::vector<double> refit = strategySah(loaded, "refit", {3, 4});
  const std::vector<double> every4 = strategySah(loaded, "refit+rebuild:4", {5, 6});
  const std::vector<double> expected = {rebuild[0], rebuild[1], rebuild[2], refit[0], refit[1], every4[0], every4[1]};
  for (size_t i = 0; i < clip.size(); ++i) EXPECT_EQ(clip[i]["sah_cost"].get<double>(), expected[i]) << i;
  // ... and the strategies differ here, so the check above can tell them apart.
  EXPECT_GT(refit[1], strategySah(loaded, "rebuild", {4})[0]);
  // The switches are logged like any other.
  ASSERT_EQ(j["switches"].size(), 2u);
  EXPECT_EQ(j["switches"][0]["switch"], "update");
  EXPECT_EQ(j["switches"][1]["value"], "refit+rebuild:4");
}

TEST(ViewClip, RefusesAStaticSceneABadSpecAndAFramePastTheClip) {
  REQUIRE_VIEWER(prefix);
  const std::string still = writeTemp("still.toml",
                                      "[camera]\neye = [0, 2.5, 4]\ntarget = [0, 0, 0]\n"
                                      "[[object]]\nkind = \"mesh\"\ngenerate = \"terrain\"\ntriangles = 1000\n")
                                .string();
  clitest::Result r = view(*prefix, still + " --update refit --frames 1");
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.err.find("--update"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("not animated"), std::string::npos) << r.err;

  const std::string scene = explodingScene();
  r = view(*prefix, scene + " --update refit+rebuild:0 --frames 1");
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.err.find("--update"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("refit+rebuild:0"), std::string::npos) << r.err;

  const std::string past = writeTemp("past.txt", "1 set clip_frame 12\n").string();
  r = view(*prefix, scene + " --script " + past + " --frames 2");
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.err.find(past + ":1: clip_frame 12 is past the clip (12 frames)"), std::string::npos) << r.err;

  // Two-level trees: a layout without a two-level walk, and a static BLAS under a deforming mesh.
  r = view(*prefix, scene + " --update two-level:blas=refit --layout bvh4 --frames 1");
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.err.find("no two-level walk"), std::string::npos) << r.err;
  r = view(*prefix, scene + " --update two-level --frames 1");
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.err.find("deforms"), std::string::npos) << r.err;

  const std::string bad = writeTemp("bad.txt", "1 set update sometimes\n").string();
  r = view(*prefix, scene + " --script " + bad + " --frames 2");
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.err.find(bad + ":1: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("'sometimes'"), std::string::npos) << r.err;
}

// The viewer plays a clip through a two-level tree (its BLAS refit, the TLAS rebuilt every frame):
// every clip frame made and drawn, the first one building, the later ones updating.
TEST(ViewClip, PlaysAClipThroughATwoLevelTree) {
  REQUIRE_VIEWER(prefix);
  const std::string script = writeTemp("two_level.txt", "3 key SPACE\n").string();  // scripted: a clip frame a frame
  const clitest::Result r =
      view(*prefix, explodingScene() + " --update two-level:blas=refit --script " + script + " --frames 4 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const json out = json::parse(r.out);
  EXPECT_EQ(out["update"], "two-level:blas=refit");
  const json& clip = out["clip"];
  ASSERT_EQ(clip.size(), 3u) << clip.dump();  // paused at frame 3 before it advanced
  for (size_t i = 0; i < clip.size(); ++i) {
    EXPECT_EQ(clip[i]["clip_frame"], int(i));
    EXPECT_EQ(clip[i]["update"], "two-level:blas=refit");
    EXPECT_EQ(clip[i]["rebuilt"].get<bool>(), i == 0) << clip[i].dump();
    EXPECT_GT(clip[i]["sah_cost"].get<double>(), 0.0);
    EXPECT_GT(clip[i]["nodes"].get<int>(), 1);
  }
}

// A GPU builder rebuilding every frame: built and packed on the GPU and drawn from the streams left
// there (`update_on` gpu); the same trees (SAH, exactly) and the same last image as the CPU lbvh's.
TEST(ViewClip, AGpuBuilderRebuildsOnTheGpuAndDrawsWhatTheCpuBuilderDraws) {
  REQUIRE_VIEWER(prefix);
  const std::string scene = explodingScene();
  const std::string script = writeTemp("gpu_clip.txt", "3 key SPACE\n").string();
  json out[2];
  std::string shots[2];
  for (int k = 0; k < 2; ++k) {
    const std::string builder = k == 0 ? "lbvh-gpu" : "lbvh";
    shots[k] = clitest::testDir().string() + "/view_" + builder + ".png";
    const clitest::Result r = view(*prefix, scene + " --builder " + builder + " --script " + script +
                                                " --frames 4 --json --screenshot " + shots[k]);
    ASSERT_EQ(r.code, 0) << r.err;
    out[k] = json::parse(r.out);
  }
  const json &gpu = out[0]["clip"], &cpu = out[1]["clip"];
  ASSERT_EQ(gpu.size(), 3u) << gpu.dump();
  ASSERT_EQ(cpu.size(), 3u) << cpu.dump();
  for (size_t i = 0; i < gpu.size(); ++i) {
    SCOPED_TRACE(i);
    EXPECT_EQ(gpu[i]["update_on"], "gpu");
    EXPECT_EQ(cpu[i]["update_on"], "cpu");
    EXPECT_TRUE(gpu[i]["rebuilt"].get<bool>());
    EXPECT_EQ(gpu[i]["sah_cost"], cpu[i]["sah_cost"]);
    EXPECT_EQ(gpu[i]["nodes"], cpu[i]["nodes"]);
  }
  EXPECT_EQ(loadImageRgba8(shots[0]).rgba, loadImageRgba8(shots[1]).rgba) << "the frames drawn differ";
}

TEST(ViewClip, AJumpStartsTheStrategyAgainAtThatFrame) {
  REQUIRE_VIEWER(prefix);
  const std::string scene = explodingScene();
  const std::string script = writeTemp("jump.txt", "2 set clip_frame 9\n").string();
  const clitest::Result r = view(*prefix, scene + " --update refit --script " + script + " --frames 4 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const json clip = json::parse(r.out)["clip"];
  ASSERT_EQ(clip.size(), 4u) << clip.dump();
  const std::vector<int> frames = {0, 1, 9, 10};
  const std::vector<bool> rebuilt = {true, false, true, false};
  for (size_t i = 0; i < clip.size(); ++i) {
    EXPECT_EQ(clip[i]["clip_frame"], frames[i]) << i;
    EXPECT_EQ(clip[i]["rebuilt"], rebuilt[i]) << i;
  }
  const Scene loaded = loadInput(scene);
  EXPECT_EQ(clip[3]["sah_cost"].get<double>(), strategySah(loaded, "refit", {9, 10})[1]);
}

}  // namespace
}  // namespace bvhlab
