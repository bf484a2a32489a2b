// `trace --update SPEC` over an animated clip (render/trace_clip.hpp): per-frame records, the clip's
// total, refusals; and the `updates` axis of experiment configs. Small scenes: a generated terrain
// patch (2000 triangles), 32x32 primary rays, a few frames.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_run.hpp"
#include "datasets/image_io.hpp"
#include "datasets/scene.hpp"
#include "experiments/config.hpp"

namespace bvhlab {
namespace {

using clitest::run;
using clitest::writeTemp;
using nlohmann::json;

const std::string kView =
    "[camera]\neye = [0, 2.5, 4]\ntarget = [0, 0, 0]\n[render]\nwidth = 32\nheight = 32\n";
const std::string kTerrain = "[[object]]\nkind = \"mesh\"\ngenerate = \"terrain\"\ntriangles = 2000\nfit = 2\n";

// A clip of `frames` frames whose mesh does not move (`deform` empty) or deforms.
std::string clipScene(const std::string& name, int frames, const std::string& deform = "") {
  std::string text = "[clip]\nframes = " + std::to_string(frames) + "\nfps = 10\n" + kView + kTerrain;
  if (!deform.empty()) text += "[object.deform]\n" + deform;
  return writeTemp(name, text).string();
}

json traceJson(const std::string& args) {
  const clitest::Result r = run("trace " + args + " --json --frames 1 --warmup 0");
  EXPECT_EQ(r.code, 0) << r.err;
  if (r.code != 0) return json::object();
  return json::parse(r.out);
}

TEST(DynamicTrace, RefitOfAStillClipKeepsTheTreeAndMatchesAStaticTrace) {
  const std::string scene = clipScene("still.toml", 4);
  const json clip = traceJson(scene + " --update refit");
  const json still = traceJson(scene);
  ASSERT_TRUE(clip.contains("frames") && clip["frames"].is_array());
  ASSERT_EQ(clip["frames"].size(), 4u);
  for (const json& f : clip["frames"]) {
    SCOPED_TRACE("frame " + std::to_string(f["frame"].get<int>()));
    EXPECT_EQ(f["tree_hash"], still["tree_hash"]);
    EXPECT_EQ(f["hits"], still["hits"]);
    EXPECT_EQ(f["node_visits_per_ray"], still["node_visits_per_ray"]);
    EXPECT_EQ(f["triangle_tests_per_ray"], still["triangle_tests_per_ray"]);
    EXPECT_EQ(f["ray_cost"], still["ray_cost"]);
    EXPECT_EQ(f["hit_mismatches"], 0);
    EXPECT_EQ(f["rebuilt"], f["frame"] == 0);  // refit builds once
  }
}

// The explode deformation moves every triangle away from the centre from t = 0, each in its own
// direction: a refit tree keeps frame 0's topology, so its boxes come to span the whole debris while a
// rebuilt tree groups what now lies together. Provable here: frame 0's trees are the same build (equal
// cost); a refit box always contains its children, so refit's cost can only stay or rise as neighbours
// part; what is asserted is the order, not a tuned factor.
TEST(DynamicTrace, RefitRayCostGrowsOnAnExplodingMeshWhileRebuildsStaysBelowIt) {
  const std::string scene =
      clipScene("explode.toml", 6, "kind = \"explode\"\nspeed = 3\njitter = 0.5\nspeed_jitter = 0.8\nseed = 3\n");
  const json refit = traceJson(scene + " --update refit");
  const json rebuild = traceJson(scene + " --update rebuild");
  ASSERT_EQ(refit["frames"].size(), 6u);
  ASSERT_EQ(rebuild["frames"].size(), 6u);
  const json &r0 = refit["frames"].front(), &rN = refit["frames"].back();
  EXPECT_EQ(r0["ray_cost"], rebuild["frames"].front()["ray_cost"]);
  EXPECT_GT(rN["ray_cost"].get<double>(), r0["ray_cost"].get<double>());
  EXPECT_GT(rN["sah_cost"].get<double>(), r0["sah_cost"].get<double>());
  for (const json& f : rebuild["frames"]) {
    EXPECT_TRUE(f["rebuilt"].get<bool>());
    EXPECT_LT(f["ray_cost"].get<double>(), rN["ray_cost"].get<double>()) << "rebuild frame " << f["frame"];
  }
  EXPECT_GT(rebuild["frames"].back()["tree_hash"], "");
  EXPECT_NE(rebuild["frames"].back()["tree_hash"], rebuild["frames"].front()["tree_hash"]);
}

TEST(DynamicTrace, FramesHaveEveryKeyAndTheClipTotalIsTheSumOfTheParts) {
  const std::string scene = clipScene("wave.toml", 3, "kind = \"wave\"\namplitude = 0.2\nwavelength = 1\n");
  const clitest::Result r =
      run("trace " + scene + " --json --frames 3 --warmup 0 --update refit+rebuild:2 --update-repeats 2 --epo");
  ASSERT_EQ(r.code, 0) << r.err;
  const json j = json::parse(r.out);
  ASSERT_EQ(j["frames"].size(), 3u);
  double update = 0.0, upload = 0.0, trace = 0.0;
  for (const char* key : {"frame", "rebuilt", "update_ms", "update_ms_all", "upload_ms", "ms", "ms_ci_low", "ms_ci_high",
                          "ms_all", "sah_cost", "epo", "ray_cost", "tree_hash"})
    for (const json& f : j["frames"]) EXPECT_TRUE(f.contains(key)) << key << " in frame " << f["frame"];
  for (const json& f : j["frames"]) {
    EXPECT_EQ(f["update_ms_all"].size(), 2u);
    EXPECT_EQ(f["ms_all"].size(), 3u);
    EXPECT_EQ(f["rebuilt"], f["frame"].get<int>() % 2 == 0);
    EXPECT_TRUE(f["repeats_agree"].get<bool>());
    update += f["update_ms"].get<double>();
    upload += f["upload_ms"].get<double>();
    trace += f["ms"].get<double>();
  }
  const json& clip = j["clip"];
  EXPECT_EQ(clip["frames"], 3);
  EXPECT_EQ(clip["fps"], 10.0);
  // By construction: the total is the sum of the per-frame medians of the three parts.
  const double total = clip["total_ms"].get<double>();
  EXPECT_NEAR(clip["update_ms_total"].get<double>(), update, 1e-9 * total);
  EXPECT_NEAR(clip["upload_ms_total"].get<double>(), upload, 1e-9 * total);
  EXPECT_NEAR(clip["trace_ms_total"].get<double>(), trace, 1e-9 * total);
  EXPECT_NEAR(total, update + upload + trace, 1e-9 * total);
  ASSERT_TRUE(clip["total_ms_ci_low"].is_number() && clip["total_ms_ci_high"].is_number());
  EXPECT_LE(clip["total_ms_ci_low"].get<double>(), clip["total_ms_ci_high"].get<double>());
  EXPECT_GT(clip["total_ms_ci_low"].get<double>(), 0.0);
}

TEST(DynamicTrace, ShortenedClipTakesEveryStepthFrame) {
  const std::string scene = clipScene("still7.toml", 7);
  const json j = traceJson(scene + " --update refit --clip-step 3");
  ASSERT_EQ(j["frames"].size(), 3u);
  EXPECT_EQ(j["frames"][2]["frame"], 6);
  const json k = traceJson(scene + " --update refit --clip-frames 2");
  EXPECT_EQ(k["frames"].size(), 2u);
}

TEST(DynamicRender, RefitOfAStillClipKeepsTheTreeAndMatchesAStaticRender) {
  const std::string scene = clipScene("still_render.toml", 3);
  const clitest::Result a = run("render " + scene + " --json --frames 1 --warmup 0 --update refit");
  const clitest::Result b = run("render " + scene + " --json --frames 1 --warmup 0");
  ASSERT_EQ(a.code, 0) << a.err;
  ASSERT_EQ(b.code, 0) << b.err;
  const json clip = json::parse(a.out), still = json::parse(b.out);
  ASSERT_EQ(clip["frames"].size(), 3u);
  for (const json& f : clip["frames"]) {
    SCOPED_TRACE("frame " + std::to_string(f["frame"].get<int>()));
    EXPECT_EQ(f["tree_hash"], still["tree_hash"]);
    EXPECT_EQ(f["ray_cost"], still["ray_cost"]);
    EXPECT_EQ(f["node_visits_per_ray"], still["node_visits_per_ray"]);
    for (const char* key : {"update_ms", "upload_ms", "ms", "sah_cost", "rebuilt"}) EXPECT_TRUE(f.contains(key)) << key;
  }
  EXPECT_NEAR(clip["clip"]["total_ms"].get<double>(),
              clip["clip"]["update_ms_total"].get<double>() + clip["clip"]["upload_ms_total"].get<double>() +
                  clip["clip"]["trace_ms_total"].get<double>(),
              1e-9 * clip["clip"]["total_ms"].get<double>());
  const std::string still2 = writeTemp("static_render.toml", kView + kTerrain).string();
  const clitest::Result r = run("render " + still2 + " --update refit --frames 1 --warmup 0");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("--update"), std::string::npos) << r.err;
}

// A measure group of clip runs steps them in lockstep in one context: each clip's clock-free results
// equal its own `trace --update`'s, a static run beside them is traced as before, and a clip that
// cannot be set up fails alone.
TEST(DynamicTrace, AGroupInterleavesItsClipsFrameByFrame) {
  const std::string scene =
      clipScene("group.toml", 4, "kind = \"explode\"\nspeed = 3\njitter = 0.5\nspeed_jitter = 0.8\nseed = 3\n");
  const std::vector<std::string> common = {scene, "--json", "--rays", "primary", "--frames", "1", "--warmup", "0"};
  auto args = [&](std::vector<std::string> more) {
    std::vector<std::string> a = common;
    a.insert(a.end(), more.begin(), more.end());
    return a;
  };
  const json spec = {{"session", "s"}, {"min_frames", 1}, {"max_frames", 1}, {"aa_control", false}, {"command", "trace"},
                     {"runs", {{{"key", "refit"}, {"args", args({"--update", "refit"})}},
                               {{"key", "rebuild"}, {"args", args({"--update", "rebuild"})}},
                               {{"key", "bad"}, {"args", args({"--update", "refit+rebuild:0"})}},
                               {{"key", "static"}, {"args", args({})}}}}};
  const clitest::Result r = run("measure " + writeTemp("group.json", spec.dump()).string());
  ASSERT_EQ(r.code, 0) << r.err;
  const json out = json::parse(r.out)["runs"];
  EXPECT_NE(out["bad"]["error"].get<std::string>().find("--update"), std::string::npos) << out["bad"];
  EXPECT_TRUE(out["static"].contains("frame_ms_all")) << out["static"];
  for (const char* key : {"refit", "rebuild"}) {
    SCOPED_TRACE(key);
    ASSERT_TRUE(out[key].contains("frames")) << out[key];
    EXPECT_EQ(out[key]["interleaved_with"], 1);
    const json solo = traceJson(scene + " --rays primary --update " + key);
    ASSERT_EQ(out[key]["frames"].size(), solo["frames"].size());
    for (size_t f = 0; f < solo["frames"].size(); ++f) {
      EXPECT_EQ(out[key]["frames"][f]["tree_hash"], solo["frames"][f]["tree_hash"]);
      EXPECT_EQ(out[key]["frames"][f]["ray_cost"], solo["frames"][f]["ray_cost"]);
    }
  }
}

TEST(DynamicTrace, StaticSceneAndBadSpecAreRefused) {
  const std::string still = writeTemp("static.toml", kView + kTerrain).string();
  clitest::Result r = run("trace " + still + " --update refit --frames 1 --warmup 0");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("--update"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("not animated"), std::string::npos) << r.err;
  const std::string scene = clipScene("bad_spec.toml", 2);
  for (const char* spec : {"refit+rebuild:0", "refti", "refit+rebuild:sah>0.5"}) {
    r = run("trace " + scene + " --update '" + spec + "' --frames 1 --warmup 0");
    EXPECT_EQ(r.code, 2) << spec << ": " << r.err;
    EXPECT_NE(r.err.find("--update"), std::string::npos) << r.err;
    EXPECT_EQ(r.out, "");
  }
}

// `--update two-level`: two terrain patches moving past each other, traced through the two-level
// walk. Embree's answers over the flat frame agree with the kernel's (hits mapped back to the flat
// scene's triangles), the counters split TLAS and BLAS, and the rigid BLASes are built once.
TEST(DynamicTrace, TwoLevelTracesTheClipThroughTheTwoLevelWalk) {
  std::string text = "[clip]\nframes = 6\nfps = 10\n" + kView;
  for (const char* keys : {"[[object.keys]]\nframe = 0\nposition = [-1, 0, 0]\n[[object.keys]]\nframe = 5\n"
                           "position = [1, 0.2, 0]\nrotation = { axis = [0, 1, 0], angle = 90 }\n",
                           "[[object.keys]]\nframe = 0\nposition = [1, 0, 0]\n[[object.keys]]\nframe = 5\n"
                           "position = [-1, -0.2, 0]\nscale = [1, 2, 0.5]\n"})
    text += kTerrain + keys;
  const std::string scene = writeTemp("two_level.toml", text).string();
  for (const std::string layout : {"v1", "bvh2-cb"}) {
    SCOPED_TRACE(layout);
    const json j = traceJson(scene + " --update two-level:tlas=lbvh --layout " + layout + " --update-repeats 2");
    ASSERT_EQ(j["frames"].size(), 6u);
    EXPECT_EQ(j["clip"]["hit_mismatches"], 0);
    EXPECT_EQ(j["clip"]["rebuilds"], 1);  // frame 0 builds the BLASes; later frames only the TLAS
    for (const json& f : j["frames"]) {
      EXPECT_EQ(f["instances"], 2);
      EXPECT_EQ(f["blases"], 1);  // one rest mesh, shared
      EXPECT_GT(f["hits"].get<int>(), 100);
      EXPECT_TRUE(f["repeats_agree"].get<bool>());
      const double tlas = f["tlas_node_visits_per_ray"].get<double>(), blas = f["blas_node_visits_per_ray"].get<double>();
      EXPECT_GE(tlas, 1.0);  // every ray visits the TLAS root
      EXPECT_GT(blas, 0.0);
      EXPECT_GT(f["instance_tests_per_ray"].get<double>(), 0.0);
      EXPECT_DOUBLE_EQ(f["node_visits_per_ray"].get<double>(), tlas + blas);
      EXPECT_NEAR(f["update_ms"].get<double>(), f["blas_update_ms"].get<double>() + f["tlas_update_ms"].get<double>(),
                  1e-6 + 0.5 * f["update_ms"].get<double>());  // medians of sums vs sums of medians (2 copies)
    }
  }
  // A static BLAS under a deforming object, and a layout or triangle format without a two-level walk.
  const std::string wave = clipScene("two_level_wave.toml", 3, "kind = \"wave\"\namplitude = 0.2\nwavelength = 1\n");
  clitest::Result r = run("trace " + wave + " --update two-level --frames 1 --warmup 0");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("deforms"), std::string::npos) << r.err;
  EXPECT_EQ(traceJson(wave + " --update two-level:blas=refit")["clip"]["hit_mismatches"], 0);
  for (const std::string args : {" --layout bvh4", " --triangles indexed"}) {
    r = run("trace " + scene + " --update two-level --frames 1 --warmup 0" + args);
    EXPECT_EQ(r.code, 2) << args << ": " << r.err;
    EXPECT_NE(r.err.find("--update two-level"), std::string::npos) << r.err;
  }
}

