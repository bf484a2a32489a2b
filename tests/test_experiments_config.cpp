// The experiment runner's configs: parsing and validation (file, line and key in every error), product
// expansion minus exclusions, stable run keys, sweep unions and references, generated scenes, camera
// paths, the render command line, and every shipped config against the real registries and data.
#include "test_experiments_fixture.hpp"
#include "builders/gpu/gpu_builders.hpp"
#include "layout/layouts.hpp"
#include "traversal/kernels.hpp"

using namespace bvhlab::experiments_test;

namespace {

TEST_F(Experiments, ExpandsTheProductInAxisOrderMinusPartialExclusions) {
  writeText(root / "a.off", "OFF\n0 0 0\n");
  writeText(root / "b.off", "OFF\n0 0 0\n");
  const ExperimentConfig cfg = parse(kSweepConfig);
  // 2 scenes x 2 builders x 1 kernel x 3 leaf sizes = 12, minus median at leaf 1 and 4 on both scenes.
  ASSERT_EQ(cfg.runs.size(), 8u);
  const char* expected[8][3] = {{"a", "median", "16"},    {"a", "sah-binned", "1"}, {"a", "sah-binned", "4"},
                                {"a", "sah-binned", "16"}, {"b", "median", "16"},    {"b", "sah-binned", "1"},
                                {"b", "sah-binned", "4"},  {"b", "sah-binned", "16"}};
  std::set<std::string> keys;
  for (size_t i = 0; i < cfg.runs.size(); ++i) {
    const RunSpec& run = cfg.runs[i];
    EXPECT_EQ(run.index, i);
    EXPECT_EQ(run.axis("scene")->label, expected[i][0]);
    EXPECT_EQ(run.axis("builder")->label, expected[i][1]);
    EXPECT_EQ(run.axis("leaf_size")->label, expected[i][2]);
    EXPECT_EQ(run.axis("kernel")->label, "stack-ordered");  // a scalar is a one-value axis
    EXPECT_EQ(run.axis("scene")->file, (root / (std::string(expected[i][0]) + ".off")).lexically_normal());
    EXPECT_EQ(run.key.size(), 16u);
    keys.insert(run.key);
  }
  EXPECT_EQ(keys.size(), cfg.runs.size()) << "run keys must be unique";
}

TEST_F(Experiments, RunKeysAreStableAndIndependentOfWhereTheConfigLives) {
  writeText(root / "a.off", "OFF\n0 0 0\n");
  writeText(root / "b.off", "OFF\n0 0 0\n");
  writeText(root / "other" / "a.off", "OFF\n0 0 0\n");
  writeText(root / "other" / "b.off", "OFF\n0 0 0\n");
  const ExperimentConfig first = parse(kSweepConfig);
  writeText(root / "other" / "cfg.toml", std::string(kSweepConfig) + "\n# a comment changes the hash, not keys\n");
  const ExperimentConfig moved = loadExperimentConfig(root / "other" / "cfg.toml", kNames);
  EXPECT_NE(first.hash, moved.hash);
  ASSERT_EQ(first.runs.size(), moved.runs.size());
  for (size_t i = 0; i < first.runs.size(); ++i) EXPECT_EQ(first.runs[i].key, moved.runs[i].key);

  // Any parameter that changes the run changes the key.
  std::string wider = kSweepConfig;
  wider.replace(wider.find("width = 8"), 9, "width = 9");
  const ExperimentConfig changed = parse(wider);
  for (size_t i = 0; i < first.runs.size(); ++i) EXPECT_NE(first.runs[i].key, changed.runs[i].key);
}

TEST_F(Experiments, SweepsUnionDeduplicatesSharedRunsAndReferencesAreAdded) {
  writeText(root / "m.off", "OFF\n0 0 0\n");
  const ExperimentConfig cfg = parse(R"(
[experiment]
reference = { aa = "ssaa16", frames = 1 }
[axes]
scenes = "m.off"
depths = 3
leaf_sizes = 4
aa = "none"
[[sweep]]
name = "depth"
depths = [1, 3]
[[sweep]]
name = "leaf"
leaf_sizes = [2, 4]
)");
  // depth sweep: (d1,l4) (d3,l4); leaf sweep: (d3,l2) (d3,l4) -> (d3,l4) is shared.
  ASSERT_EQ(cfg.sweepNames, (std::vector<std::string>{"depth", "leaf"}));
  std::vector<const RunSpec*> sweepRuns, references;
  for (const RunSpec& r : cfg.runs) (r.referenceOnly ? references : sweepRuns).push_back(&r);
  ASSERT_EQ(sweepRuns.size(), 3u);
  EXPECT_EQ(sweepRuns[1]->sweeps, (std::vector<std::string>{"depth", "leaf"}));
  // Each sweep run's reference is itself with aa = ssaa16 and 1 frame: three distinct references.
  ASSERT_EQ(references.size(), 3u);
  for (const RunSpec* run : sweepRuns) {
    const RunSpec* ref = nullptr;
    for (const RunSpec& r : cfg.runs)
      if (r.key == run->referenceKey) ref = &r;
    ASSERT_NE(ref, nullptr);
    EXPECT_TRUE(ref->referenceOnly);
    EXPECT_EQ(ref->axis("aa")->label, "ssaa16");
    EXPECT_EQ(ref->render.frames, 1);
    EXPECT_EQ(ref->axis("depth")->label, run->axis("depth")->label);
    EXPECT_EQ(ref->axis("leaf_size")->label, run->axis("leaf_size")->label);
    EXPECT_TRUE(ref->sweeps.empty());
  }
}

TEST_F(Experiments, ReferenceInsideTheSweepIsReusedNotDuplicated) {
  writeText(root / "m.off", "OFF\n0 0 0\n");
  const ExperimentConfig cfg = parse(R"(
[experiment.reference]
aa = "ssaa16"
[axes]
scenes = "m.off"
aa = ["none", "smaa", "ssaa16"]
)");
  ASSERT_EQ(cfg.runs.size(), 3u);
  for (const RunSpec& r : cfg.runs) EXPECT_EQ(r.referenceKey, cfg.runs[2].key);
}

// A traced run (rays axis) draws no image: it gets no reference, so a reference with a render-only axis
// (depth) beside a rays sweep is not turned into a trace run that `bvhlab trace` rejects.
TEST_F(Experiments, TracedRunsGetNoReference) {
  writeText(root / "m.off", "OFF\n0 0 0\n");
  const ExperimentConfig cfg = parse(R"(
[experiment]
reference = { depth = 8, frames = 1 }
[axes]
scenes = "m.off"
[[sweep]]
name = "frames"
depths = 1
[[sweep]]
name = "rays"
rays = "primary"
)");
  ASSERT_EQ(cfg.runs.size(), 3u) << "the frame run, its depth-8 reference, the traced run";
  for (const RunSpec& r : cfg.runs) {
    if (r.axis("workload")) {
      EXPECT_TRUE(r.referenceKey.empty()) << r.describe();
      EXPECT_FALSE(r.referenceOnly);
    }
  }
}

TEST_F(Experiments, ValidationErrorsNameTheFileLineAndKey) {
  writeText(root / "m.off", "OFF\n0 0 0\n");
  struct Case {
    const char* text;
    std::vector<std::string> expected;
  };
  const Case cases[] = {
      {"[axes]\nscenes = 'm.off'\nkernal = ['stackless']\n", {"cfg.toml:3", "axes.kernal", "unknown axis"}},
      {"[axes]\nscenes = 'm.off'\nleaf_sizes = []\n", {"cfg.toml:3", "axes.leaf_sizes", "empty list"}},
      {"[axes]\nscenes = 'm.off'\nleaf_sizes = [4, '8']\n", {"cfg.toml:3", "axes.leaf_sizes[1]", "integer"}},
      {"[axes]\nscenes = 'm.off'\nleaf_sizes = 0\n", {"cfg.toml:3", "axes.leaf_sizes", "outside 1..255"}},
      {"[axes]\nscenes = 'm.off'\n\nbuilders = ['median', 'octree']\n",
       {"cfg.toml:4", "axes.builders[1]", "unknown builder 'octree'", "sah-binned"}},
      {"[axes]\nscenes = 'm.off'\nbuilders = [{ name = 'median', binz = 4 }]\n", {"cfg.toml:3", "binz"}},
      {"[axes]\nscenes = 'm.off'\nkernels = 'stack-unordred'\n", {"cfg.toml:3", "axes.kernels", "unknown kernel"}},
      {"[axes]\nscenes = ['m.off', 'missing.off']\n", {"cfg.toml:2", "axes.scenes[1]", "missing.off", "not found"}},
      {"[axes]\nscenes = 'm.off'\naa = 'fxaa'\n", {"cfg.toml:3", "axes.aa", "unknown aa 'fxaa'"}},
      {"[render]\nwidht = 3\n[axes]\nscenes = 'm.off'\n", {"cfg.toml:2", "render.widht", "unknown key"}},
      {"[render]\nwidth = 'wide'\n[axes]\nscenes = 'm.off'\n", {"cfg.toml:2", "render.width", "integer"}},
      {"[axes]\nscenes = 'm.off'\nleaf_sizes = [1, 2]\n[[exclude]]\nleaf_size = 3\n",
       {"cfg.toml:5", "exclude[0].leaf_size", "'3' matches no value"}},
      {"[axes]\nscenes = 'm.off'\n[[exclude]]\nscene = 'm'\n", {"exclude", "every run"}},
      {"[axes]\nleaf_sizes = 4\n", {"axes.scenes", "missing"}},
      {"[axes\nscenes = 'm.off'\n", {"cfg.toml:1", "TOML syntax error"}},
      {"[axis]\nscenes = 'm.off'\n", {"cfg.toml:1", "axis", "unknown section"}},
      {"[experiment]\nreference = { depth = [1, 2] }\n[axes]\nscenes = 'm.off'\n",
       {"cfg.toml:2", "experiment.reference.depth", "one value"}},
      {"[axes]\nscenes = ['m.off', { file = 'm.off' }]\n", {"cfg.toml:2", "axes.scenes", "appears twice"}},
      {"[axes]\nscenes = { generate = 'large' }\n", {"cfg.toml:2", "axes.scenes", "needs `triangles`"}},
      {"[axes]\nscenes = { generate = 'cube', triangles = 500 }\n", {"cfg.toml:2", "unknown generator 'cube'"}},
      {"[axes]\nscenes = { generate = 'large', triangles = 10 }\n", {"cfg.toml:2", "triangles", "outside"}},
      {"[axes]\nscenes = { file = 'm.off', eye = [0, nan, 1] }\n", {"cfg.toml:2", "axes.scenes.eye", "finite"}},
      {"[render]\ntimeout_s = inf\n[axes]\nscenes = 'm.off'\n", {"cfg.toml:2", "render.timeout_s", "finite"}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.text);
    try {
      parse(c.text);
      ADD_FAILURE() << "expected an InputError";
    } catch (const InputError& e) {
      for (const std::string& s : c.expected) EXPECT_NE(std::string(e.what()).find(s), std::string::npos) << e.what();
    }
  }
}

TEST_F(Experiments, GeneratedScenesAreWrittenOnceAndRenderedFromTheirFile) {
  writeText(root / "cfg.toml", R"(
[axes]
scenes = [{ generate = "large", triangles = 300, seed = 7 }, { generate = "soup", triangles = 120, name = "s" }]
leaf_sizes = [1, 4]
)");
  FakeRenderer fake;
  std::set<fs::path> files;
  RunOptions o = options(root / "cfg.toml", root / "out", fake);
  o.executor = [&](RunRequest& r) {
    files.insert(r.spec.axis("scene")->file);
    return fake(r);
  };
  runSweep(o);
  ASSERT_EQ(files.size(), 2u);
  const fs::path large = root / "out" / "generated" / "large-300-seed7.ply";
  EXPECT_TRUE(files.count(large.lexically_normal()));
  for (const fs::path& f : files) {
    const Scene scene = loadInput(f);  // the renderer's own loader reads it back
    EXPECT_EQ(scene.triangleCount(), f == large ? 300u : 120u) << f;
  }
  const json rows = readJsonFile(root / "out" / "results.json")["rows"];
  EXPECT_EQ(rows[0]["scene"], "large-300");
  EXPECT_EQ(rows[2]["scene"], "s");
  // A second invocation reuses the files (and the finished runs).
  const auto before = fs::last_write_time(large);
  EXPECT_EQ(runSweep(o).executed, 0u);
  EXPECT_EQ(fs::last_write_time(large), before);
}

// Every shipped config loads against the real builder and kernel registries, with its data: a config
// whose scene or mesh is missing FAILS (CI fetches the data with datasets/fetch.sh first; a shipped
// config that cannot run is a broken config, not a skip). Known configs also keep their run counts;
// one added later is loaded and checked for runs without a count. The registry is bvhlab's: the CPU
// builders and the GPU builders it registers.
TEST(ShippedConfigs, AreValidAgainstTheRegistriesAndTheirDataIsThere) {
  registerGpuBuilders();  // as the bvhlab app does before it parses a command (no GL needed to register)
  const fs::path dir = fs::path(BVHLAB_SOURCE_DIR) / "experiments" / "configs";
  std::map<std::string, size_t> expectedRuns = {
      {"quick.toml", 72},      {"seed-figures.toml", 20}, {"builders.toml", 1990}, {"accuracy-vs-time.toml", 30},
      {"antialiasing.toml", 34},  // 2 scenes x (6 modes + colour edges + ({none, smaa-high} + smaa-high geometry edges) x 3 texture LODs) + 2 references
      {"texture-lod.toml", 20},   // 2 scenes x {none, smaa-high luma, smaa-high geometry} x 3 texture LODs + 2 references
      {"flythrough.toml", 15}, {"large.toml", 2}, {"bench.toml", 400},
      {"morton-grid.toml", 20}, {"ploc-top-down.toml", 12}, {"storage.toml", 15},
      {"sbvh-knobs.toml", 15},  // 3 scenes x (sah-binned + 4 sbvh settings)
      {"builders-gpu.toml", 104},  // 3 scenes x 2 workloads x 13 builders + 2 rendered scenes x 13
      {"kernels-gpu.toml", 21}};   // 3 scenes x 2 workloads x 3 kernels + the report scene x 3
  // layouts.toml sweeps `layouts = "all"`: (3 scenes x 2 workloads + the report scene + the bunny's diffuse
  // rays with indexed triangles) per registered layout.
  expectedRuns["layouts.toml"] = 8 * layouts().size();
  // layouts-gpu.toml: 3 scenes x 2 workloads per registered layout, on the EGL backend.
  expectedRuns["layouts-gpu.toml"] = 6 * layouts().size();
  // layouts-paper-gpu.toml: 6 scenes x 3 workloads per registered kernel (`kernels = "all"`, each with its layout).
  expectedRuns["layouts-paper-gpu.toml"] = 18 * allKernels().size();
  // layouts-kernels.toml: the bunny's primary and diffuse rays per registered kernel (named one by one: a
  // kernel registered later and not added to the list fails here).
  expectedRuns["layouts-kernels.toml"] = 2 * allKernels().size();
  std::set<std::string> seen;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().extension() != ".toml") continue;
    const std::string name = entry.path().filename().string();
    SCOPED_TRACE(name);
    seen.insert(name);
    try {
      const ExperimentConfig cfg = loadExperimentConfig(entry.path());
      EXPECT_FALSE(cfg.runs.empty());
      if (expectedRuns.count(name)) {
        EXPECT_EQ(cfg.runs.size(), expectedRuns.at(name));
      }
      EXPECT_FALSE(cfg.description.empty());
    } catch (const InputError& e) {
      const std::string what = e.what();
      ADD_FAILURE() << what
                    << (what.find("not found") != std::string::npos
                            ? "\n(shipped config's data missing: run `bash datasets/fetch.sh`, as CI does)"
                            : "");
    }
  }
  for (const auto& [name, runs] : expectedRuns) EXPECT_TRUE(seen.count(name)) << name << " is no longer shipped";
}

