// `run`, `measure` and `report` each end with one line a person reads, the angle first; the
// whole record is on stdout only under --json. One tiny run with its photographs (seconds) is
// run, measured and reported.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_support.hpp"

namespace reposetwin::test_support {
namespace {

const fs::path kTiny = fs::path(REPOSETWIN_SOURCE_DIR) / "data" / "loop" / "tiny_scene.toml";

// The lines of `text` (stdout and stderr together) that are not empty and not warnings, which
// go to stderr: what a person reads as the command's answer.
std::vector<std::string> answer(const std::string& text) {
  std::vector<std::string> out;
  for (std::size_t start = 0; start < text.size();) {
    std::size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    const std::string line = text.substr(start, end - start);
    if (!line.empty() && line.rfind("reposetwin: warning: ", 0) != 0) out.push_back(line);
    start = end + 1;
  }
  return out;
}

int lines(const std::string& text) { return static_cast<int>(answer(text).size()); }

TEST(OneLine, RunMeasureAndReportEachPrintOneHeadlineLineAndJsonOnlyWhenAsked) {
  const fs::path dir = fresh_dir("one_line");
  const fs::path run = dir / "run";
  const CliResult r = run_cli("run " + quoted(kTiny) + " --out " + quoted(run) + " --quiet");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(r.out.rfind("angle of repose ", 0), 0u) << r.out;
  EXPECT_EQ(lines(r.out), 1) << r.out;
  const nlohmann::json result = nlohmann::json::parse(read_text(run / "result.json"));
  ASSERT_TRUE(result["headline_angle_deg"].is_number());
  const std::string angle = [&] {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.2f", result["headline_angle_deg"].get<double>());
    return std::string(buf);
  }();
  // The tiny pile is low and narrow for its grains: the result says so.
  EXPECT_TRUE(result["representativeness"]["warnings"].contains("pile_height"));

  // measure: one line on stdout (the overlay beside the image), the JSON only with --json.
  const fs::path side = run / "images" / "side_az000.png";
  ASSERT_TRUE(fs::exists(side));
  const std::string measure =
      "measure " + quoted(side) + " --overlay " + quoted(dir / "m.png") + " ";
  const CliResult m = run_cli(measure);
  ASSERT_EQ(m.code, 0) << m.out;
  ASSERT_EQ(lines(m.out), 1) << m.out;
  EXPECT_EQ(answer(m.out)[0].rfind("angle of repose ", 0), 0u) << m.out;
  EXPECT_NE(m.out.find("(image atan(2H/D), 1 side view, perspective corrected)"), std::string::npos)
      << m.out;
  EXPECT_NE(m.out.find("overlay " + (dir / "m.png").string()), std::string::npos) << m.out;
  // --json: the record alone (its warnings inside it), so a script can parse it.
  const CliResult mj = run_cli(measure + "--json");
  ASSERT_EQ(mj.code, 0) << mj.out;
  const nlohmann::json mjson = nlohmann::json::parse(mj.out);
  EXPECT_EQ(mjson["views"], 1);
  EXPECT_NE(m.out.find([&] {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.2f", mjson["theta_deg"].get<double>());
    return std::string(buf);
  }()),
            std::string::npos);

  // report: the run's angle and the page, one line; the summary as JSON only with --json.
  const CliResult p = run_cli("report " + quoted(run));
  ASSERT_EQ(p.code, 0) << p.out;
  EXPECT_EQ(lines(p.out), 1) << p.out;
  EXPECT_NE(p.out.find("angle of repose " + angle), std::string::npos) << p.out;
  EXPECT_NE(p.out.find("(image atan(2H/D), 1 run)"), std::string::npos) << p.out;
  EXPECT_NE(p.out.find("; report " + (run / "report" / "index.html").string()), std::string::npos)
      << p.out;
  const CliResult pj = run_cli("report " + quoted(run) + " --force --json");
  ASSERT_EQ(pj.code, 0) << pj.out;
  EXPECT_TRUE(nlohmann::json::parse(pj.out).contains("cases"));
}

}  // namespace
}  // namespace reposetwin::test_support
