// The rays axis of experiment configs: runs that trace a ray workload (`bvhlab trace`) instead of
// rendering frames: config parsing and validation, the command line, and a real sweep through the
// runner to results, findings and the report's ray sections.
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_run.hpp"
#include "datasets/scene.hpp"
#include "experiments/config.hpp"
#include "experiments/executor.hpp"
#include "experiments/process.hpp"
#include "render/workloads.hpp"

namespace {

using namespace bvhlab;
using namespace bvhlab::clitest;
using nlohmann::json;

[[maybe_unused]] ::testing::Environment* const kRemoveTestDir = ::testing::AddGlobalTestEnvironment(new RemoveTestDir);

ExperimentConfig parse(const std::string& text) {
  const fs::path file = writeTemp("rays/cfg.toml", text);
  writeTemp("rays/m.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  return parseExperimentConfig(text, file, registeredNames());
}

TEST(ExperimentRays, AxisExpandsAndOnlyTraceRunsKeyTheTraceSettings) {
  const ExperimentConfig cfg = parse(R"(
[trace]
count = 5000
seed = 3
[axes]
scenes = "m.off"
builders = ["median", "sah-binned"]
rays = ["primary", "diffuse", "ao"]
)");
  ASSERT_EQ(cfg.runs.size(), 6u);
  EXPECT_EQ(cfg.runs[1].axis("workload")->label, "diffuse");
  EXPECT_NE(cfg.runs[0].keyJson().dump().find("\"count\":5000"), std::string::npos);
  // A render run's key does not change with [trace] (configs written before the axis keep their keys).
  const ExperimentConfig plain = parse("[axes]\nscenes = \"m.off\"\n");
  const ExperimentConfig withTrace = parse("[trace]\ncount = 7\n[axes]\nscenes = \"m.off\"\n");
  EXPECT_EQ(plain.runs[0].key, withTrace.runs[0].key);
  // The axis's values are the trace command's workloads.
  EXPECT_EQ(workloadNames().size(), 5u);
}

TEST(ExperimentRays, ValidationNamesTheKey) {
  struct Case {
    const char* text;
    std::vector<std::string> expected;
  };
  const Case cases[] = {
      {"[axes]\nscenes = 'm.off'\nrays = 'difuse'\n", {"cfg.toml:3", "axes.rays", "unknown workload 'difuse'", "diffuse"}},
      {"[axes]\nscenes = 'm.off'\nrays = 'ao'\ndepths = [1, 2]\n", {"axes.rays", "'depth'"}},
      {"[trace]\ncount = 0\n[axes]\nscenes = 'm.off'\n", {"cfg.toml:2", "trace.count"}},
      {"[trace]\nao_radius = 2.0\n[axes]\nscenes = 'm.off'\n", {"cfg.toml:2", "trace.ao_radius", "(0, 1]"}},
      {"[trace]\ncolor = 1\n[axes]\nscenes = 'm.off'\n", {"cfg.toml:2", "trace.color", "unknown key"}},
      {"[trace]\nembree_threads = -1\n[axes]\nscenes = 'm.off'\n", {"cfg.toml:2", "trace.embree_threads"}},
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

TEST(ExperimentRays, TraceRunsRunTheTraceCommand) {
  const ExperimentConfig cfg = parse(R"(
[render]
frames = 6
warmup = 1
[measure]
max_frames = 20
target_ci_pct = 4
[trace]
count = 1234
seed = 9
ao_radius = 0.25
[axes]
scenes = { file = "m.off", eye = [1, 2, 3] }
builders = { name = "sah-binned", bins = 16 }
kernels = "stackless"
leaf_sizes = 2
robust = "fast"
rays = "ao"
)");
  ASSERT_EQ(cfg.runs.size(), 1u);
  RunRequest req{cfg.runs[0], testDir() / "i.png", testDir() / "v.png", "", ""};
  const std::string line = shellQuote(renderCommandLine("/bin/bvhlab", req));
  for (const char* part : {"/bin/bvhlab trace ", "m.off --json --count 1234 --seed 9 --ao-radius 0.25 --frames 6 --warmup 1",
                           "--max-frames 20 --target-ci-pct 4", "--eye 1,2,3", "--builder sah-binned --bins 16",
                           "--kernel stackless", "--leaf-size 2", "--robust fast", "--rays ao"})
    EXPECT_NE(line.find(part), std::string::npos) << part << " not in: " << line;
  for (const char* absent : {" -o ", "--visits-out", "--width", "--embree-threads"})
    EXPECT_EQ(line.find(absent), std::string::npos) << line;
}

// [trace] embree_threads (with env LP_NUM_THREADS, one core per tracer): on the trace command line and
// in the keys of trace runs only when set, so configs without it keep their keys.
TEST(ExperimentRays, EmbreeThreadsReachTheTraceCommandAndOnlyTraceKeys) {
  const char* base = "[axes]\nscenes = 'm.off'\n[[sweep]]\nname = 'a'\nrays = 'primary'\n[[sweep]]\nname = 'b'\n";
  const ExperimentConfig plain = parse(base);
  const ExperimentConfig oneCore = parse(std::string("[render]\nenv = { LP_NUM_THREADS = '1' }\n[trace]\nembree_threads = 1\n") + base);
  const ExperimentConfig oneThread = parse(std::string("[trace]\nembree_threads = 1\n") + base);
  ASSERT_EQ(plain.runs.size(), 2u);
  ASSERT_EQ(oneThread.runs.size(), 2u);
  ASSERT_TRUE(oneThread.runs[0].axis("workload"));
  ASSERT_FALSE(oneThread.runs[1].axis("workload"));
  EXPECT_NE(plain.runs[0].key, oneThread.runs[0].key);  // the traced run: another yardstick, another run
  EXPECT_EQ(plain.runs[1].key, oneThread.runs[1].key);  // the rendered run: unchanged
  const std::string line =
      shellQuote(renderCommandLine("/bin/bvhlab", RunRequest{oneCore.runs[0], testDir() / "i.png", "", "", ""}));
  EXPECT_NE(line.find("--embree-threads 1"), std::string::npos) << line;
  EXPECT_EQ(oneCore.runs[0].render.env.at("LP_NUM_THREADS"), "1");
  // The setting survives the plan file (runs are read back from plan.json on resume).
  EXPECT_EQ(RunSpec::fromJson(oneThread.runs[0].toJson()).render.embreeThreads, 1);
}

// A real sweep: a generated mesh, two builders, two workloads, through `bvhlab run`.
TEST(ExperimentRays, SweepRecordsTraceResultsAndTheReportShowsThem) {
  const fs::path cfg = writeTemp("rays-run/cfg.toml", R"(
[experiment]
name = "rays-test"
description = "trace runs"
[render]
frames = 6
warmup = 1
[measure]
max_frames = 6
[trace]
count = 3000
[axes]
scenes = { generate = "large", triangles = 20000, seed = 2, name = "cloud" }
builders = ["median", "sah-binned"]
rays = ["primary", "diffuse"]
)");
  const fs::path out = testDir() / "rays-run/out";
  Result r = run("run " + cfg.string() + " --out " + out.string());
  ASSERT_EQ(r.code, 0) << r.err;
  std::ifstream in(out / "results.json");
  const json results = json::parse(in);
  size_t traced = 0;
  for (const json& row : results["rows"]) {
    if (row.value("control_of", json()).is_string()) continue;
    ASSERT_EQ(row["status"], "ok") << row.dump();
    ++traced;
    EXPECT_EQ(row["rays"], 3000);
    EXPECT_GT(row["mrays_per_s"].get<double>(), 0.0);
    EXPECT_GT(row["embree_mrays_per_s"].get<double>(), 0.0);
    EXPECT_EQ(row["hit_mismatches"], 0);
    EXPECT_TRUE(row["workload"] == "primary" || row["workload"] == "diffuse");
    EXPECT_FALSE(row["node_visits_per_ray_ci_low"].is_null());
  }
  EXPECT_EQ(traced, 4u);
  std::ifstream fin(out / "findings.json");
  const json findings = json::parse(fin);
  size_t builderComparisons = 0;
  for (const json& c : findings["comparisons"])
    if (c["axis"] == "builder" && c["context"].get<std::string>().find("workload=") != std::string::npos)
      ++builderComparisons;
  EXPECT_GE(builderComparisons, 2u) << findings.dump();
  std::ifstream hin(out / "report.html");
  const std::string html((std::istreambuf_iterator<char>(hin)), {});
  for (const char* id : {"id=\"rays\"", "id=\"rays-table-cloud\"", "visits vs sah-binned", "id=\"plot-scaling\""})
    EXPECT_NE(html.find(id), std::string::npos) << id;
}

}  // namespace