TEST_F(Experiments, RenderCommandLineCarriesEveryAxisAndSetting) {
  writeText(root / "m.off", "OFF\n0 0 0\n");
  const ExperimentConfig cfg = parse(R"(
[render]
width = 64
height = 32
frames = 7
warmup = 3
backend = "egl"
args = ["--exposure", "2"]
[axes]
scenes = { file = "m.off", eye = [1, 2.5, 3], target = [0, 0, 0], fov = 35 }
builders = { name = "sah-binned", bins = 12 }
kernels = "stackless"
leaf_sizes = 8
depths = 2
storages = "tex2d"
aa = "smaa"
robust = "watertight"
branching = "report"
views = "visits"
uber = true
)");
  ASSERT_EQ(cfg.runs.size(), 1u);
  RunRequest req{cfg.runs[0], root / "i.png", root / "v.png", "", ""};
  const std::vector<std::string> argv = renderCommandLine("/bin/bvhlab", req);
  const std::string line = shellQuote(argv);
  for (const char* part :
       {"/bin/bvhlab render ", "m.off --json -o ", "/i.png --width 64 --height 32 --frames 7 --warmup 3 --backend egl",
        "--visits-out ", "/v.png", "--eye 1,2.5,3 --target 0,0,0 --fov 35", "--builder sah-binned --bins 12",
        "--kernel stackless", "--leaf-size 8", "--depth 2", "--storage tex2d", "--aa smaa", "--robust watertight",
        "--branching report", "--view visits", "--uber", "--exposure 2"})
    EXPECT_NE(line.find(part), std::string::npos) << part << " not in: " << line;
  EXPECT_EQ(cfg.runs[0].axis("builder")->label, "sah-binned[bins=12]");
}

