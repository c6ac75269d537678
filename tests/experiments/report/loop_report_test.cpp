// The loop's page from a loop.json written here: every section, table and test appears, values
// are escaped, and each condition gets its residual plot.
#include <gtest/gtest.h>

#include <filesystem>

#include "experiments/io/provenance.hpp"
#include "experiments/loop/loop.hpp"
#include "experiments/report/loop_report.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;

json small_loop(bool with_effect) {
  const json residual = {{"residual_deg", 0.5}, {"sigma_deg", 0.2}, {"predicted_deg", 35.25}};
  json loop = {
      {"provenance", {{"data", "lab<1>.csv"}, {"code_version", "v1"}, {"finished", "now"}}},
      {"tests",
       {{{"id", "t1"}, {"role", "calibrate"}, {"angle_deg", 35.75}, {"conditions", {{"W_mm", 40}}}},
        {{"id", "t2"}, {"role", "validate"}, {"angle_deg", 36.5}, {"conditions", {{"W_mm", 60}}}}}},
      {"baseline",
       {{"residuals", {residual, residual}},
        {"mu_r", 0.1234},
        {"mu_r_se", 0.01},
        {"seed_sd_deg", 0.4},
        {"curves", {{{"id", "t1"}, {"clogged_pours", {1, 0, 1}}}}}}},
      {"final",
       {{"residuals", {residual, residual}},
        {"effects", json::array()}}},
      {"summary",
       {{"rmse_calibrate_before_deg", 1.2345},
        {"rmse_calibrate_after_deg", 0.5},
        {"rmse_validate_before_deg", 1.5},
        {"rmse_validate_after_deg", nullptr}}},
      {"rule", {{"text", "|c| > 3 se"}, {"min_t", 3}, {"loo_margin_deg", 0.1}}},
      {"iterations",
       {{{"iteration", 1},
         {"mu_r", 0.12},
         {"null", {{"loo_rmse_mu_only_deg", 1.1}}},
         {"candidates",
          {{{"name", "plate_friction"},
            {"coef", 0.9},
            {"coef_se", 0.1},
            {"t", 9.0},
            {"loo_rmse_deg", 0.4},
            {"loo_gain_deg", 0.7},
            {"explained", 0.8},
            {"accepted", true}}}},
         {"stopped", "no candidate left"}}}},
      {"unavailable_candidates", {{{"name", "humidity"}, {"why", "no column"}}}}};
  if (with_effect)
    loop["final"]["effects"] = {{{"name", "plate_friction"},
                                 {"kind", "scene"},
                                 {"value", 0.3},
                                 {"value_se", 0.05},
                                 {"units", "-"},
                                 {"mu_r", 0.11}}};
  return loop;
}

TEST(ReportLoop, PageShowsEverySectionAndTest) {
  const fs::path out = fs::temp_directory_path() / "reposetwin_loop_report_test";
  fs::remove_all(out);
  write_loop_html(small_loop(true), out.string());
  const std::string html = read_file((out / "index.html").string());
  for (const char* s :
       {"<title>ReposeTwin loop</title>", "<h1>Closing the loop</h1>", "Data: lab&lt;1&gt;.csv",
        "Code v1, finished now", "<h2>Error before and after</h2>", "RMSE calibration tests [deg]",
        "1.23", "Baseline mu_r = 0.123", "<h2>Chosen effects</h2>", "plate_friction", "0.3",
        "Rule: |c| &gt; 3 se (min_t 3, margin 0.1 deg)", "<h3>Iteration 1 (mu_r 0.12; mu_r-only LOO 1.1 deg)</h3>",
        "<td>yes</td>", "Stopped: no candidate left.", "<li>t1: 2</li>", "<li>humidity: no column</li>",
        "<h2>Residuals</h2>", "<td class='l'>t2</td><td class='l'>validate</td><td>36.5</td>",
        "35.2"})
    EXPECT_NE(html.find(s), std::string::npos) << s;
  EXPECT_EQ(html.find("None: no candidate"), std::string::npos);
  EXPECT_TRUE(fs::exists(out / "plots" / "residual_W_mm.dat"));
  if (fs::exists(out / "plots" / "residual_W_mm.png")) {  // gnuplot is optional
    EXPECT_NE(html.find("src='plots/residual_W_mm.png'"), std::string::npos);
  }

  write_loop_html(small_loop(false), out.string());
  EXPECT_NE(read_file((out / "index.html").string()).find("None: no candidate beat the seed noise."),
            std::string::npos);
}

