// The command line as a user meets it: the built `reposetwin` run in a temporary folder, its
// exit code and messages checked. Only commands that finish in seconds (the refusals come
// before any work).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "tests/apps/cli_support.hpp"

namespace {
namespace fs = std::filesystem;
using reposetwin::test_support::fresh_dir;
using reposetwin::test_support::touch;
using Result = reposetwin::test_support::CliResult;

Result run(const std::string& args) { return reposetwin::test_support::run_cli(args); }

TEST(Cli, TypoedCommandGetsDidYouMean) {
  const Result r = run("runn --out /nonexistent");
  EXPECT_EQ(r.code, 109) << r.out;
  EXPECT_NE(r.out.find("did you mean 'run'"), std::string::npos) << r.out;
  const Result r2 = run("rendr x");
  EXPECT_NE(r2.out.find("did you mean 'render'"), std::string::npos) << r2.out;
}

TEST(Cli, RangeErrorReadsAsARange) {
  const fs::path d = fresh_dir("range");
  touch(d / "photo.png");
  const Result r = run("measure '" + (d / "photo.png").string() + "' --mm-per-px -1");
  EXPECT_EQ(r.code, 105) << r.out;
  EXPECT_NE(r.out.find("positive"), std::string::npos) << r.out;
  EXPECT_LT(r.out.size(), 300u) << r.out;  // no 300-digit bound
}

TEST(Cli, PlanAboveTheLimitIsRefusedWithoutYes) {
  const fs::path d = fresh_dir("plan") / "run";
  // The quick scene draws about 865 particles: above a limit of 100.
  const Result r = run("run --out '" + d.string() + "' --max-particles 100");
  EXPECT_EQ(r.code, 6) << r.out;
  EXPECT_NE(r.out.find("plan: "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("refused"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("sample.d_min_mm"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("--yes"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(d)) << "nothing may be written for a refused plan";
  // A run within the limits is not refused: a bad key then fails it before it simulates.
  const Result ok = run("run --out '" + d.string() + "' --set scene.nope=1");
  EXPECT_EQ(ok.code, 2) << ok.out;
  EXPECT_EQ(ok.out.find("refused"), std::string::npos) << ok.out;
}

TEST(Cli, RenderRefusesToOverwriteWithoutForce) {
  const fs::path d = fresh_dir("render");
  touch(d / "images" / "measurement.json");
  const Result r = run("render '" + d.string() + "'");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("--force"), std::string::npos) << r.out;
  EXPECT_TRUE(fs::exists(d / "images" / "measurement.json"));
  // With --force it goes on, and stops at the next check: the folder holds no finished run.
  const Result f = run("render '" + d.string() + "' --force");
  EXPECT_EQ(f.code, 2) << f.out;
  EXPECT_NE(f.out.find("result.json"), std::string::npos) << f.out;
  EXPECT_EQ(f.out.find("--force"), std::string::npos) << f.out;
}

TEST(Cli, ReportRefusesToOverwriteWithoutForce) {
  const fs::path d = fresh_dir("report");
  touch(d / "report" / "index.html");
  const Result r = run("report '" + d.string() + "'");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("--force"), std::string::npos) << r.out;
  const Result f = run("report '" + d.string() + "' --force");
  EXPECT_EQ(f.code, 2) << f.out;
  EXPECT_NE(f.out.find("no run, campaign or calibration results"), std::string::npos) << f.out;
}

TEST(Cli, SceneReferenceInDocsIsCurrent) {
  const Result r = run("keys --markdown");
  ASSERT_EQ(r.code, 0) << r.out;
  std::ifstream in(fs::path(REPOSETWIN_SOURCE_DIR) / "docs" / "scene.md");
  std::stringstream s;
  s << in.rdbuf();
  EXPECT_EQ(s.str(), r.out) << "docs/scene.md is not current: regenerate it with "
                               "`reposetwin keys --markdown > docs/scene.md`";
  const Result plain = run("keys");
  EXPECT_NE(plain.out.find("sample.d_min_mm"), std::string::npos);
}

}  // namespace

namespace {

// One command reproduces the paper: --list prints every item of the shipped index with its
// planned runs, CPU-hours and status, and the total against the budget, running nothing.
TEST(Cli, PaperListPrintsEveryItemWithItsCost) {
  const fs::path d = fresh_dir("paper_list");
  const Result r = run("paper '" + std::string(REPOSETWIN_SOURCE_DIR) +
                       "/experiments/paper/index.toml' --list --out '" + (d / "out").string() +
                       "'");
  EXPECT_EQ(r.code, 0) << r.out;
  for (const char* item : {"t3_s1_epsd", "t3_s4_cdt", "fig5_timestep", "fig6_cdt", "fig7",
                           "fig8_s4", "fig10_s4", "fig11_s4", "fig14_s1", "fig18_s4"})
    EXPECT_NE(r.out.find(item), std::string::npos) << item << "\n" << r.out;
  EXPECT_NE(r.out.find("not started"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("within"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(d / "out" / "t3_s1_epsd"));
  // A misspelt key of an index is named with its file, and nothing runs.
  reposetwin::test_support::write_text(d / "index.toml", "title = \"x\"\nbudjet_cpu_hours = 1\n");
  const Result bad = run("paper '" + (d / "index.toml").string() + "' --out '" +
                         (d / "out").string() + "'");
  EXPECT_EQ(bad.code, 2) << bad.out;
  EXPECT_NE(bad.out.find("budjet_cpu_hours"), std::string::npos) << bad.out;
  EXPECT_NE(bad.out.find("index.toml"), std::string::npos) << bad.out;
}

}  // namespace
