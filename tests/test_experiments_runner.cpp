// The experiment runner running sweeps (with a fake executor): records with provenance and image error,
// failed runs retried, resume after a kill, shards + merge, and the subprocess executor against a
// shell-script stand-in for `bvhlab render`.
#include "test_experiments_fixture.hpp"

using namespace bvhlab::experiments_test;

namespace {

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
      throw RunFailure("renderer exit code 1: bvhlab: error: fragment shader failed to compile");
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
      EXPECT_NE(row["error"].get<std::string>().find("shader failed to compile"), std::string::npos);
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
  const json rowsOf1 = readJsonFile(root / "merged" / "results.json")["rows"];  // named: a range-for over a temporary's member dangles
  for (const json& row : rowsOf1)
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
  EXPECT_NE(error("badflag").find("exit code 2: bvhlab: error: render: The following argument was not expected"),
            std::string::npos)
      << error("badflag");
  for (const char* k : {"crash", "bad-json", "hang", "exit4", "badflag"}) EXPECT_TRUE(byKernel[k]["image"].is_null()) << k;
}

}  // namespace
