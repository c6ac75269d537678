// Each kind of report built on a small input, checked as a reader meets it (page_check.hpp):
// links and images relative and present, no pasted JSON, axes labelled by the cases' inputs
// rather than their folder names, the calibration plot with its fit and calibrated mu_r, and the
// lab photo beside the render at one scale. Inputs: the committed records of a calibration
// (results/table1_s1_calibration: its result files, no run folders) with one tiny run's photos
// put in place of a check run's, and the committed loop.json.
#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "../../support/scratch.hpp"
#include "../../support/tiny_scene.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/photos/pile_images.hpp"
#include "experiments/pile/pile_run.hpp"
#include "experiments/report/format.hpp"
#include "experiments/report/page_check.hpp"
#include "experiments/report/report.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;

const fs::path kSource = REPOSETWIN_SOURCE_DIR;
const std::string kCheckCase = "predict_sample1_check_rolling_friction_0.3766643557248654";

void expect_opens_anywhere(const fs::path& page) {
  ASSERT_TRUE(fs::exists(page)) << page;
  for (const report::PageProblem& p : report::page_problems(page))
    ADD_FAILURE() << p.where << ": " << report::to_string(p.kind) << ": " << p.what;
}

// The committed calibration's records (no report, no run folders) copied to `dir`.
void copy_calibration_records(const fs::path& dir) {
  const fs::path from = kSource / "results" / "table1_s1_calibration";
  for (const char* f : {"calibration.json", "predictions.json"})
    fs::copy_file(from / f, dir / f);
  fs::copy(from / "cases", dir / "cases", fs::copy_options::recursive);
}

// A tiny pile photographed at 960 x 540, its images/ put where the check run's would be.
// Returns the render's scale at the pile axis [mm/px].
double put_tiny_photos(const fs::path& run_dir) {
  const SceneConfig scene =
      parse_scene_text(test_support::kTinyScene, (run_dir.parent_path() / "tiny.toml").string());
  RunOptions opt;
  opt.out_dir = run_dir.string();
  opt.progress = false;
  const PileRun run = *run_pile_test(scene, opt);
  ImageSettings s;
  s.width_px = 960;
  s.height_px = 540;
  s.side_views = 1;
  const json m = render_and_measure_run(run, run_dir.string(), s);
  return m.at("side_views").at(0).at("scale").at("mm_per_px").get<double>();
}

TEST(ReportPages, CalibrationReportReadsAsTablesWithReadableAxesAndOneScale) {
  const fs::path root = test_support::temp_dir("report_pages_calibration");
  const fs::path dir = root / "table1_s1_calibration";
  fs::create_directories(dir);
  copy_calibration_records(dir);
  const fs::path run = dir / "cases" / kCheckCase / "seed_1" / "run";
  const double render_mm_per_px = put_tiny_photos(run);
  ASSERT_GT(render_mm_per_px, 0.0);
  // The "lab photo": the same render at a third of its size, so three times its mm per px.
  const cv::Mat render = cv::imread((run / "images" / "side_az000.png").string());
  ASSERT_FALSE(render.empty());
  cv::Mat lab;
  cv::resize(render, lab, cv::Size(render.cols / 3, render.rows / 3), 0, 0, cv::INTER_AREA);
  cv::imwrite((root / "lab.png").string(), lab);

  ReportSettings settings;
  settings.lab_photo = (root / "lab.png").string();
  settings.lab_mm_per_px = 3.0 * render_mm_per_px;
  settings.paper_dir = (kSource / "data" / "paper").string();
  const json summary = build_report(dir.string(), settings);
  const fs::path out = dir / "report";
  expect_opens_anywhere(out / "index.html");
  const std::string html = read_file((out / "index.html").string());
  EXPECT_EQ(html.find("<pre"), std::string::npos);
  EXPECT_NE(html.find("calibrated mu_r [95% interval]"), std::string::npos);
  EXPECT_NE(html.find("0.377 [0.351, 0.410]"), std::string::npos);
  EXPECT_NE(html.find("sample1_check"), std::string::npos);  // the predictions table
  // What next: the export of this folder's material. The page names no absolute path (it is
  // read in a copied folder too): given an absolute folder, the command names the folder and is
  // run in the one that holds it.
  EXPECT_NE(html.find("<h2>What next</h2>"), std::string::npos);
  EXPECT_NE(html.find("<code>reposetwin export table1_s1_calibration</code>"), std::string::npos)
      << html;
  EXPECT_NE(html.find("in the folder that holds table1_s1_calibration"), std::string::npos);
  EXPECT_NE(html.find("field-scale deck (a stope, a dump) is not built yet"), std::string::npos);

  // Axis labels by inputs: the plot's data names no case folder.
  const std::string angles = read_file((out / "angles.dat").string());
  EXPECT_EQ(angles.find("calib_rolling_friction_"), std::string::npos) << angles;
  EXPECT_NE(angles.find("\"mu_r 0.399\""), std::string::npos) << angles;
  EXPECT_NE(angles.find("\"sample1_check: mu_r 0.377\""), std::string::npos) << angles;

  // The calibration plot: runs, the fit's points, the calibrated mu_r in its band, the checks.
  const std::string gp = read_file((out / "calibration.gp").string());
  for (const char* s : {"calibration_fit.dat", "calibration_runs.dat", "calibration_checks.dat",
                        "rect from 0.3508", "arrow 1 from 0.3767", "target 33.47"})
    EXPECT_NE(gp.find(s), std::string::npos) << s << " not in\n" << gp;
  const std::string fit = read_file((out / "calibration_fit.dat").string());
  EXPECT_EQ(std::count(fit.begin(), fit.end(), '\n'), 4);  // the four mu_r points of the record
  EXPECT_TRUE(fs::exists(out / "calibration.png"));

  // One scale: the same scene at three times the mm per px comes out the size of the render
  // brought to that scale, both with their overlays, and the page says the scale.
  const cv::Mat a = cv::imread((out / "lab_photo.measured.png").string());
  const cv::Mat b = cv::imread((out / "render_beside_lab.png").string());
  ASSERT_FALSE(a.empty());
  ASSERT_FALSE(b.empty());
  EXPECT_NEAR(a.cols, b.cols, 1);
  EXPECT_NEAR(a.rows, b.rows, 1);
  EXPECT_NEAR(summary["lab_photo_common_mm_per_px"].get<double>(), 3.0 * render_mm_per_px,
              1e-9);
  EXPECT_NE(html.find("mm per px at the pile axis"), std::string::npos);
  EXPECT_NE(html.find("render_beside_lab.png"), std::string::npos);

  // The renders copied into the report stay when the run folder is gone, and the rebuilt page
  // still opens.
  fs::remove_all(run);
  build_report(dir.string(), ReportSettings{"", 0.0, "", settings.paper_dir});
  expect_opens_anywhere(out / "index.html");
  EXPECT_NE(read_file((out / "index.html").string()).find(kCheckCase + "_side.png"),
            std::string::npos);
}