// [render] gpu_builds reaches the command line (render and trace runs alike), the run's key (only when
// set: other configs keep their keys) and plan.json; a value outside 0..1000 is refused naming the key.
TEST_F(Experiments, GpuBuildsReachTheCommandLineTheKeyAndThePlan) {
  writeText(root / "m.off", "OFF\n0 0 0\n");
  const ExperimentConfig plain = parse("[axes]\nscenes = 'm.off'\n");
  const ExperimentConfig timed = parse("[render]\ngpu_builds = 6\n[axes]\nscenes = 'm.off'\n");
  ASSERT_EQ(timed.runs.size(), 1u);
  EXPECT_NE(plain.runs[0].key, timed.runs[0].key);
  const std::string line = shellQuote(renderCommandLine("/bin/bvhlab", RunRequest{timed.runs[0], root / "i.png", "", "", ""}));
  EXPECT_NE(line.find("--gpu-builds 6"), std::string::npos) << line;
  const std::string plainLine = shellQuote(renderCommandLine("/bin/bvhlab", RunRequest{plain.runs[0], root / "i.png", "", "", ""}));
  EXPECT_EQ(plainLine.find("--gpu-builds"), std::string::npos) << plainLine;
  EXPECT_EQ(RunSpec::fromJson(timed.runs[0].toJson()).render.gpuBuilds, 6);
  try {
    parse("[render]\ngpu_builds = -1\n[axes]\nscenes = 'm.off'\n");
    ADD_FAILURE() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cfg.toml:2"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("render.gpu_builds"), std::string::npos) << e.what();
  }
}