// `render --update two-level` draws through the kernel's two-level walk what the flat tree draws: two
// instances of one terrain patch (one BLAS, shared) with different materials, one rotated, one scaled
// non-uniformly, shaded with shadows and a reflection. The last frame's image equals the
// flat tree's but for a few pixels where the instance transform's rounding moves an edge or a shadow
// boundary by a hair (what must hold: normals through the inverse transpose, the instance's material,
// the geometric normal from the placed vertices); the counters sum the TLAS and BLAS walks.
TEST(DynamicRender, TwoLevelDrawsWhatTheFlatTreeDraws) {
  std::string text = "[clip]\nframes = 3\nfps = 10\n" + kView +
                     "[[light]]\nkind = \"directional\"\ndirection = [-0.3, -1, -0.2]\nintensity = 1\n"
                     "[[material]]\nname = \"red\"\ncolor = [0.8, 0.2, 0.2]\n"
                     "[[material]]\nname = \"mirror\"\ncolor = [0.3, 0.4, 0.9]\nreflectivity = 0.5\n";
  const char* keys[2] = {"material = \"red\"\n[[object.keys]]\nframe = 0\nposition = [-0.8, 0, 0]\n[[object.keys]]\n"
                         "frame = 2\nposition = [-0.6, 0.3, 0]\nrotation = { axis = [0, 1, 0], angle = 60 }\n",
                         "material = \"mirror\"\n[[object.keys]]\nframe = 0\nposition = [0.8, 0, 0]\n"
                         "scale = [1.3, 1.5, 0.7]\n[[object.keys]]\nframe = 2\nposition = [0.6, -0.2, 0.3]\n"
                         "scale = [1.3, 1.5, 0.7]\n"};
  for (const char* k : keys) text += kTerrain + k;
  const std::string scene = writeTemp("two_level_render.toml", text).string();
  for (const std::string layout : {"v1", "bvh2-cb"}) {
    SCOPED_TRACE(layout);
    const auto flatPng = writeTemp("two_level_flat_" + layout + ".png", ""), twoPng = writeTemp("two_level_" + layout + ".png", "");
    const std::string args = " --json --frames 1 --warmup 0 --layout " + layout;
    const clitest::Result a = run("render " + scene + args + " --update rebuild -o " + flatPng.string());
    const clitest::Result b = run("render " + scene + args + " --update two-level:tlas=lbvh -o " + twoPng.string());
    ASSERT_EQ(a.code, 0) << a.err;
    ASSERT_EQ(b.code, 0) << b.err;
    const json flat = json::parse(a.out), two = json::parse(b.out);
    ASSERT_EQ(two["frames"].size(), 3u);
    EXPECT_TRUE(two["two_level"].get<bool>());
    EXPECT_EQ(two["clip"]["rebuilds"], 1);  // the BLAS on frame 0; later frames only the TLAS
    for (const json& f : two["frames"]) {
      EXPECT_EQ(f["instances"], 2);
      EXPECT_EQ(f["blases"], 1);
      EXPECT_TRUE(f["epo"].is_null());
      EXPECT_GT(f["ray_cost"].get<double>(), 0.0);
      EXPECT_GT(f["tlas_update_ms"].get<double>(), 0.0);
    }
    const ImageRgba8 x = loadImageRgba8(flatPng), y = loadImageRgba8(twoPng);
    ASSERT_EQ(x.rgba.size(), y.rgba.size());
    size_t differ = 0, lit = 0;  // lit: pixels of the red instance
    for (size_t p = 0; p < x.rgba.size(); p += 4) {
      int d = 0;
      for (int c = 0; c < 3; ++c) d = std::max(d, std::abs(int(x.rgba[p + c]) - int(y.rgba[p + c])));
      differ += d > 2;  // 2/255: a rounding of the colour, not a different surface or material
      lit += int(x.rgba[p]) > int(x.rgba[p + 2]) + 40;  // the red instance (nothing else in the scene is red)
    }
    const size_t pixels = x.rgba.size() / 4;
    EXPECT_GT(lit, pixels / 50) << "the red instance covers too little of the image to compare";
    EXPECT_LE(differ, pixels / 100) << differ << " of " << pixels << " pixels differ";
  }
}

