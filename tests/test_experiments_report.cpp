// The experiment runner's HTML report (report.py) on sweeps run with a fake executor: every plot, table
// and finding, the accuracy-vs-time tables, and the seed-figures report.
#include "test_experiments_fixture.hpp"

using namespace bvhlab::experiments_test;

namespace {

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
  const json rowsOf1 = readJsonFile(out / "results.json")["rows"];  // named: a range-for over a temporary's member dangles
  for (const json& row : rowsOf1)
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
