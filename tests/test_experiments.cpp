// The experiment runner: config parsing and validation, product expansion, resume after a kill,
// shards + merge, the subprocess executor (against a shell-script stand-in for `bvhlab render`) and
// the HTML report. Runs use a fake executor: no GL, no renderer needed.
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>

#include <gtest/gtest.h>

#include "datasets/image_io.hpp"
#include "datasets/scene.hpp"
#include "datasets/scene_io.hpp"
#include "experiments/config.hpp"
#include "experiments/executor.hpp"
#include "experiments/image_error.hpp"
#include "experiments/process.hpp"
#include "experiments/runner.hpp"
#include "experiments/sweep_dir.hpp"

namespace fs = std::filesystem;
using namespace bvhlab;
using nlohmann::json;

namespace {

const fs::path kFixtures = fs::path(BVHLAB_SOURCE_DIR) / "tests" / "fixtures" / "experiments";
const KnownNames kNames{{"median", "sah-binned", "sah-sweep", "embree"}, {"stack-ordered", "stackless"}};

void writeText(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

std::string readText(const fs::path& p) {
  std::ifstream in(p);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

json readJsonFile(const fs::path& p) { return json::parse(readText(p)); }

// Triangle count from an OFF header ("OFF\nV F E"): lets the fake report mesh/no-mesh scenes.
int offTriangles(const fs::path& p) {
  std::ifstream in(p);
  std::string magic;
  int v = 0, f = 0;
  in >> magic >> v >> f;
  return f;
}

// A stand-in for `bvhlab render`: deterministic synthetic timings that depend on the run's axes the
// way the real ones plausibly do, and an image whose noise shrinks with better anti-aliasing, so
// the image-error and report paths see structured data. Counts its calls per key.
struct FakeRenderer {
  std::map<std::string, int> calls;

  json operator()(RunRequest& req) {
    const RunSpec& s = req.spec;
    ++calls[s.key];
    auto number = [&](const char* axis, double fallback) {
      const AxisValue* v = s.axis(axis);
      return v ? v->value.get<double>() : fallback;
    };
    auto text = [&](const char* axis, const std::string& fallback) {
      const AxisValue* v = s.axis(axis);
      return v ? v->value.get<std::string>() : fallback;
    };
    const std::string builder = s.axis("builder") ? s.axis("builder")->value["name"].get<std::string>() : "sah-binned";
    const double leaf = number("leaf_size", 4), depth = number("depth", 5);
    const double leafPenalty = 1.0 + 0.15 * std::abs(std::log2(leaf / 4.0));
    double ms = (2.0 + depth) * (builder == "median" ? 1.3 : 1.0) * leafPenalty;
    const std::string aa = text("aa", "none");
    const int noise = aa == "none" ? 24 : aa == "smaa" ? 10 : aa == "ssaa4" ? 4 : 0;
    ms *= aa == "smaa" ? 1.1 : aa == "ssaa4" ? 4.0 : aa == "ssaa16" ? 16.0 : 1.0;
    const std::string robust = text("robust", "fast");
    ms *= robust == "watertight" ? 1.05 : robust == "tri" ? 1.04 : 1.0;
    ms *= text("kernel", "stack-ordered") == "stackless" ? 1.2 : 1.0;
    const double sah = (builder == "median" ? 44.0 : 34.5) * leafPenalty;

    const int w = s.render.width, h = s.render.height;
    std::vector<uint8_t> rgba(size_t(4 * w * h));
    for (int i = 0; i < w * h; ++i) {
      const int n = noise ? int((uint32_t(i) * 2654435761u) >> 27) % (noise + 1) : 0;  // Knuth hash as noise
      rgba[4 * i + 0] = uint8_t(std::min(255, 8 * (i % w) + n));
      rgba[4 * i + 1] = uint8_t(std::min(255, 12 * (i / w) + n));
      rgba[4 * i + 2] = uint8_t(100 + n);
      rgba[4 * i + 3] = 255;
    }
    saveImageRgba8(req.image, w, h, rgba);
    if (!req.visitsImage.empty()) saveImageRgba8(req.visitsImage, w, h, rgba);
    req.command = "fake " + s.describe();
    const int triangles = offTriangles(s.axis("scene")->file);
    return json{{"frame_ms", ms},
                {"frame_ms_min", ms * 0.98},
                {"frame_ms_max", ms * 1.03},
                {"renderer", "fake renderer (test)"},
                {"builder", builder},
                {"leaf_size", int(leaf)},
                {"depth", int(depth)},
                {"build_ms", builder == "median" ? 1.0 : 3.0},
                {"sah_cost", sah},
                {"nodes", 2 * triangles + 1},
                {"node_visits_per_ray", 0.8 * sah},
                {"node_visits_p95", 1.5 * sah},
                {"triangle_tests_per_ray", leaf * 1.5},
                {"triangles", triangles},
                {"mesh_rays", w * h},
                {"aa_ms", aa == "smaa" ? json(0.1 * ms) : json(nullptr)}};
  }
};

// Death-test children are fresh processes (threadsafe style re-executes the test binary); this
// variable hands them the parent's directory.
constexpr const char* kDeathTestDirEnv = "BVHLAB_EXPERIMENTS_DEATH_TEST_DIR";

class Experiments : public ::testing::Test {
 protected:
  void SetUp() override {
    if (const char* inherited = std::getenv(kDeathTestDirEnv)) {
      root = inherited;  // a death-test child works in its parent's directory
    } else {
      std::string tmpl = (fs::path(::testing::TempDir()) / "bvhlab-experiments-XXXXXX").string();
      ASSERT_NE(::mkdtemp(tmpl.data()), nullptr);
      root = tmpl;
    }
    ::setenv("BVHLAB_SOURCE_DIR", BVHLAB_SOURCE_DIR, 1);
  }
  void TearDown() override {
    if (!std::getenv("BVHLAB_KEEP_TEST_DIRS")) fs::remove_all(root);
  }

  ExperimentConfig parse(const std::string& text) {
    const fs::path file = root / "cfg.toml";
    writeText(file, text);
    return loadExperimentConfig(file, kNames);
  }

  RunOptions options(const fs::path& config, const fs::path& out, FakeRenderer& fake) {
    RunOptions o;
    o.config = config;
    o.outDir = out;
    o.report = false;
    o.progress = false;
    o.names = kNames;
    o.executor = [&fake](RunRequest& r) { return fake(r); };
    return o;
  }

  fs::path root;
};

// Rows without the fields that differ between two executions of the same run.
json comparableRows(const fs::path& dir) {
  json rows = readJsonFile(dir / "results.json")["rows"];
  for (json& row : rows)
    for (const char* volatileField : {"started_at", "wall_s"}) row.erase(volatileField);
  return rows;
}

const char* kSweepConfig = R"(
[experiment]
name = "t"
[render]
width = 8
height = 4
[axes]
scenes = ["a.off", "b.off"]
builders = ["median", "sah-binned"]
kernels = "stack-ordered"
leaf_sizes = [1, 4, 16]
[[exclude]]
builder = "median"
leaf_size = [1, 4]
)";

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

// The shipped configs parse against the real builder and kernel registries. A config whose data is
// not there (datasets/fetch.sh not run, a scene file not written yet) is reported and skipped.
TEST(ShippedConfigs, AreValidAgainstTheRegistries) {
  const fs::path dir = fs::path(BVHLAB_SOURCE_DIR) / "experiments" / "configs";
  const std::map<std::string, size_t> expectedRuns = {
      {"quick.toml", 56}, {"seed-figures.toml", 18}, {"builders.toml", 1810}, {"accuracy-vs-time.toml", 30},
      {"antialiasing.toml", 16}, {"flythrough.toml", 15}};
  std::vector<std::string> skipped;
  for (const auto& [name, runs] : expectedRuns) {
    SCOPED_TRACE(name);
    try {
      const ExperimentConfig cfg = loadExperimentConfig(dir / name);
      EXPECT_EQ(cfg.runs.size(), runs);
      EXPECT_FALSE(cfg.description.empty());
    } catch (const InputError& e) {
      if (std::string(e.what()).find("not found") == std::string::npos) ADD_FAILURE() << e.what();
      else skipped.push_back(e.what());
    }
  }
  for (const std::string& s : skipped) std::cerr << "skipped (missing data): " << s << "\n";
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

TEST_F(Experiments, ImageErrorIsMeanAbsoluteErrorAndPsnrOverRgb) {
  const int w = 4, h = 3;
  std::vector<uint8_t> a(4 * w * h, 10), b(4 * w * h, 13);
  for (int i = 0; i < w * h; ++i) a[4 * i + 3] = b[4 * i + 3] = 255;  // opaque, as the renderer writes
  saveImageRgba8(root / "a.png", w, h, a);
  saveImageRgba8(root / "b.png", w, h, b);
  const ImageError e = compareImages(root / "a.png", root / "b.png");
  EXPECT_DOUBLE_EQ(e.meanAbsError, 3.0);
  EXPECT_DOUBLE_EQ(e.mse, 9.0);
  ASSERT_TRUE(e.psnr().has_value());
  EXPECT_NEAR(*e.psnr(), 10.0 * std::log10(255.0 * 255.0 / 9.0), 1e-9);
  EXPECT_FALSE(compareImages(root / "a.png", root / "a.png").psnr().has_value()) << "identical: PSNR infinite";
  saveImageRgba8(root / "c.png", 2, 2, std::vector<uint8_t>(16, 0));
  EXPECT_THROW(compareImages(root / "a.png", root / "c.png"), std::invalid_argument);
}

TEST_F(Experiments, RunRecordsEveryRunWithProvenanceAndImageError) {
  FakeRenderer fake;
  const fs::path out = root / "out";
  const SweepOutcome o = runSweep(options(kFixtures / "report.toml", out, fake));
  const json results = readJsonFile(out / "results.json");
  const size_t planned = results["summary"]["planned"];
  EXPECT_EQ(o.executed, planned);
  EXPECT_EQ(results["rows"].size(), planned);
  EXPECT_EQ(results["summary"]["ok"], planned);
  EXPECT_EQ(fake.calls.size(), planned);
  for (const json& row : results["rows"]) {
    EXPECT_EQ(row["status"], "ok");
    EXPECT_EQ(row["config_hash"].get<std::string>().size(), 16u);
    EXPECT_FALSE(row["git_commit"].get<std::string>().empty());
    EXPECT_FALSE(row["hostname"].get<std::string>().empty());
    EXPECT_FALSE(row["cpu"].get<std::string>().empty());
    EXPECT_GT(row["cores"].get<int>(), 0);
    EXPECT_EQ(row["gl_renderer"], "fake renderer (test)");
    EXPECT_TRUE(fs::exists(out / row["image"].get<std::string>()));
    EXPECT_TRUE(fs::exists(out / row["visits_image"].get<std::string>()));
    ASSERT_TRUE(row["image_mae"].is_number()) << row.dump();
    // The fake's noise shrinks with anti-aliasing; the reference (ssaa16) is noise-free.
    const std::string aa = row["aa"];
    if (aa == "ssaa16") EXPECT_EQ(row["image_mae"].get<double>(), 0.0);
    else EXPECT_GT(row["image_mae"].get<double>(), 0.0);
  }
  // CSV: a header and one line per row.
  std::ifstream csv(out / "results.csv");
  size_t lines = 0;
  std::string header;
  std::getline(csv, header);
  for (std::string line; std::getline(csv, line);) ++lines;
  EXPECT_EQ(lines, planned);
  EXPECT_EQ(header.rfind("key,index,status,", 0), 0u);
  EXPECT_NE(header.find("image_psnr"), std::string::npos);

  // Errors shrink with better anti-aliasing, on matched runs.
  std::map<std::string, double> maeByAa;
  for (const json& row : results["rows"])
    if (row["scene"] == "tri" && row["builder"] == "sah-binned" && row["kernel"] == "stack-ordered" &&
        row["leaf_size"] == 4 && row["depth"] == 3)
      maeByAa[row["aa"]] = row["image_mae"];
  ASSERT_EQ(maeByAa.size(), 3u);
  EXPECT_GT(maeByAa["none"], maeByAa["smaa"]);
  EXPECT_GT(maeByAa["smaa"], maeByAa["ssaa16"]);
}

TEST_F(Experiments, FailedRunsAreRecordedTheSweepGoesOnAndTheyAreRetriedNextTime) {
  writeText(root / "m.off", "OFF\n0 0 0\n");
  writeText(root / "cfg.toml", "[axes]\nscenes = 'm.off'\nkernels = ['stack-ordered', 'stackless']\nleaf_sizes = [1, 2]\n");
  FakeRenderer fake;
  bool broken = true;
  RunOptions o = options(root / "cfg.toml", root / "out", fake);
  o.executor = [&](RunRequest& r) -> json {
    if (broken && r.spec.axis("kernel")->label == "stackless") {
      r.log = "0:1(2): error: shader does not compile\n";
      throw RunFailure("renderer exit code 4: bvhlab: shader error");
    }
    return fake(r);
  };
  SweepOutcome first = runSweep(o);
  EXPECT_EQ(first.executed, 4u);
  EXPECT_EQ(first.failed, 2u);
  json rows = readJsonFile(root / "out" / "results.json")["rows"];
  ASSERT_EQ(rows.size(), 4u);
  for (const json& row : rows) {
    if (row["kernel"] == "stackless") {
      EXPECT_EQ(row["status"], "failed");
      EXPECT_NE(row["error"].get<std::string>().find("shader error"), std::string::npos);
      const json record = readJsonFile(root / "out" / "runs" / (row["key"].get<std::string>() + ".json"));
      EXPECT_NE(record["log"].get<std::string>().find("does not compile"), std::string::npos);
    } else {
      EXPECT_EQ(row["status"], "ok");
    }
  }

  // Without retry the failures are kept; with retry (the default) only they run again.
  o.retryFailed = false;
  EXPECT_EQ(runSweep(o).executed, 0u);
  broken = false;
  o.retryFailed = true;
  const std::map<std::string, int> callsBefore = fake.calls;
  SweepOutcome second = runSweep(o);
  EXPECT_EQ(second.executed, 2u);
  EXPECT_EQ(second.skipped, 2u);
  EXPECT_EQ(second.summary["ok"], 4);
  for (const auto& [key, n] : callsBefore) EXPECT_EQ(fake.calls[key], n) << "finished run " << key << " redone";
}

TEST_F(Experiments, ResumeAfterAKillMidSweepLosesNothingAndDuplicatesNothing) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  const fs::path out = root / "out";
  const fs::path config = kFixtures / "report.toml";
  // The child process dies (no unwinding, no cleanup) in the middle of its 6th run.
  ::setenv(kDeathTestDirEnv, root.c_str(), 1);
  EXPECT_EXIT(
      {
        FakeRenderer fake;
        RunOptions o = options(config, out, fake);
        int n = 0;
        o.executor = [&](RunRequest& r) -> json {
          if (++n == 6) std::_Exit(3);
          return fake(r);
        };
        runSweep(o);
        std::_Exit(0);
      },
      ::testing::ExitedWithCode(3), "");
  ::unsetenv(kDeathTestDirEnv);

  const std::map<std::string, json> afterKill = readRecords(SweepDir{out});
  ASSERT_EQ(afterKill.size(), 5u);
  EXPECT_EQ(readJsonFile(out / "results.json")["rows"].size(), 5u) << "results regenerated after every run";
  // A run cut off while its record was being written on a non-atomic file system leaves garbage:
  // it must count as not finished.
  const json plan = readPlan(SweepDir{out});
  const std::string garbled = plan["runs"][7]["key"];
  writeText(out / "runs" / (garbled + ".json"), "{\"key\": \"" + garbled + "\", \"stat");

  FakeRenderer fake;
  const SweepOutcome resumed = runSweep(options(config, out, fake));
  for (const auto& [key, record] : afterKill) EXPECT_EQ(fake.calls.count(key), 0u) << "finished run " << key << " redone";
  EXPECT_EQ(fake.calls.count(garbled), 1u);
  const json results = readJsonFile(out / "results.json");
  const size_t planned = results["summary"]["planned"];
  EXPECT_EQ(resumed.executed + 5, planned);
  ASSERT_EQ(results["rows"].size(), planned);
  std::set<std::string> keys;
  for (const json& row : results["rows"]) keys.insert(row["key"].get<std::string>());
  EXPECT_EQ(keys.size(), planned);
  for (const fs::directory_entry& e : fs::directory_iterator(out / "runs"))
    EXPECT_NE(e.path().filename().string().front(), '.') << "temporary left behind: " << e.path();
}

TEST_F(Experiments, ShardsMergedEqualTheUnshardedSweep) {
  const fs::path config = kFixtures / "report.toml";
  FakeRenderer fakeAll, fake0, fake1;
  runSweep(options(config, root / "all", fakeAll));
  RunOptions s0 = options(config, root / "s0", fake0), s1 = options(config, root / "s1", fake1);
  std::tie(s0.shardIndex, s0.shardCount) = parseShard("0/2");
  std::tie(s1.shardIndex, s1.shardCount) = parseShard("1/2");
  const SweepOutcome o0 = runSweep(s0), o1 = runSweep(s1);
  EXPECT_EQ(o0.executed + o1.executed, fakeAll.calls.size());
  for (const auto& [key, n] : fake0.calls) EXPECT_EQ(fake1.calls.count(key), 0u) << "run in both shards";

  const json summary = mergeSweeps({root / "s0", root / "s1"}, root / "merged");
  EXPECT_EQ(summary["ok"], fakeAll.calls.size());
  EXPECT_EQ(comparableRows(root / "merged"), comparableRows(root / "all"));
  for (const json& row : readJsonFile(root / "merged" / "results.json")["rows"])
    EXPECT_TRUE(fs::exists(root / "merged" / row["image"].get<std::string>()));

  // Merging again, with a shard given twice, changes nothing.
  mergeSweeps({root / "s1", root / "s0", root / "s1"}, root / "merged");
  EXPECT_EQ(comparableRows(root / "merged"), comparableRows(root / "all"));

  EXPECT_THROW(parseShard("2/2"), InputError);
  EXPECT_THROW(parseShard("1of2"), InputError);
}

TEST_F(Experiments, MergeRefusesDirectoriesFromDifferentConfigs) {
  writeText(root / "m.off", "OFF\n0 0 0\n");
  writeText(root / "a.toml", "[axes]\nscenes = 'm.off'\nleaf_sizes = [1, 2]\n");
  writeText(root / "b.toml", "[axes]\nscenes = 'm.off'\nleaf_sizes = [1, 4]\n");
  FakeRenderer fake;
  runSweep(options(root / "a.toml", root / "a", fake));
  runSweep(options(root / "b.toml", root / "b", fake));
  try {
    mergeSweeps({root / "a", root / "b"}, root / "m");
    ADD_FAILURE() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("different config"), std::string::npos) << e.what();
  }
}

TEST_F(Experiments, SubprocessExecutorRecordsOutputCrashesAndTimeouts) {
  const fs::path png = root / "fixture.png";
  saveImageRgba8(png, 8, 4, std::vector<uint8_t>(4 * 8 * 4, 128));
  writeText(root / "m.off", "OFF\n0 0 0\n");
  writeText(root / "cfg.toml",
            "[render]\nwidth = 8\nheight = 4\ntimeout_s = 1.0\nenv = { FAKE_RENDER_PNG = '" + png.string() +
                "' }\n[measure]\ninterleave = false\n[axes]\nscenes = 'm.off'\n"
                "kernels = ['good', 'crash', 'bad-json', 'hang', 'exit4', 'badflag']\n");
  RunOptions o;
  o.config = root / "cfg.toml";
  o.outDir = root / "out";
  o.report = false;
  o.progress = false;
  o.names = KnownNames{};  // the fake's kernel names are not real ones
  o.binary = kFixtures / "fake_render.sh";
  const SweepOutcome outcome = runSweep(o);
  EXPECT_EQ(outcome.executed, 6u);
  EXPECT_EQ(outcome.failed, 5u);
  std::map<std::string, json> byKernel;
  for (const auto& [key, record] : readRecords(SweepDir{root / "out"}))
    byKernel[record["params"]["axes"][1]["label"]] = record;
  ASSERT_EQ(byKernel.size(), 6u);

  const json& good = byKernel["good"];
  EXPECT_EQ(good["status"], "ok");
  EXPECT_EQ(good["result"]["frame_ms"], 2.5);
  EXPECT_NE(good["log"].get<std::string>().find("a warning on stderr"), std::string::npos);
  EXPECT_NE(good["command"].get<std::string>().find("--kernel good"), std::string::npos);
  EXPECT_NE(good["result"]["args"].get<std::string>().find("--width 8 --height 4"), std::string::npos);
  EXPECT_EQ(good["image"], "images/" + good["key"].get<std::string>() + ".png");
  EXPECT_TRUE(fs::exists(root / "out" / good["visits_image"].get<std::string>()));

  auto error = [&](const char* kernel) { return byKernel[kernel]["error"].get<std::string>(); };
  EXPECT_NE(error("crash").find("signal 11"), std::string::npos) << error("crash");
  EXPECT_NE(error("crash").find("syntax error"), std::string::npos) << error("crash");
  EXPECT_NE(byKernel["crash"]["log"].get<std::string>().find("0:12(3)"), std::string::npos);
  EXPECT_NE(error("bad-json").find("no JSON object"), std::string::npos) << error("bad-json");
  EXPECT_NE(error("hang").find("timed out"), std::string::npos) << error("hang");
  EXPECT_LT(byKernel["hang"]["wall_s"].get<double>(), 10.0);
  EXPECT_NE(error("exit4").find("exit code 4"), std::string::npos) << error("exit4");
  EXPECT_NE(error("exit4").find("kernel does not compile"), std::string::npos) << error("exit4");
  EXPECT_NE(error("badflag").find("exit code 109: The following arguments were not expected"), std::string::npos)
      << error("badflag");
  for (const char* k : {"crash", "bad-json", "hang", "exit4", "badflag"}) EXPECT_TRUE(byKernel[k]["image"].is_null()) << k;
}

bool reportToolsAvailable() {
  try {
    return runProcess({"/usr/bin/python3", "-c", "import matplotlib"}).ok();
  } catch (const std::exception&) {
    return false;
  }
}

TEST_F(Experiments, ReportHasEveryPlotTableAndFinding) {
  if (!reportToolsAvailable()) GTEST_SKIP() << "/usr/bin/python3 with matplotlib is not installed (python3-matplotlib)";
  FakeRenderer fake;
  const fs::path out = root / "out";
  runSweep(options(kFixtures / "report.toml", out, fake));
  const std::string html = readText(writeReport(out));
  for (const char* id :
       {"id=\"findings\"", "id=\"plot-frame-vs-leaf\"", "id=\"plot-frame-vs-depth\"", "id=\"plot-visits-vs-sah\"",
        "id=\"plot-builders\"", "id=\"plot-pareto\"", "id=\"images-per-builder\"", "id=\"table-results\"",
        "id=\"table-failed\"", "id=\"provenance\"", "data:image/png;base64,"})
    EXPECT_NE(html.find(id), std::string::npos) << id;
  EXPECT_EQ(html.find("http://"), std::string::npos) << "the report must work offline";
  EXPECT_EQ(html.find("https://"), std::string::npos) << "the report must work offline";
  EXPECT_EQ(html.find("id=\"seed-fig8\""), std::string::npos) << "not a seed-figures config";
  // Every run appears in the full table.
  for (const json& row : readJsonFile(out / "results.json")["rows"])
    EXPECT_NE(html.find(row["key"].get<std::string>()), std::string::npos);
}

// The accuracy-vs-time sections: the anti-aliasing table (both time judgements, the edge/non-edge error
// split, crops) and the robustness table, whose hard-case columns come from the real `bvhlab hard-cases`
// run by the sweep (DIR/hard_cases.json) while the frame times are the fake's.
TEST_F(Experiments, AccuracyReportHasTheAntiAliasingAndRobustnessTables) {
  if (!reportToolsAvailable()) GTEST_SKIP() << "/usr/bin/python3 with matplotlib is not installed (python3-matplotlib)";
  FakeRenderer fake;
  const fs::path out = root / "out";
  RunOptions o = options(kFixtures / "accuracy.toml", out, fake);
  o.binary = BVHLAB_BINARY;
  runSweep(o);
  const json hard = readJsonFile(out / "hard_cases.json");
  ASSERT_EQ(hard.value("status", ""), "ok") << hard.dump(1);
  EXPECT_EQ(hard["variants"], json({"fast", "tri", "watertight"}));
  const json& variants = hard["result"]["variants"];
  const auto total = [&](const std::string& v, const char* key) {
    for (const json& x : variants)
      if (x.value("robust", "") == v) return x["total"].value(key, -1);
    return -1;
  };
  EXPECT_EQ(total("watertight", "leaks"), 0);
  EXPECT_GT(total("fast", "leaks"), 0);

  const std::string html = readText(writeReport(out));
  for (const char* id : {"id=\"antialiasing\"", "id=\"aa-", "id=\"robustness\"", "id=\"robustness-table-1\""})
    EXPECT_NE(html.find(id), std::string::npos) << id;
  // The fake's smaa frame is 1.1x none's and ssaa4 4x: added time (1.1 - 1) / (4 - 1) = 0.0333.
  EXPECT_NE(html.find("added time / SSAA 4×"), std::string::npos);
  EXPECT_NE(html.find("<td>0.0333</td>"), std::string::npos);
  EXPECT_NE(html.find("of the error lies in the"), std::string::npos) << "the edge / non-edge split";
  // The robustness table: the fake's ratio to fast, and the hard cases' leak counts per variant.
  const size_t table = html.find("id=\"robustness-table-1\"");
  ASSERT_NE(table, std::string::npos);
  const std::string rows = html.substr(table, html.find("</table>", table) - table);
  for (const char* v : {"<b>fast</b>", "<b>tri</b>", "<b>watertight</b>"}) EXPECT_NE(rows.find(v), std::string::npos) << v;
  EXPECT_NE(rows.find("<td>1.05</td>"), std::string::npos) << "watertight's time ratio to fast";
  EXPECT_NE(rows.find("<td>" + std::to_string(total("fast", "leaks")) + "</td>"), std::string::npos) << rows;
  EXPECT_NE(html.find("watertight takes 1.05× the fast variant's frame time and leaks 0"), std::string::npos);
}

TEST_F(Experiments, SeedFiguresReportMirrorsFigures8To12AndOmitsPlotsWithoutData) {
  if (!reportToolsAvailable()) GTEST_SKIP() << "/usr/bin/python3 with matplotlib is not installed (python3-matplotlib)";
  FakeRenderer fake;
  const fs::path out = root / "out";
  runSweep(options(kFixtures / "seed.toml", out, fake));
  const std::string html = readText(writeReport(out));
  for (const char* id : {"id=\"seed-fig8\"", "id=\"seed-fig9\"", "id=\"seed-fig10\"", "id=\"seed-fig11\"",
                         "id=\"seed-fig12\""})
    EXPECT_NE(html.find(id), std::string::npos) << id;
  // No kernel or aa-with-reference data: the Pareto plot is omitted with a note, not drawn empty.
  EXPECT_NE(html.find("id=\"plot-pareto\""), std::string::npos);
  EXPECT_NE(html.find("no image-error data"), std::string::npos);
}

}  // namespace

namespace {

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
  if (!fs::exists(fs::path(BVHLAB_SOURCE_DIR) / "datasets" / "cache" / "meshes" / "bunny00.off"))
    GTEST_SKIP() << "bunny00.off not fetched (bash datasets/fetch.sh)";
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
