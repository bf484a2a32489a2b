// The layout and triangle-format axes of experiment configs: which kernel each layout runs
// ("default", "all", kernels of another layout dropped from the product), which robustness variants a
// triangle format runs, validation errors with file, line and key, keys of configs without the axes
// unchanged, --layout/--triangles on the render and trace command lines, the rows' layout/bytes columns,
// findings along the axis, the report's layout section, and a real two-layout sweep through
// `bvhlab measure` and `bvhlab trace`.
#include "test_experiments_fixture.hpp"
#include "experiments/findings.hpp"
#include "layout/layouts.hpp"
#include "traversal/kernels.hpp"
#include "require.hpp"

using namespace bvhlab::experiments_test;

namespace {

// Two layouts as the registry has them today; the tests do not depend on which others get registered.
const KnownNames kLayoutNames{{"median", "sah-binned"},
                              {"stack-ordered", "stackless", "bvh2cb-stack-ordered"},
                              {{"v1", "stack-ordered", {"stack-ordered", "stackless"}},
                               {"bvh2-cb", "bvh2cb-stack-ordered", {"bvh2cb-stack-ordered"}}},
                              "v1",
                              {"raw", "precomputed", "indexed"},
                              {{"precomputed", {"tri", "watertight"}}},
                              "watertight"};

class LayoutAxis : public Experiments {
 protected:
  ExperimentConfig parseLayouts(const std::string& text) {
    writeText(root / "m.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    const fs::path file = root / "cfg.toml";
    writeText(file, text);
    return loadExperimentConfig(file, kLayoutNames);
  }
  std::string errorOf(const std::string& text) {
    try {
      parseLayouts(text);
    } catch (const InputError& e) {
      return e.what();
    }
    return "(no error)";
  }
};

std::vector<std::string> pairs(const ExperimentConfig& cfg) {
  std::vector<std::string> out;
  for (const RunSpec& r : cfg.runs)
    out.push_back((r.axis("layout") ? r.axis("layout")->label : "-") + "/" +
                  (r.axis("kernel") ? r.axis("kernel")->label : "-"));
  return out;
}

TEST_F(LayoutAxis, EachLayoutRunsOnlyTheKernelsThatWalkIt) {
  const ExperimentConfig cfg = parseLayouts(R"(
[axes]
scenes = "m.off"
layouts = ["v1", "bvh2-cb"]
kernels = ["stack-ordered", "stackless", "bvh2cb-stack-ordered"]
)");
  // 2 layouts x 3 kernels, of which 3 pairs exist; layout varies slower than kernel (axis order).
  EXPECT_EQ(pairs(cfg), (std::vector<std::string>{"v1/stack-ordered", "v1/stackless", "bvh2-cb/bvh2cb-stack-ordered"}));
  EXPECT_EQ(cfg.axisLabels.at("layout"), (std::vector<std::string>{"v1", "bvh2-cb"}));
}

TEST_F(LayoutAxis, DefaultKernelIsEachLayoutsOwnAndKeysLikeTheNamedKernel) {
  const ExperimentConfig byDefault = parseLayouts(R"(
[axes]
scenes = "m.off"
layouts = ["v1", "bvh2-cb"]
kernels = "default"
)");
  EXPECT_EQ(pairs(byDefault), (std::vector<std::string>{"v1/stack-ordered", "bvh2-cb/bvh2cb-stack-ordered"}));
  const ExperimentConfig named = parseLayouts(R"(
[axes]
scenes = "m.off"
layouts = ["v1", "bvh2-cb"]
kernels = ["stack-ordered", "bvh2cb-stack-ordered"]
)");
  ASSERT_EQ(named.runs.size(), 2u);
  for (size_t i = 0; i < 2; ++i) EXPECT_EQ(byDefault.runs[i].key, named.runs[i].key) << "the same computation";
  // Without a layout axis, "default" is the default layout's kernel.
  const ExperimentConfig plain = parseLayouts("[axes]\nscenes = 'm.off'\nkernels = 'default'\n");
  EXPECT_EQ(pairs(plain), (std::vector<std::string>{"-/stack-ordered"}));
  // No kernel axis: nothing is passed, the renderer runs the layout's default.
  const ExperimentConfig none = parseLayouts("[axes]\nscenes = 'm.off'\nlayouts = ['v1', 'bvh2-cb']\n");
  EXPECT_EQ(pairs(none), (std::vector<std::string>{"v1/-", "bvh2-cb/-"}));
}

// `layouts = "all"` / `kernels = "all"` follow the real registries: a new layout appears without an edit.
TEST_F(LayoutAxis, AllIsEveryRegisteredLayoutAndKernel) {
  writeText(root / "m.off", "OFF\n0 0 0\n");
  const fs::path file = root / "all.toml";
  writeText(file, "[axes]\nscenes = 'm.off'\nlayouts = 'all'\nkernels = 'all'\n");
  const ExperimentConfig cfg = loadExperimentConfig(file, registeredNames());
  EXPECT_EQ(cfg.runs.size(), allKernels().size()) << "every kernel once, with the layout it walks";
  for (const RunSpec& r : cfg.runs)
    EXPECT_EQ(findKernel(r.axis("kernel")->label).layout, r.axis("layout")->label) << r.describe();
  writeText(file, "[axes]\nscenes = 'm.off'\nlayouts = 'all'\nkernels = 'default'\n");
  const ExperimentConfig defaults = loadExperimentConfig(file, registeredNames());
  ASSERT_EQ(defaults.runs.size(), layouts().size());
  for (size_t i = 0; i < layouts().size(); ++i) {
    EXPECT_EQ(defaults.runs[i].axis("layout")->label, layouts()[i].name);
    EXPECT_EQ(defaults.runs[i].axis("kernel")->label, layouts()[i].defaultKernel);
  }
  // The pairs a triangle format refuses come from its own check (layout/triangle_formats.hpp).
  const KnownNames names = registeredNames();
  const auto& precomputed = names.triangleFormatRefuses.at("precomputed");
  std::string refused;
  for (const std::string& v : precomputed) refused += v + " ";
  EXPECT_NE(std::find(precomputed.begin(), precomputed.end(), "watertight"), precomputed.end()) << refused;
  EXPECT_EQ(std::find(precomputed.begin(), precomputed.end(), "fast"), precomputed.end());
  EXPECT_TRUE(names.triangleFormatRefuses.at("raw").empty());
}

TEST_F(LayoutAxis, ValidationErrorsNameTheFileLineAndKey) {
  struct Case {
    const char* text;
    std::vector<std::string> expected;
  };
  const Case cases[] = {
      {"[axes]\nscenes = 'm.off'\nlayouts = ['v1', 'bvh3']\n",
       {"cfg.toml:3", "axes.layouts[1]", "unknown layout 'bvh3'", "valid: v1, bvh2-cb"}},
      {"[axes]\nscenes = 'm.off'\nlayouts = ['all']\n", {"cfg.toml:3", "axes.layouts[0]", "unknown layout 'all'"}},
      // A kernel of a layout the runs do not use: named with the layout to add.
      {"[axes]\nscenes = 'm.off'\nkernels = ['stack-ordered', 'bvh2cb-stack-ordered']\n",
       {"cfg.toml:3", "axes.kernels[1]", "walks layout bvh2-cb", "v1 (the default", "add \"bvh2-cb\" to `layouts`"}},
      {"[axes]\nscenes = 'm.off'\nlayouts = 'bvh2-cb'\n\nkernels = ['stackless', 'bvh2cb-stack-ordered']\n",
       {"cfg.toml:5", "axes.kernels[0]", "kernel 'stackless' walks layout v1", "use bvh2-cb"}},
      {"[axes]\nscenes = 'm.off'\nlayouts = 'v1'\n[[sweep]]\nname = 's'\nkernels = 'bvh2cb-stack-ordered'\n",
       {"cfg.toml:6", "sweep[0].kernels[0]", "walks layout bvh2-cb"}},
      {"[axes]\nscenes = 'm.off'\nkernels = 'stack-orderd'\n", {"cfg.toml:3", "unknown kernel 'stack-orderd'", "default"}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.text);
    const std::string what = errorOf(c.text);
    for (const std::string& s : c.expected) EXPECT_NE(what.find(s), std::string::npos) << what;
  }
}

// A triangle format runs only with the robustness variants it can (precomputed: not the watertight test).
TEST_F(LayoutAxis, TriangleFormatsKeepTheRunsTheirRobustnessCanRun) {
  const ExperimentConfig cfg = parseLayouts(R"(
[axes]
scenes = "m.off"
triangle_formats = ["raw", "precomputed", "indexed"]
robust = ["fast", "watertight"]
)");
  std::vector<std::string> runs;
  for (const RunSpec& r : cfg.runs) runs.push_back(r.axis("triangle_format")->label + "/" + r.axis("robust")->label);
  EXPECT_EQ(runs, (std::vector<std::string>{"raw/fast", "raw/watertight", "precomputed/fast", "indexed/fast",
                                            "indexed/watertight"}));
  RunRequest req{cfg.runs[2], root / "i.png", "", "", ""};
  EXPECT_NE(shellQuote(renderCommandLine("/bin/bvhlab", req)).find("--triangles precomputed"), std::string::npos);
  // No robust axis: the renderer's default (watertight) decides; "all" keeps what runs.
  const ExperimentConfig all = parseLayouts("[axes]\nscenes = 'm.off'\ntriangle_formats = 'all'\n");
  ASSERT_EQ(all.runs.size(), 2u);
  EXPECT_EQ(all.runs[1].axis("triangle_format")->label, "indexed");
  const std::string what = errorOf("[axes]\nscenes = 'm.off'\n\ntriangle_formats = ['raw', 'precomputed']\n");
  for (const char* part : {"cfg.toml:4", "axes.triangle_formats[1]", "'precomputed' cannot run robust watertight",
                           "(the default", "runs with robust fast"})
    EXPECT_NE(what.find(part), std::string::npos) << what;
  EXPECT_NE(errorOf("[axes]\nscenes = 'm.off'\ntriangle_formats = 'packed'\n").find("unknown triangle format 'packed'"),
            std::string::npos);
}

// Keys of configs without the axis are what they were before it existed: this key was computed by the
// bvhlab of commit abc99f1 (`bvhlab run` on this config, plan.json). Finished sweeps keep their runs.
TEST_F(LayoutAxis, KeysOfConfigsWithoutTheAxisAreUnchanged) {
  const ExperimentConfig cfg = parseLayouts(R"(
[render]
width = 8
height = 4
frames = 1
warmup = 0
[axes]
scenes = "m.off"
builders = "sah-binned"
kernels = "stack-ordered"
leaf_sizes = 4
)");
  ASSERT_EQ(cfg.runs.size(), 1u);
  EXPECT_EQ(cfg.runs[0].key, "6b8ca464e7a05d9d");
  EXPECT_EQ(cfg.runs[0].keyJson()["axes"].count("layout"), 0u);
}

TEST_F(LayoutAxis, RenderAndTraceCommandLinesCarryTheLayout) {
  const ExperimentConfig cfg = parseLayouts(R"(
[axes]
scenes = "m.off"
layouts = "bvh2-cb"
kernels = "default"
[[sweep]]
name = "render"
[[sweep]]
name = "trace"
rays = "diffuse"
)");
  ASSERT_EQ(cfg.runs.size(), 2u);
  for (const RunSpec& run : cfg.runs) {
    RunRequest req{run, root / "i.png", "", "", ""};
    const std::string line = shellQuote(renderCommandLine("/bin/bvhlab", req));
    EXPECT_NE(line.find("--layout bvh2-cb --kernel bvh2cb-stack-ordered"), std::string::npos) << line;
  }
}

// The fake renderer reports what the real one does for a layout: its name, kernel and memory.
json fakeWithLayout(FakeRenderer& fake, RunRequest& req) {
  json out = fake(req);
  const std::string layout = req.spec.axis("layout") ? req.spec.axis("layout")->label : "v1";
  const double perTriangle = layout == "v1" ? 148.9 : 120.5;
  out["layout"] = layout;
  out["kernel"] = req.spec.axis("kernel") ? req.spec.axis("kernel")->label : "stack-ordered";
  out["bytes"] = perTriangle * out["triangles"].get<double>();
  out["bytes_per_triangle"] = perTriangle;
  out["node_bytes_per_ray"] = layout == "v1" ? 96.25 : 680.5;  // bytes fetched per ray (trace's mirror pass)
  out["triangle_bytes_per_ray"] = 48.0;
  out["stack_bytes_per_ray"] = 24.0;
  out["frame_ms"] = out["frame_ms"].get<double>() * (layout == "v1" ? 1.0 : 0.8);
  return out;
}

constexpr const char* kTwoLayouts = R"(
[experiment]
name = "layouts-test"
description = "two layouts"
[render]
width = 8
height = 4
[axes]
scenes = ["a.off", "b.off"]
builders = ["median", "sah-binned"]
layouts = ["v1", "bvh2-cb"]
kernels = ["stack-ordered", "stackless", "bvh2cb-stack-ordered"]
)";

TEST_F(LayoutAxis, RowsCarryLayoutAndMemoryAndFindingsCompareLayouts) {
  writeText(root / "a.off", "OFF\n0 10 0\n");
  writeText(root / "b.off", "OFF\n0 20 0\n");
  writeText(root / "cfg.toml", kTwoLayouts);
  FakeRenderer fake;
  RunOptions o = options(root / "cfg.toml", root / "out", fake);
  o.names = kLayoutNames;
  o.executor = [&fake](RunRequest& r) { return fakeWithLayout(fake, r); };
  runSweep(o);
  const json results = readJsonFile(root / "out" / "results.json");
  const std::vector<std::string> columns = results["columns"];
  for (const char* c : {"layout", "bytes", "bytes_per_triangle"})
    EXPECT_NE(std::find(columns.begin(), columns.end(), c), columns.end()) << c;
  size_t bvh2cb = 0;
  for (const json& row : results["rows"]) {
    ASSERT_EQ(row["status"], "ok") << row.dump();
    if (row["layout"] == "bvh2-cb") {
      ++bvh2cb;
      EXPECT_EQ(row["kernel"], "bvh2cb-stack-ordered");
      EXPECT_EQ(row["bytes_per_triangle"], 120.5);
    }
  }
  EXPECT_EQ(bvh2cb, 4u);  // 2 scenes x 2 builders
  const std::string csv = readText(root / "out" / "results.csv");
  EXPECT_NE(csv.find(",layout,triangle_format,kernel,"), std::string::npos);

  // Along the layout axis each layout at its first kernel in config order (v1: stack-ordered, not
  // stackless) against the baseline layout (v1, the config's first), the builder held equal.
  const json findings = readJsonFile(root / "out" / "findings.json");
  size_t layoutComparisons = 0;
  for (const json& c : findings["comparisons"]) {
    if (c["axis"] != "layout") continue;
    ++layoutComparisons;
    EXPECT_EQ(c["a_label"], "bvh2-cb");
    EXPECT_EQ(c["b_label"], "v1");
    EXPECT_EQ(c["b_values"]["kernel"], "stack-ordered") << c.dump();
    EXPECT_EQ(c["a_values"]["kernel"], "bvh2cb-stack-ordered") << c.dump();
    EXPECT_NEAR(c["ratio"].get<double>(), 0.8, 1e-9);
  }
  EXPECT_EQ(layoutComparisons, 4u) << "one per scene and builder";
}

// Traced runs are separate processes: compared through the Embree rounds each traced beside its own, so
// a machine twice as slow during one of them does not make its layout look twice as slow.
TEST(LayoutFindings, TracedRunsOfTwoProcessesAreComparedThroughTheirEmbreeRounds) {
  auto traced = [](const char* key, const char* layout, double machine) {
    json glsl = json::array(), embree = json::array();
    for (int i = 0; i < 12; ++i) {
      glsl.push_back(machine * (20.0 + 0.25 * (i % 4)));
      embree.push_back(machine * (10.0 + 0.125 * (i % 4)));
    }
    return json{{"key", key},        {"status", "ok"},      {"scene", "s"},        {"layout", layout},
                {"workload", "diffuse"}, {"frame_ms", machine * 20.25}, {"frame_ms_all", glsl},
                {"embree_ms_all", embree}};
  };
  const json rows = json::array({traced("a", "v1", 1.0), traced("b", "bvh2-cb", 2.0)});
  const json findings = computeFindings(rows, json::object());
  ASSERT_EQ(findings["comparisons"].size(), 1u) << findings.dump();
  const json& c = findings["comparisons"][0];
  EXPECT_EQ(c["axis"], "layout");
  EXPECT_EQ(c["normalised_by"], "embree");
  EXPECT_NEAR(c["ratio"].get<double>(), 1.0, 1e-9);
  // Two processes and no band measured between processes (no replicates): not called.
  EXPECT_EQ(c["verdict"], "not called: no noise band");
}

bool reportToolsAvailable() {
  try {
    return runProcess({"/usr/bin/python3", "-c", "import matplotlib"}).ok();
  } catch (const std::exception&) {
    return false;
  }
}

TEST_F(LayoutAxis, ReportHasALayoutTablePerSceneAndTheMemoryPlot) {
  if (!reportToolsAvailable()) BVHLAB_SKIP_OR_FAIL("/usr/bin/python3 with matplotlib is not installed (python3-matplotlib)");
  writeText(root / "a.off", "OFF\n0 10 0\n");
  writeText(root / "b.off", "OFF\n0 20 0\n");
  writeText(root / "cfg.toml", kTwoLayouts);
  FakeRenderer fake;
  RunOptions o = options(root / "cfg.toml", root / "out", fake);
  o.names = kLayoutNames;
  o.executor = [&fake](RunRequest& r) { return fakeWithLayout(fake, r); };
  runSweep(o);
  const std::string html = readText(writeReport(root / "out"));
  for (const char* id : {"id=\"layouts\"", "id=\"layouts-table-a\"", "id=\"layouts-table-b\"",
                         "id=\"plot-layout-memory\"", "What memory costs in time", "bytes/triangle", "node bytes/ray",
                         "triangle bytes/ray", "stack bytes/ray"})
    EXPECT_NE(html.find(id), std::string::npos) << id;
  const size_t table = html.find("id=\"layouts-table-a\"");
  ASSERT_NE(table, std::string::npos);
  const std::string rows = html.substr(table, html.find("</table>", table) - table);
  for (const char* cell : {"<b>bvh2-cb</b>", "<b>v1</b>", "<td>120.5</td>", "<td>148.9</td>", "<td>680.5</td>", "<td>96.25</td>"})
    EXPECT_NE(rows.find(cell), std::string::npos) << cell << " in " << rows;
  EXPECT_EQ(html.find("Plot omitted: no run reported bytes_per_triangle"), std::string::npos);
}

// A real sweep: v1 and bvh2-cb with their default kernels, rendered (one interleaved group) and traced.
TEST_F(LayoutAxis, RealSweepOverTwoLayoutsRendersAndTracesBoth) {
  writeText(root / "cfg.toml", R"(
[experiment]
name = "layouts-real"
description = "two layouts, real renderer"
[render]
width = 32
height = 16
frames = 3
warmup = 1
[measure]
max_frames = 3
aa_control = false
[trace]
count = 2000
[axes]
scenes = { generate = "large", triangles = 5000, seed = 3, name = "cloud" }
layouts = ["v1", "bvh2-cb"]
kernels = "default"
[[sweep]]
name = "render"
[[sweep]]
name = "trace"
rays = "primary"
)");
  RunOptions o;
  o.config = root / "cfg.toml";
  o.outDir = root / "out";
  o.report = false;
  o.progress = false;
  o.binary = BVHLAB_BINARY;
  const SweepOutcome outcome = runSweep(o);
  EXPECT_EQ(outcome.failed, 0u);
  const json results = readJsonFile(root / "out" / "results.json");
  std::map<std::string, double> bytes;  // layout -> bytes per triangle
  size_t rows = 0;
  for (const json& row : results["rows"]) {
    ASSERT_EQ(row["status"], "ok") << row.dump();
    ++rows;
    const std::string layout = row["layout"];
    EXPECT_EQ(row["kernel"], findLayout(layout).defaultKernel);
    EXPECT_GT(row["bytes_per_triangle"].get<double>(), 0.0);
    if (row.value("workload", json()).is_string()) {
      EXPECT_EQ(row.value("hit_mismatches", -1), 0) << layout;
      EXPECT_GT(row.value("node_bytes_per_ray", 0.0), 0.0) << layout << ": trace's mirror pass counts bytes";
    }
    bytes[layout] = row["bytes_per_triangle"].get<double>();
  }
  EXPECT_EQ(rows, 4u);
  EXPECT_EQ(bytes.size(), 2u);
}

}  // namespace
