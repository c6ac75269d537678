// No headline without a pile, through the command as a user runs it: a run stopped by the time
// limit, one whose pile did not settle, one whose outlet jammed and one whose photographs could
// not be written each print the reason instead of an angle, exit with their own code, write
// headline_angle_deg = null with the reason in result.json, and say so on their page. A scene
// without gravity is refused before anything runs. Each run is the tiny scene cut short by tiny
// limits (a few seconds).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "cli_support.hpp"

namespace reposetwin::test_support {
namespace {

const fs::path kTiny = fs::path(REPOSETWIN_SOURCE_DIR) / "data" / "loop" / "tiny_scene.toml";

struct NoHeadlineRun {
  CliResult cli;
  nlohmann::json result;
  std::string page;
};

NoHeadlineRun run_tiny(const std::string& name, const std::string& args) {
  const fs::path out = fresh_dir(name) / "run";
  NoHeadlineRun r;
  r.cli = run_cli("run " + quoted(kTiny) + " --out " + quoted(out) + " --quiet " + args);
  if (fs::exists(out / "result.json"))
    r.result = nlohmann::json::parse(read_text(out / "result.json"));
  r.page = read_text(out / "summary.html");
  return r;
}

// What every run without a headline shows: no angle on the last line, the reason in its place,
// headline_angle_deg null with the reason's word in result.json, and a page that says so and
// never blames a flag nobody passed.
void expect_no_headline(const NoHeadlineRun& r, int code, const std::string& word,
                        const std::string& says) {
  EXPECT_EQ(r.cli.code, code) << r.cli.out;
  EXPECT_EQ(r.cli.out.find("angle of repose "), std::string::npos) << r.cli.out;
  EXPECT_NE(r.cli.out.find("no angle of repose: "), std::string::npos) << r.cli.out;
  EXPECT_NE(r.cli.out.find(says), std::string::npos) << r.cli.out;
  EXPECT_NE(r.cli.out.find("try: "), std::string::npos) << r.cli.out;
  ASSERT_TRUE(r.result.contains("headline_angle_deg")) << r.result.dump();
  EXPECT_TRUE(r.result["headline_angle_deg"].is_null());
  EXPECT_EQ(r.result["no_headline"]["reason"], word);
  EXPECT_NE(r.result["no_headline"]["message"].get<std::string>().find(says), std::string::npos);
  EXPECT_NE(r.page.find("No angle of repose"), std::string::npos);
  EXPECT_NE(r.page.find(says), std::string::npos);
  EXPECT_EQ(r.page.find("--no-images"), std::string::npos);
}

TEST(NoHeadline, ARunStoppedByTheTimeLimitWhileFillingHasNoAngle) {
  const NoHeadlineRun r = run_tiny("time_limit", "--set procedure.max_time_s=0.05");
  expect_no_headline(r, 7, "time_limit", "procedure.max_time_s = 0.05 s reached while filling");
}

TEST(NoHeadline, ARunWhosePileDidNotSettleHasNoAngle) {
  // The last settling may last 0.02 s, far less than the 0.1 s a pile needs at the least.
  const NoHeadlineRun r = run_tiny("unsettled", "--set procedure.final_settle_max_s=0.02");
  expect_no_headline(r, 7, "not_settled", "the pile did not settle");
  EXPECT_NE(r.cli.out.find("procedure.final_settle_max_s = 0.02 s"), std::string::npos)
      << r.cli.out;
}

TEST(NoHeadline, AJammedOutletHasNoAngle) {
  // An outlet of two grain diameters arches at once; a short window sees the flow stop.
  const NoHeadlineRun r = run_tiny(
      "jammed", "--set container.bottom_diameter_m=0.007 --set procedure.clog_window_s=0.1");
  expect_no_headline(r, 7, "jam", "jammed: the outlet clogged");
  EXPECT_NE(r.cli.out.find("lodged in the container"), std::string::npos) << r.cli.out;
}

TEST(NoHeadline, PhotographsThatCannotBeWrittenAreAnErrorNotAFallback) {
  const fs::path out = fresh_dir("unwritable") / "run";
  // A folder where the top photograph should be: the run folder holds no file, so it is a
  // fresh run's (experiments/pile/run_folder.hpp), and the photograph cannot be written (root
  // ignores permission bits, so a read-only images/ would not stop it).
  fs::create_directories(out / "images" / "top.png");
  const CliResult cli = run_cli("run " + quoted(kTiny) + " --out " + quoted(out) + " --quiet");
  EXPECT_EQ(cli.code, 8) << cli.out;
  EXPECT_EQ(cli.out.find("angle of repose "), std::string::npos) << cli.out;
  EXPECT_NE(cli.out.find("the photographs could not be taken"), std::string::npos) << cli.out;
  EXPECT_NE(cli.out.find((out / "images").string()), std::string::npos) << cli.out;
  const nlohmann::json r = nlohmann::json::parse(read_text(out / "result.json"));
  EXPECT_TRUE(r["headline_angle_deg"].is_null());
  EXPECT_EQ(r["no_headline"]["reason"], "photographs");
  EXPECT_EQ(read_text(out / "summary.html").find("--no-images"), std::string::npos);
}

TEST(NoHeadline, NoGravityIsRefusedBeforeAnythingRuns) {
  const fs::path out = fresh_dir("no_gravity") / "run";
  for (const char* g : {"0", "-9.81"}) {
    const CliResult cli = run_cli("run " + quoted(kTiny) + " --out " + quoted(out) +
                                  " --quiet --set numerics.gravity_m_s2=" + g);
    EXPECT_EQ(cli.code, 2) << cli.out;
    EXPECT_NE(cli.out.find("numerics.gravity_m_s2"), std::string::npos) << cli.out;
    EXPECT_NE(cli.out.find("must be positive"), std::string::npos) << cli.out;
    EXPECT_FALSE(fs::exists(out / "result.json"));
  }
}

TEST(NoHeadline, EveryExitCodeIsInTheReadmeAndTheHelp) {
  const CliResult help = run_cli("--help");
  const std::string readme = read_text(fs::path(REPOSETWIN_SOURCE_DIR) / "README.md");
  for (const int code : {0, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11}) {
    EXPECT_NE(help.out.find("\n  " + std::to_string(code) + "  "), std::string::npos) << code;
    EXPECT_NE(readme.find("\n| " + std::to_string(code) + " | "), std::string::npos) << code;
  }
}

}  // namespace
}  // namespace reposetwin::test_support
