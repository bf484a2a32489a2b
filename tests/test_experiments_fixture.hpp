// Shared by the experiment-runner tests (test_experiments_config.cpp, test_experiments_runner.cpp,
// test_experiments_report.cpp): file helpers, a fake `bvhlab render` executor and the fixture that
// gives each test its own directory. Runs use the fake executor: no GL, no renderer needed.
#pragma once
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
#include "render/frame_stats.hpp"

namespace fs = std::filesystem;
using namespace bvhlab;
using nlohmann::json;

namespace bvhlab::experiments_test {

inline const fs::path kFixtures = fs::path(BVHLAB_SOURCE_DIR) / "tests" / "fixtures" / "experiments";
inline const KnownNames kNames{{"median", "sah-binned", "sah-sweep", "sbvh", "embree", "ploc"}, {"stack-ordered", "stackless"}};

inline void writeText(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

inline std::string readText(const fs::path& p) {
  std::ifstream in(p);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

inline json readJsonFile(const fs::path& p) { return json::parse(readText(p)); }

// Options for a sweep of `configFile` (sweepOptions: of `text`, written there first) into `out`,
// without a report or progress lines; the caller sets the executor (or a real binary).
inline RunOptions quietOptions(const fs::path& configFile, const fs::path& out, const KnownNames& names) {
  RunOptions o;
  o.config = configFile;
  o.outDir = out;
  o.report = false;
  o.progress = false;
  o.names = names;
  return o;
}
inline RunOptions sweepOptions(const fs::path& configFile, const std::string& text, const fs::path& out,
                               const KnownNames& names) {
  writeText(configFile, text);
  return quietOptions(configFile, out, names);
}

// Triangle count from an OFF header ("OFF\nV F E"): lets the fake report mesh/no-mesh scenes.
inline int offTriangles(const fs::path& p) {
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

// What a fake `bvhlab measure` reports for one run of a group session: the frames of its rounds,
// their median with its interval, and the session (the fields findings pair runs by).
inline json fakeMeasuredRun(const std::vector<double>& ms, const std::string& session) {
  const auto ci = medianInterval(ms);
  return {{"frame_ms", medianOf(ms)},
          {"frame_ms_ci_low", ci->low},
          {"frame_ms_ci_high", ci->high},
          {"frame_ms_all", ms},
          {"frames", ms.size()},
          {"session", session}};
}

// Death-test children are fresh processes (threadsafe style re-executes the test binary); this
// variable hands them the parent's directory.
inline constexpr const char* kDeathTestDirEnv = "BVHLAB_EXPERIMENTS_DEATH_TEST_DIR";

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
    RunOptions o = quietOptions(config, out, kNames);
    o.executor = [&fake](RunRequest& r) { return fake(r); };
    return o;
  }

  fs::path root;
};

// Rows without the fields that differ between two executions of the same run.
inline json comparableRows(const fs::path& dir) {
  json rows = readJsonFile(dir / "results.json")["rows"];
  for (json& row : rows)
    for (const char* volatileField : {"started_at", "wall_s", "load_avg_1m_start", "load_avg_1m_end", "steal_pct"})
      row.erase(volatileField);
  return rows;
}

inline constexpr const char* kSweepConfig = R"(
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

}  // namespace bvhlab::experiments_test