// The `updates` axis: every value is a spec parseUpdateSpec accepts, checked at load; a bad one names
// the file, its line and the key.
std::string configError(const std::string& text) {
  const auto file = writeTemp("dynamic.toml", text);
  try {
    loadExperimentConfig(file);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

const std::string kConfigHead = "[experiment]\nname = \"t\"\n[axes]\nscenes = [\"" +
                                clitest::scene("bench/anim-explode.toml").string() + "\"]\nrays = [\"primary\"]\n";

TEST(DynamicConfig, UpdatesAxisValuesAreCheckedAtLoad) {
  EXPECT_EQ(configError(kConfigHead + "updates = [\"refit\", \"refit+rebuild:sah>1.5\"]\n"), "");
  const std::string bad = configError(kConfigHead + "updates = [\"refit\",\n  \"refit+rebuild:0\"]\n");
  EXPECT_NE(bad.find("dynamic.toml:7:"), std::string::npos) << bad;
  EXPECT_NE(bad.find("updates"), std::string::npos) << bad;
  EXPECT_NE(bad.find("refit+rebuild:K"), std::string::npos) << bad;  // parseUpdateSpec's message
  const std::string unknown = configError(kConfigHead + "updates = [\"refti\"]\n");
  EXPECT_NE(unknown.find("dynamic.toml:6:"), std::string::npos) << unknown;
  // A clip is traced: the axis needs a workload.
  const std::string noRays = configError("[experiment]\nname = \"t\"\n[axes]\nscenes = [\"" +
                                         clitest::scene("bench/anim-explode.toml").string() +
                                         "\"]\nupdates = [\"refit\"]\n");
  EXPECT_NE(noRays.find("rays axis"), std::string::npos) << noRays;
}

// A scene entry's own count, clip_step and clip_frames replace [trace]'s for its runs (and their
// keys); out-of-range values are refused naming the file, line and key.
TEST(DynamicConfig, ASceneMayTraceItsClipAtItsOwnStepLengthAndRays) {
  const std::string scene = clitest::scene("bench/anim-explode.toml").string();
  const auto file = writeTemp("own_clip.toml", "[experiment]\nname = \"t\"\n[trace]\ncount = 512\nclip_step = 4\n"
                                               "clip_frames = 15\n[axes]\nscenes = [\"" + scene + "\",\n"
                                               "  { file = \"" + scene + "\", name = \"fine\", clip_step = 1, "
                                               "clip_frames = 30, count = 2048 }]\nrays = [\"primary\"]\n"
                                               "updates = [\"refit\"]\n");
  const ExperimentConfig cfg = loadExperimentConfig(file);
  ASSERT_EQ(cfg.runs.size(), 2u);
  std::set<std::string> keys;
  for (const RunSpec& run : cfg.runs) {
    keys.insert(run.key);
    const bool fine = run.axis("scene")->label == "fine";
    EXPECT_EQ(run.render.clipStep, fine ? 1 : 4);
    EXPECT_EQ(run.render.clipFrames, fine ? 30 : 15);
    EXPECT_EQ(run.render.traceCount, fine ? 2048 : 512);
  }
  EXPECT_EQ(keys.size(), 2u);
  for (const std::string field : {"clip_step = 0", "clip_frames = -1", "count = 0"}) {
    const std::string bad = configError("[experiment]\nname = \"t\"\n[axes]\nscenes = [\n  { file = \"" + scene +
                                        "\", " + field + " }]\nrays = [\"primary\"]\nupdates = [\"refit\"]\n");
    EXPECT_NE(bad.find("dynamic.toml:5:"), std::string::npos) << field << ": " << bad;
    EXPECT_NE(bad.find(field.substr(0, field.find(' '))), std::string::npos) << field << ": " << bad;
  }
}

}  // namespace
}  // namespace bvhlab