// A builder table's ploc_radius and morton_size_bits reach the render command line and the label, and
// a value outside the flag's range is refused with the file, line and key.
TEST_F(Experiments, PlocBuilderTableCarriesRadiusAndMortonSizeBits) {
  writeText(root / "m.off", "OFF\n0 0 0\n");
  const ExperimentConfig cfg = parse(R"(
[axes]
scenes = "m.off"
builders = { name = "ploc", ploc_radius = 32, morton_size_bits = 6 }
)");
  ASSERT_EQ(cfg.runs.size(), 1u);
  const std::string line = shellQuote(renderCommandLine("/bin/bvhlab", RunRequest{cfg.runs[0], root / "i.png", root / "v.png", "", ""}));
  EXPECT_NE(line.find("--builder ploc --ploc-radius 32 --morton-size-bits 6"), std::string::npos) << line;
  EXPECT_EQ(cfg.runs[0].axis("builder")->label, "ploc[radius=32][size-bits=6]");
  try {
    parse("[axes]\nscenes = 'm.off'\nbuilders = { name = 'ploc', morton_size_bits = 10 }\n");
    ADD_FAILURE() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cfg.toml:3"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("morton_size_bits"), std::string::npos) << e.what();
  }
}

// A builder table's morton_grid reaches the render command line and the label; an unknown grid is
// refused with the file, line, key and the valid names.
TEST_F(Experiments, BuilderTableCarriesTheMortonGrid) {
  writeText(root / "m.off", "OFF\n0 0 0\n");
  const ExperimentConfig cfg = parse(R"(
[axes]
scenes = "m.off"
builders = [{ name = "ploc", morton_grid = "axes" }, "ploc"]
)");
  ASSERT_EQ(cfg.runs.size(), 2u);
  const std::string line = shellQuote(renderCommandLine("/bin/bvhlab", RunRequest{cfg.runs[0], root / "i.png", root / "v.png", "", ""}));
  EXPECT_NE(line.find("--builder ploc --morton-grid axes"), std::string::npos) << line;
  EXPECT_EQ(cfg.runs[0].axis("builder")->label, "ploc[grid=axes]");
  EXPECT_EQ(cfg.runs[1].axis("builder")->label, "ploc");
  try {
    parse("[axes]\nscenes = 'm.off'\nbuilders = { name = 'ploc', morton_grid = 'square' }\n");
    ADD_FAILURE() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cfg.toml:3"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("morton_grid"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("axes"), std::string::npos) << e.what();
  }
}

