// The experiment runner's HTML report (report.py) on sweeps run with a fake executor: every plot, table
// and finding, the accuracy-vs-time tables, and the seed-figures report.
#include <cstdio>
#include <functional>
#include <regex>

#include "experiments/provenance.hpp"
#include "test_experiments_fixture.hpp"
#include "require.hpp"

using namespace bvhlab::experiments_test;

namespace {

bool reportToolsAvailable() {
  try {
    return runProcess({"/usr/bin/python3", "-c", "import matplotlib"}).ok();
  } catch (const std::exception&) {
    return false;
  }
}

// Every <img> of a page has alt text.
void expectAltOnEveryImage(const std::string& html) {
  size_t images = 0;
  for (size_t img = html.find("<img"); img != std::string::npos; img = html.find("<img", img + 1), ++images)
    EXPECT_NE(html.substr(img, html.find('>', img) - img).find(" alt=\""), std::string::npos) << html.substr(img, 120);
  EXPECT_GT(images, 0u);
}

TEST_F(Experiments, ReportHasEveryPlotTableAndFinding) {
  if (!reportToolsAvailable()) BVHLAB_SKIP_OR_FAIL("/usr/bin/python3 with matplotlib is not installed (python3-matplotlib)");
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
  expectAltOnEveryImage(html);
  // Every run appears in the full table.
  const json rowsOf1 = readJsonFile(out / "results.json")["rows"];  // named: a range-for over a temporary's member dangles
  for (const json& row : rowsOf1)
    EXPECT_NE(html.find(row["key"].get<std::string>()), std::string::npos);
}

// The accuracy-vs-time sections: the anti-aliasing table (both time judgements, the edge/non-edge error
// split, crops) and the robustness table, whose hard-case columns come from the real `bvhlab hard-cases`
// run by the sweep (DIR/hard_cases.json) while the frame times are the fake's.
TEST_F(Experiments, AccuracyReportHasTheAntiAliasingAndRobustnessTables) {
  if (!reportToolsAvailable()) BVHLAB_SKIP_OR_FAIL("/usr/bin/python3 with matplotlib is not installed (python3-matplotlib)");
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
  if (!reportToolsAvailable()) BVHLAB_SKIP_OR_FAIL("/usr/bin/python3 with matplotlib is not installed (python3-matplotlib)");
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
  expectAltOnEveryImage(html);
}

// The machine's load over a group: steal as a share of the CPU time that passed, nothing from unknown samples.
TEST(MachineLoad, StealIsTheShareOfCpuTimeThatPassed) {
  MachineLoad a{true, 1.5, 1000, 10}, b{true, 2.5, 1200, 20};
  const json load = machineLoadDuring(a, b);
  EXPECT_DOUBLE_EQ(load["load_avg_1m_start"].get<double>(), 1.5);
  EXPECT_DOUBLE_EQ(load["load_avg_1m_end"].get<double>(), 2.5);
  EXPECT_DOUBLE_EQ(load["steal_pct"].get<double>(), 5.0);  // 10 of 200 jiffies
  EXPECT_TRUE(machineLoadDuring(a, a)["steal_pct"].is_null()) << "no CPU time passed";
  EXPECT_EQ(machineLoadDuring(MachineLoad{}, b), json::object());
  const MachineLoad now = machineLoadNow();
  if (fs::exists("/proc/loadavg") && fs::exists("/proc/stat")) {
    EXPECT_TRUE(now.known);
    EXPECT_GE(now.loadAvg1m, 0.0);
    EXPECT_GT(now.totalJiffies, 0u);
  }
}

// Every measured run's row carries its group's load: the sweep's rows read from /proc around each run.
TEST_F(Experiments, RowsCarryTheirGroupsMachineLoad) {
  if (!fs::exists("/proc/loadavg") || !fs::exists("/proc/stat")) BVHLAB_SKIP_OR_FAIL("no /proc/loadavg or /proc/stat");
  FakeRenderer fake;
  const fs::path out = root / "out";
  runSweep(options(kFixtures / "report.toml", out, fake));
  const json rows = readJsonFile(out / "results.json")["rows"];
  ASSERT_FALSE(rows.empty());
  for (const json& row : rows) {
    SCOPED_TRACE(row["key"].get<std::string>());
    ASSERT_TRUE(row.contains("load_avg_1m_start") && row["load_avg_1m_start"].is_number()) << row.dump();
    EXPECT_GE(row["load_avg_1m_end"].get<double>(), 0.0);
    if (!row["steal_pct"].is_null()) {
      EXPECT_GE(row["steal_pct"].get<double>(), 0.0);
      EXPECT_LE(row["steal_pct"].get<double>(), 100.0);
    }
  }
}

// The report's first screen (experiments/report_summary.py) from a hand-made results directory
// (tests/fixtures/experiments/summary) whose findings.json follows format 2: comparisons of each builder
// with the baseline builder at two kernels and three ray types, one against a non-baseline builder and a
// kernel comparison, none of which may become a cell except the baseline kernel's builder comparisons.
class SummaryReport : public Experiments {
 protected:
  void SetUp() override {
    Experiments::SetUp();
    results = readJsonFile(kFixtures / "summary" / "results.json");
    findings = readJsonFile(kFixtures / "summary" / "findings.json");
  }
  // report.html of the fixture with `edit` applied to every row first.
  std::string render(const std::function<void(json&)>& edit = {}) {
    const fs::path out = root / ("out" + std::to_string(++renders));
    json r = results;
    if (edit)
      for (json& row : r["rows"]) edit(row);
    writeText(out / "results.json", r.dump(1));
    writeText(out / "findings.json", findings.dump(1));
    return readText(writeReport(out));
  }
  json results, findings;
  int renders = 0;
};

std::string ratioText(const json& c) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "%.3f\u00d7 <span class=\"ci\">[%.3f, %.3f]</span>", c["ratio"].get<double>(),
                c["ci_low"].get<double>(), c["ci_high"].get<double>());
  return buf;
}