// A loop that traced jointly: the design's statements, the grid, the joint table and the
// decision appear.
TEST(ReportLoop, PageShowsTheDesignTheGridAndTheJointDecision) {
  json loop = small_loop(false);
  loop["design"] = {{"can", {"mu_r is fitted on the 1 calibration test(s)"}},
                    {"cannot", {"the held-out RMSE after the refit is in-sample"}}};
  loop["grid"] = {{"statement", "mu_r 0.05 lies inside the grid extended by 0.05"}};
  loop["not_traced"] = nullptr;
  const json score = {{"name", "lift_speed"}, {"coef", 0.8}, {"coef_se", 0.1}, {"t", 8.0},
                      {"chi2", 48.8},         {"loo_chi2", 62.4}, {"values", 24}};
  json& it = loop["iterations"][0];
  it["channels"] = {"angle", "H", "D"};
  it["joint"] = {score};
  it["offset"] = score;
  it["offset"]["name"] = "offset";
  it["mu_only"] = nullptr;
  it["decision"] = {{"statement", "indistinguishable within the noise, none named"}};
  const fs::path out = fs::temp_directory_path() / "reposetwin_loop_report_joint_test";
  fs::remove_all(out);
  write_loop_html(loop, out.string());
  const std::string html = read_file((out / "index.html").string());
  for (const char* s : {"<li>mu_r is fitted on the 1 calibration test(s)</li>",
                        "<li>the held-out RMSE after the refit is in-sample</li>",
                        "mu_r grid: mu_r 0.05 lies inside the grid extended by 0.05.",
                        "Traced jointly on angle, H, D:", "48.8", "62.4", "offset",
                        "Decision: indistinguishable within the noise, none named."})
    EXPECT_NE(html.find(s), std::string::npos) << s;
  EXPECT_EQ(html.find("Nothing was traced"), std::string::npos);
  loop["not_traced"] = "with 2 test(s) nothing can be traced";
  write_loop_html(loop, out.string());
  EXPECT_NE(read_file((out / "index.html").string())
                .find("<strong>Nothing was traced</strong>: with 2 test(s) nothing can be traced."),
            std::string::npos);
}

}  // namespace
}  // namespace reposetwin::experiments

namespace reposetwin::experiments {
namespace {

// The crest width gets its residual-table columns only where the lab measured it: measured,
// before and after for a test with a crest, "-" for one without; none at all without a crest.
TEST(ReportLoop, CrestColumnsAppearOnlyWhereTheLabMeasuredTheCrest) {
  const fs::path out = fs::temp_directory_path() / "reposetwin_loop_report_crest_test";
  fs::remove_all(out);
  json loop = small_loop(false);
  write_loop_html(loop, out.string());
  EXPECT_EQ(read_file((out / "index.html").string()).find("crest measured"), std::string::npos);
  loop["tests"][0]["crest_mm"] = 6.25;
  loop["baseline"]["residuals"][0]["predicted_crest_mm"] = 4.75;
  loop["final"]["residuals"][0]["predicted_crest_mm"] = 5.5;
  write_loop_html(loop, out.string());
  const std::string html = read_file((out / "index.html").string());
  for (const char* s : {"crest measured [mm]", "crest before [mm]", "crest after [mm]",
                        "<td>6.25</td><td>4.75</td><td>5.5</td>", "<td class='l'>-</td>"})
    EXPECT_NE(html.find(s), std::string::npos) << s;
}

}  // namespace
}  // namespace reposetwin::experiments