TEST(ReportPages, ComparisonOverFoldersLinksEachFolderRelatively) {
  const fs::path root = test_support::temp_dir("report_pages_comparison");
  const fs::path dir = root / "table1_s1_calibration";
  fs::create_directories(dir);
  copy_calibration_records(dir);
  ReportSettings settings;
  settings.paper_dir = (kSource / "data" / "paper").string();
  build_report({dir.string()}, (root / "table3").string(), settings);
  expect_opens_anywhere(root / "table3" / "report" / "index.html");
  expect_opens_anywhere(dir / "report" / "index.html");
  const std::string html = read_file((root / "table3" / "report" / "index.html").string());
  EXPECT_NE(html.find("href='../../table1_s1_calibration/report/index.html'"), std::string::npos);
  EXPECT_EQ(html.find(root.string()), std::string::npos);  // no path of this machine
}

TEST(ReportPages, LoopPageIsRebuiltFromItsLoopJson) {
  const fs::path dir = test_support::temp_dir("report_pages_loop");
  fs::copy_file(kSource / "results" / "paper_loop_image_fines" / "loop.json", dir / "loop.json");
  // The page is where the loop wrote it, so `report --force` guards that one.
  EXPECT_EQ(fs::path(report_page(dir.string())), dir / "index.html");
  build_report(dir.string());
  expect_opens_anywhere(dir / "index.html");
  const std::string html = read_file((dir / "index.html").string());
  EXPECT_NE(html.find("Error before and after"), std::string::npos);
  EXPECT_NE(html.find("<img src='plots/residual_"), std::string::npos);
  EXPECT_EQ(html.find("<pre"), std::string::npos);
}

// The first paper loop's loop.json, written before the loop recorded its design, grid and joint
// trace, is refused by name rather than shown with those sections made up.
TEST(ReportPages, ALoopJsonOlderThanItsRecordIsRefusedByName) {
  const fs::path dir = test_support::temp_dir("report_pages_old_loop");
  fs::copy_file(kSource / "results" / "paper_loop" / "loop.json", dir / "loop.json");
  try {
    build_report(dir.string());
    ADD_FAILURE() << "an old loop.json made a page";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), (dir / "loop.json").string() + ": /design: missing");
  }
  EXPECT_FALSE(fs::exists(dir / "index.html"));
}

// On an axis, a case is labelled by what sets it apart: a user's calibration sets the funnel and
// the mass on every case, and those parts are dropped; a prediction keeps its name.
TEST(ReportFormat, AxisLabelsDropTheInputsEveryCaseShares) {
  const std::string mu = "contacts.rock-rock.rolling_friction";
  const std::vector<std::pair<std::string, json>> cases = {
      {"calib_a", {{mu, 0.05}, {"container.bottom_diameter_m", 0.02}, {"sample.mass_kg", 0.006}}},
      {"calib_b", {{mu, 0.5}, {"container.bottom_diameter_m", 0.02}, {"sample.mass_kg", 0.006}}},
      {"predict_heavy_rolling_friction_0.2",
       {{mu, 0.2}, {"container.bottom_diameter_m", 0.02}, {"sample.mass_kg", 0.008}}}};
  EXPECT_EQ(report::case_labels(cases),
            (std::vector<std::string>{"mu_r 0.05, mass_kg 0.006", "mu_r 0.5, mass_kg 0.006",
                                      "heavy: mu_r 0.2, mass_kg 0.008"}));
  // One case, or cases that differ in nothing numeric, keep their whole labels.
  EXPECT_EQ(report::case_labels({cases[0]}),
            std::vector<std::string>{report::case_label(cases[0].first, cases[0].second)});
  EXPECT_EQ(report::case_labels({cases[0], cases[0]})[0],
            report::case_label(cases[0].first, cases[0].second));
}

}  // namespace
}  // namespace reposetwin::experiments