TEST_F(SummaryReport, OpensWithABuilderByRayTypeTableWhoseCellsAreFindingsJson) {
  if (!reportToolsAvailable()) BVHLAB_SKIP_OR_FAIL("/usr/bin/python3 with matplotlib is not installed (python3-matplotlib)");
  const std::string html = render();
  const size_t summary = html.find("id=\"summary\""), firstFinding = html.find("id=\"findings\"");
  ASSERT_NE(summary, std::string::npos);
  ASSERT_NE(firstFinding, std::string::npos);
  EXPECT_LT(summary, firstFinding) << "the summary is the first section";
  EXPECT_EQ(html.find("id=\"busy-machine\""), std::string::npos) << "an idle machine gets no warning";

  const json& baselines = findings["baselines"];
  const std::regex cell(
      R"re(<td class="cell (c-[a-z]+)" data-a="([^"]*)" data-b="([^"]*)" data-verdict="([^"]*)">(.*?)</td>)re");
  const std::map<std::string, std::vector<std::string>> columns = {{"bunny", {"frames", "primary", "diffuse"}},
                                                                   {"cloud", {"frames"}}};
  for (const auto& [scene, cols] : columns) {
    SCOPED_TRACE(scene);
    const size_t at = html.find("<table class=\"summary\" id=\"summary-" + scene + "\" data-scene=\"" + scene + "\">");
    ASSERT_NE(at, std::string::npos) << "no summary table";
    const std::string table = html.substr(at, html.find("</table>", at) - at);
    std::string header;
    for (const std::string& c : cols) header += "<th>" + c + "</th>";
    EXPECT_NE(table.find("<th>builder</th>" + header + "</tr>"), std::string::npos) << table.substr(0, 300);
    EXPECT_NE(table.find("<tr data-builder=\"sah-binned\"><td>sah-binned</td><td class=\"base\">baseline</td>"),
              std::string::npos);

    // The cells a reader must see: every builder against the baseline builder at the baseline kernel.
    std::set<std::pair<std::string, std::string>> expected, seen;
    for (const json& c : findings["comparisons"]) {
      if (c["scene"] != scene || c["axis"] != "builder" || c["kind"] != "axis" || !c["baseline"].get<bool>()) continue;
      bool atBaseline = true;
      for (const auto& [axis, value] : baselines.items())
        if (axis != "builder" && c["a_values"].contains(axis)) atBaseline = atBaseline && c["a_values"][axis] == value;
      if (atBaseline) expected.insert({c["a"].get<std::string>(), c["b"].get<std::string>()});
    }
    ASSERT_EQ(expected.size(), 3 * cols.size()) << "the fixture: 3 builders beside the baseline per column";

    for (auto m = std::sregex_iterator(table.begin(), table.end(), cell); m != std::sregex_iterator(); ++m) {
      const std::string cls = (*m)[1], a = (*m)[2], b = (*m)[3], verdict = (*m)[4], text = (*m)[5];
      SCOPED_TRACE(a + " / " + b);
      seen.insert({a, b});
      const json* found = nullptr;
      for (const json& c : findings["comparisons"])
        if (c["a"] == a && c["b"] == b) found = &c;
      ASSERT_NE(found, nullptr) << "a cell findings.json does not have";
      const json& c = *found;
      EXPECT_EQ(c["scene"], scene);
      EXPECT_EQ(verdict, c["verdict"].get<std::string>());
      EXPECT_NE(text.find(ratioText(c)), std::string::npos) << text;
      EXPECT_NE(text.find("<span class=\"verdict\">" + c["verdict"].get<std::string>() + "</span>"), std::string::npos)
          << text;
      const std::string v = c["verdict"];
      EXPECT_EQ(cls, v == "faster" ? "c-faster" : v == "slower" ? "c-slower" : "c-none") << "colour of " << v;
    }
    EXPECT_EQ(seen, expected);
  }
  // The fixture's kernel comparison (1.6x slower) and its median-vs-lbvh one (0.5x) are nowhere in a table.
  const std::string tables = html.substr(summary, firstFinding - summary);
  EXPECT_EQ(tables.find("1.600\u00d7"), std::string::npos);
  EXPECT_EQ(tables.find("0.500\u00d7"), std::string::npos);
  // The leaf-size plot draws findings.json's ratios to the baseline leaf size (the depth plot has none: a note).
  const size_t leaf = html.find("id=\"plot-frame-vs-leaf\"");
  ASSERT_NE(leaf, std::string::npos);
  EXPECT_EQ(html.find("<figure><img src=\"data:image/png;base64,", leaf), html.find("<figure>", leaf));
  EXPECT_LT(html.find("<figure>", leaf), html.find("id=\"plot-frame-vs-depth\""));
  EXPECT_NE(html.find("Plot omitted: findings.json has no comparison along depth"), std::string::npos);
  // Time ratio vs cost ratio: drawn from the builder comparisons' SAH counts.
  const size_t costs = html.find("id=\"plot-time-vs-costs\"");
  ASSERT_NE(costs, std::string::npos);
  EXPECT_LT(html.find("<figure><img src=\"data:image/png;base64,", costs), html.find("id=\"plot-visits-vs-sah\""));
  // Noise floor and machine load lines under each table; alt text on every image of the page.
  EXPECT_NE(tables.find("Noise floor (A/A band of each group, 3): "), std::string::npos);
  EXPECT_NE(tables.find("0.40\u21920.60, steal 0.0%"), std::string::npos);
  expectAltOnEveryImage(html);
}

// The warning banner: shown iff some group ran on a busy machine (load average above the cores, or more than
// 3% of CPU time stolen) and runs of those groups missed the config's interval target.
TEST_F(SummaryReport, BusyMachineBannerFollowsTheRecordedLoad) {
  if (!reportToolsAvailable()) BVHLAB_SKIP_OR_FAIL("/usr/bin/python3 with matplotlib is not installed (python3-matplotlib)");
  const std::string banner = "id=\"busy-machine\"";
  const auto wide = [](json& row) { row["ci_pct"] = 3.5; };  // the target is 2%
  EXPECT_EQ(render(wide).find(banner), std::string::npos) << "idle (load 0.4-0.6 on 2 cores, no steal)";
  const std::string loaded = render([&](json& row) {
    wide(row);
    if (row["scene"] == "cloud") row["load_avg_1m_end"] = 3.2;
  });
  EXPECT_NE(loaded.find(banner), std::string::npos) << "load 3.2 on 2 cores";
  EXPECT_NE(loaded.find("1 of 4 groups ran at a load average up to 3.20 on 2 cores. 8 of their 8 runs"),
            std::string::npos);
  EXPECT_NE(render([&](json& row) {
              wide(row);
              row["steal_pct"] = 12.5;
            }).find(banner),
            std::string::npos)
      << "12.5% of CPU time stolen";
  EXPECT_EQ(render([](json& row) { row["load_avg_1m_start"] = 6.0; }).find(banner), std::string::npos)
      << "busy, but every interval met its 2% target";
  // Rows without the load fields (measured before they existed): no banner and a line saying so.
  const std::string old = render([&](json& row) {
    wide(row);
    for (const char* k : {"load_avg_1m_start", "load_avg_1m_end", "steal_pct"}) row.erase(k);
  });
  EXPECT_EQ(old.find(banner), std::string::npos);
  EXPECT_NE(old.find("Machine load: not recorded"), std::string::npos);
}

}  // namespace