// A builder table's ploc_top_down reaches the render command line and the label; out of range is
// refused with the file, line and key.
TEST_F(Experiments, BuilderTableCarriesPlocTopDown) {
  writeText(root / "m.off", "OFF\n0 0 0\n");
  const ExperimentConfig cfg = parse(R"(
[axes]
scenes = "m.off"
builders = [{ name = "ploc", ploc_top_down = 4 }, "ploc"]
)");
  ASSERT_EQ(cfg.runs.size(), 2u);
  const std::string line = shellQuote(renderCommandLine("/bin/bvhlab", RunRequest{cfg.runs[0], root / "i.png", root / "v.png", "", ""}));
  EXPECT_NE(line.find("--builder ploc --ploc-top-down 4"), std::string::npos) << line;
  EXPECT_EQ(cfg.runs[0].axis("builder")->label, "ploc[top-down=4]");
  EXPECT_EQ(cfg.runs[1].axis("builder")->label, "ploc");
  try {
    parse("[axes]\nscenes = 'm.off'\nbuilders = { name = 'ploc', ploc_top_down = 2000 }\n");
    ADD_FAILURE() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cfg.toml:3"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("ploc_top_down"), std::string::npos) << e.what();
  }
}

// A builder table's sbvh_budget reaches the command line and the label; below 1 is refused with the
// file, line and key.
TEST_F(Experiments, BuilderTableCarriesSbvhBudget) {
  writeText(root / "m.off", "OFF\n0 0 0\n");
  const ExperimentConfig cfg = parse(R"(
[axes]
scenes = "m.off"
builders = [{ name = "sbvh", sbvh_budget = 1.5 }, { name = "sbvh", sbvh_alpha = 0.001, sbvh_budget = 4 }, "sbvh"]
)");
  ASSERT_EQ(cfg.runs.size(), 3u);
  const std::string line = shellQuote(renderCommandLine("/bin/bvhlab", RunRequest{cfg.runs[0], root / "i.png", root / "v.png", "", ""}));
  EXPECT_NE(line.find("--builder sbvh --sbvh-budget 1.5"), std::string::npos) << line;
  EXPECT_EQ(cfg.runs[0].axis("builder")->label, "sbvh[budget=1.5]");
  EXPECT_EQ(cfg.runs[1].axis("builder")->label, "sbvh[alpha=0.001][budget=4.0]");
  EXPECT_EQ(cfg.runs[2].axis("builder")->label, "sbvh");
  const std::string plain = shellQuote(renderCommandLine("/bin/bvhlab", RunRequest{cfg.runs[2], root / "i.png", root / "v.png", "", ""}));
  EXPECT_EQ(plain.find("--sbvh-budget"), std::string::npos) << plain;
  for (const char* bad : {"0.5", "nan", "inf"}) {
    try {
      parse(std::string("[axes]\nscenes = 'm.off'\nbuilders = { name = 'sbvh', sbvh_budget = ") + bad + " }\n");
      ADD_FAILURE() << bad << ": expected an InputError";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("cfg.toml:3"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("sbvh_budget"), std::string::npos) << e.what();
    }
  }
}

// [render] camera_path: resolved against the config's folder, validated at load, part of the key,
// passed to the renderer as --camera-path.
TEST_F(Experiments, CameraPathIsResolvedKeyedAndPassedToTheRenderer) {
  const std::string pose = "t 0 eye 0 0 3 target 0 0 0 up 0 1 0 fov 45\n";
  writeText(root / "m.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  writeText(root / "paths" / "fly.txt", pose + "t 0.5 eye 1 0 3 target 0 0 0 up 0 1 0 fov 45\n");
  const std::string axes = "[axes]\nscenes = 'm.off'\nkernels = ['stack-ordered', 'stackless']\n";
  writeText(root / "plain.toml", axes);
  writeText(root / "cfg.toml", "[render]\ncamera_path = 'paths/fly.txt'\n" + axes);
  const ExperimentConfig plain = loadExperimentConfig(root / "plain.toml", kNames);
  const ExperimentConfig cfg = loadExperimentConfig(root / "cfg.toml", kNames);
  ASSERT_EQ(cfg.runs.size(), 2u);
  EXPECT_EQ(cfg.runs[0].render.cameraPath, "paths/fly.txt");
  EXPECT_EQ(cfg.runs[0].render.cameraPathFile, (root / "paths" / "fly.txt").lexically_normal());
  EXPECT_NE(cfg.runs[0].key, plain.runs[0].key) << "the camera path is part of the run key";
  EXPECT_FALSE(plain.runs[0].render.keyJson().contains("camera_path")) << "keys without a path are unchanged";

  // A plan round trip keeps it; the command line carries the resolved file.
  const RunSpec back = RunSpec::fromJson(cfg.runs[0].toJson());
  EXPECT_EQ(back.key, cfg.runs[0].key);
  EXPECT_EQ(back.keyJson(), cfg.runs[0].keyJson());
  RunRequest request{back, root / "a.png", {}, "", ""};
  const std::vector<std::string> argv = renderCommandLine("bvhlab", request);
  auto flag = std::find(argv.begin(), argv.end(), "--camera-path");
  ASSERT_NE(flag, argv.end());
  ASSERT_NE(flag + 1, argv.end());
  EXPECT_EQ(fs::path(*(flag + 1)), (root / "paths" / "fly.txt").lexically_normal());

  // Re-recording the path (same name, new poses) makes new runs: old results are not reused.
  writeText(root / "paths" / "fly.txt", pose);
  EXPECT_NE(loadExperimentConfig(root / "cfg.toml", kNames).runs[0].key, cfg.runs[0].key);
}

TEST_F(Experiments, BadCameraPathInAConfigNamesFileLineAndKey) {
  writeText(root / "m.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  writeText(root / "broken.txt", "t 0 eye 0 0 3 target 0 0 0 up 0 1 0 fov 45\nt 1 eye 0 0 3 target 0 0 0 up 0 1 0\n");
  const std::string axes = "[axes]\nscenes = 'm.off'\n";
  struct Case {
    std::string render, expect;
  };
  for (const Case& c : {Case{"camera_path = 'missing.txt'", "not found"},
                        Case{"camera_path = 'broken.txt'", "broken.txt:2: missing 'fov'"},
                        Case{"camera_path = ''", "empty path"},
                        Case{"camera_path = 3", "expected a string"}}) {
    writeText(root / "cfg.toml", "[render]\nwidth = 64\n" + c.render + "\n" + axes);
    try {
      loadExperimentConfig(root / "cfg.toml", kNames);
      ADD_FAILURE() << "no error for " << c.render;
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind((root / "cfg.toml").string() + ":3: render.camera_path: ", 0), 0u) << what;
      EXPECT_NE(what.find(c.expect), std::string::npos) << what;
    }
  }
  // A scene's own camera would be silently replaced by the path: refused.
  writeText(root / "ok.txt", "t 0 eye 0 0 3 target 0 0 0 up 0 1 0 fov 45\n");
  writeText(root / "cfg.toml", "[render]\ncamera_path = 'ok.txt'\n[axes]\nscenes = [{ file = 'm.off', eye = [0, 0, 2] }]\n");
  try {
    loadExperimentConfig(root / "cfg.toml", kNames);
    ADD_FAILURE() << "no error for a scene camera + camera_path";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind((root / "cfg.toml").string() + ":2: render.camera_path: ", 0), 0u) << e.what();
  }
}

TEST(ExperimentConfigs, FlythroughConfigLoads) {
  const fs::path config = fs::path(BVHLAB_SOURCE_DIR) / "experiments" / "configs" / "flythrough.toml";
  // No skip without the data: a shipped config must load (CI runs datasets/fetch.sh first).
  ASSERT_TRUE(fs::exists(fs::path(BVHLAB_SOURCE_DIR) / "datasets" / "cache" / "meshes" / "bunny00.off"))
      << "bunny00.off missing: run `bash datasets/fetch.sh`";
  const ExperimentConfig cfg = loadExperimentConfig(config);
  ASSERT_FALSE(cfg.runs.empty());
  for (const RunSpec& run : cfg.runs) {
    EXPECT_FALSE(run.render.cameraPath.empty());
    EXPECT_TRUE(fs::is_regular_file(run.render.cameraPathFile)) << run.render.cameraPathFile;
  }
  EXPECT_GE(cfg.axisLabels.at("builder").size(), 2u);
  EXPECT_GE(cfg.axisLabels.at("kernel").size(), 2u);
}

}  // namespace
