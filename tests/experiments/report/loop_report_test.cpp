// The loop's page from a loop.json written here: every section, table and test appears, values
// are escaped, and each condition gets its residual plot.
#include <gtest/gtest.h>

#include <filesystem>

#include "experiments/io/provenance.hpp"
#include "experiments/loop/loop.hpp"
#include "experiments/report/loop_report.hpp"
#include "experiments/report/page_check.hpp"

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
  EXPECT_NE(read_file((out / "index.html").string()).find("None: no candidate left."),
            std::string::npos);
}

// With no effect chosen the page says why, from the last iteration, and an iteration whose
// candidate was refitted by simulation shows its trials and the outcome: confirmed (the value),
// not confirmed (the reason), or not simulated at all (the failures).
TEST(ReportLoop, SaysWhyNoEffectWasChosenAndWhatTheRefitSimulated) {
  const fs::path out = fs::temp_directory_path() / "reposetwin_loop_report_refit_test";
  fs::remove_all(out);
  auto page = [&](const json& loop) {
    write_loop_html(loop, out.string());
    return read_file((out / "index.html").string());
  };
  json loop = small_loop(false);
  json& it = loop["iterations"][0];
  it.erase("stopped");
  it["decision"] = {{"statement", "no candidate meets the acceptance rule"},
                    {"verdict", "nothing"}};
  EXPECT_NE(page(loop).find("None: no candidate beat the seed noise."), std::string::npos);
  it["decision"]["verdict"] = "measurement_suspected";
  EXPECT_NE(page(loop).find("None: the trace suspects a measurement or declared-condition error"),
            std::string::npos);
  it["decision"]["verdict"] = "indistinguishable";
  EXPECT_NE(page(loop).find("explain the residual alike and none is named"), std::string::npos);

  // Named, refitted, and not borne out by the simulations: never "no candidate beat the noise".
  const json trial = {{"simulated_at", 0.671},
                      {"response_fraction", -0.0684},
                      {"t", 1.57},
                      {"mu_r", 0.471},
                      {"rmse_calibrate_deg", 1.594}};
  it["decision"]["verdict"] = "named";
  it["not_confirmed"] = {{"name", "plate_friction"},
                         {"linear_estimate", 0.671},
                         {"simulated_at", 0.671},
                         {"t", 1.57},
                         {"mu_r", 0.471},
                         {"trials", {trial}},
                         {"refit_notes", ""},
                         {"rmse_calibrate_deg", 1.594},
                         {"reason", "RMSE 2.55 to 1.59 deg, not by more than the seed noise 1.05"}};
  std::string html = page(loop);
  for (const char* s :
       {"None: plate_friction was refitted by simulation, and the simulations did not confirm it "
        "(iteration 1).",
        "Refit by simulation: plate_friction, linear estimate 0.671, simulated on the whole grid; "
        "not confirmed: RMSE 2.55 to 1.59 deg, not by more than the seed noise 1.05. Nothing "
        "chosen.",
        "<th>simulated at</th>", "<td>-0.0684</td>", "<td>1.59</td>"})
    EXPECT_NE(html.find(s), std::string::npos) << s;
  EXPECT_EQ(html.find("no candidate beat the seed noise"), std::string::npos);

  it.erase("not_confirmed");
  it["chosen"] = {{"name", "plate_friction"},
                  {"refit_failed", "at 0.67: test s4 formed no pile; "},
                  {"linear_estimate", 0.671}};
  html = page(loop);
  for (const char* s :
       {"None: plate_friction&apos;s refit could not be simulated (iteration 1).",
        "could not be simulated: at 0.67: test s4 formed no pile; . Nothing chosen."})
    EXPECT_NE(html.find(s), std::string::npos) << s;

  // Confirmed: the value with its units (none for a friction), and the trials.
  it["chosen"] = {{"name", "cohesion"}, {"linear_estimate", 900.0}, {"trials", {trial}},
                  {"value", 850.0},     {"value_se", 120.0},        {"units", "J/m^3"},
                  {"mu_r", 0.2},        {"refit_notes", ""}};
  loop["final"]["effects"] = {{{"name", "cohesion"},
                               {"kind", "physics"},
                               {"value", 850.0},
                               {"value_se", 120.0},
                               {"units", "J/m^3"},
                               {"mu_r", 0.2}}};
  html = page(loop);
  EXPECT_NE(html.find("confirmed: cohesion 850 \u00b1 120 J/m^3 at mu_r 0.2."), std::string::npos);
  EXPECT_EQ(html.find("None:"), std::string::npos);
  // An older loop.json's effect without the refit's fields still makes a page.
  it["chosen"] = {{"name", "cohesion"}};
  EXPECT_NE(page(loop).find("Refit by simulation: cohesion, linear estimate ?"), std::string::npos);
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

#include <opencv2/imgcodecs.hpp>

namespace reposetwin::experiments {
namespace {

// The width attribute of the <img> whose src is `src`, or -1.
int img_width(const std::string& html, const std::string& src) {
  const std::string tag = "<img src='" + src + "' width='";
  const std::size_t at = html.find(tag);
  return at == std::string::npos ? -1 : std::stoi(html.substr(at + tag.size(), 8));
}

// A lab photo and a twin photo of different sizes and scales are placed side by side at one
// mm per page pixel: the lab's 400 px at 0.2 mm/px (80 mm of field) and the twin's 960 px at
// 0.1 mm/px (96 mm) at the coarser scale, 0.2 mm per page px (0.2 x 400 / 560 and 0.1 x 960 /
// 560 are finer): 400 and 480 px, in the ratio 96 / 80 of their fields; both overlays and both
// plain photos are linked. A test whose twin view could not be measured shows its lab photo
// and the reason; a test the lab gave no photo of shows the twin's alone.
TEST(ReportLoop, LabAndTwinPhotosSideBySideAtOneScale) {
  const fs::path out = fs::temp_directory_path() / "reposetwin_loop_report_photos_test";
  fs::remove_all(out);
  fs::create_directories(out / "photos" / "t1");
  auto png = [&](const std::string& name, int w, int h, int grey) {
    cv::imwrite((out / "photos" / "t1" / name).string(),
                cv::Mat(h, w, CV_8UC3, cv::Scalar::all(grey)));
  };
  png("lab.png", 400, 300, 90);
  png("lab.measured.png", 400, 300, 120);
  png("twin.png", 960, 720, 150);
  png("twin.measured.png", 960, 720, 180);
  json loop = small_loop(false);
  auto view = [](const std::string& who, int w, int h, double mm) {
    return json{{"photo", "photos/t1/" + who + ".png"},
                {"overlay", "photos/t1/" + who + ".measured.png"},
                {"source", "/lab/" + who + ".png"},
                {"mm_per_px", mm},
                {"width_px", w},
                {"height_px", h},
                {"angle_deg", 33.5}};
  };
  loop["photo_pairs"] = {{{"id", "t1"},
                          {"lab", view("lab", 400, 300, 0.2)},
                          {"twin", view("twin", 960, 720, 0.1)},
                          {"mu_r", 0.15},
                          {"seed", 1001},
                          {"effects", {{"plate_friction", 0.4}}},
                          {"note", ""}},
                         {{"id", "t2"},
                          {"lab", view("lab", 400, 300, 0.2)},
                          {"twin", nullptr},
                          {"mu_r", 0.15},
                          {"seed", 1001},
                          {"effects", json::object()},
                          {"note", "no view of the twin's photograph could be measured"}},
                         {{"id", "t3"},
                          {"lab", nullptr},
                          {"twin", view("twin", 960, 720, 0.1)},
                          {"mu_r", 0.15},
                          {"seed", 1001},
                          {"effects", json::object()},
                          {"note", ""}}};
  write_loop_html(loop, out.string());
  const std::string html = read_file((out / "index.html").string());
  const int lab = img_width(html, "photos/t1/lab.measured.png");
  const int twin = img_width(html, "photos/t1/twin.measured.png");
  EXPECT_EQ(lab, 400);
  EXPECT_EQ(twin, 480);
  EXPECT_NEAR(double(twin) / lab, (960 * 0.1) / (400 * 0.2), 1.0 / lab);
  for (const char* s : {"<h2>Lab and twin, like for like</h2>", "<h3>t1</h3>",
                        "Both at 0.2 mm per page pixel.", "href='photos/t1/lab.measured.png'",
                        "href='photos/t1/twin.measured.png'", "href='photos/t1/lab.png'",
                        "href='photos/t1/twin.png'", "mu_r 0.15, seed 1001, plate_friction 0.4",
                        "<h3>t2</h3>", "no view of the twin&apos;s photograph could be measured"})
    EXPECT_NE(html.find(s), std::string::npos) << s;
  // A test with a typed angle: the twin's photo alone, at its own scale (960 px x 0.1 mm into
  // the 560 px column), and the page says the lab gave none.
  const std::size_t t3 = html.find("<h3>t3</h3>");
  ASSERT_NE(t3, std::string::npos);
  const std::string alone = html.substr(t3);
  EXPECT_EQ(img_width(alone, "photos/t1/twin.measured.png"), 560);
  EXPECT_EQ(alone.find("lab.measured.png"), std::string::npos);
  EXPECT_NE(alone.find("At 0.171 mm per page pixel. The lab gave no photo of this test (a typed "
                       "angle)."),
            std::string::npos)
      << alone.substr(0, 400);
  // Without photo pairs (an older loop.json, or data without photos) there is no such section.
  write_loop_html(small_loop(false), out.string());
  EXPECT_EQ(read_file((out / "index.html").string()).find("like for like"), std::string::npos);

  // Rebuilt after the photos were left out of the folder (results/ keeps loop.json and the page,
  // not the photos): no image or link points at a missing file, the scales and angles stay,
  // and the page says the photos are not there.
  fs::remove_all(out / "photos");
  write_loop_html(loop, out.string());
  const std::string pruned = read_file((out / "index.html").string());
  EXPECT_EQ(pruned.find("photos/t1/"), std::string::npos);
  for (const char* s : {"<h3>t1</h3>", "lab.measured.png (not in this folder)",
                        "2 photos are not in this folder", "Both at 0.2 mm per page pixel."})
    EXPECT_NE(pruned.find(s), std::string::npos) << s;
  EXPECT_TRUE(report::page_problems(out / "index.html").empty());
}

// A text condition gets a plot with one category per value, and tests of different size
// distributions (a size band, a sieve-table file) get a PSD plot of their own and one series
// per distribution on every numeric condition's plot, each point in its own series; a condition
// every test shares at one value gets a sentence, not a plot.
TEST(ReportLoop, TextConditionsAndThePsdGetTheirOwnPlotsAndSeries) {
  const fs::path out = fs::temp_directory_path() / "reposetwin_loop_report_conditions_test";
  fs::remove_all(out);
  json loop = small_loop(false);
  const json r1 = {{"residual_deg", 1.25}, {"sigma_deg", 0.2}, {"predicted_deg", 35.0}};
  const json r2 = {{"residual_deg", -0.75}, {"sigma_deg", 0.2}, {"predicted_deg", 35.0}};
  const json r3 = {{"residual_deg", 2.5}, {"sigma_deg", 0.2}, {"predicted_deg", 35.0}};
  loop["tests"] = {
      {{"id", "t1"},
       {"role", "calibrate"},
       {"angle_deg", 35},
       {"conditions", {{"mass_kg", 0.5}, {"d_min_mm", 3}, {"d_max_mm", 4}, {"W_mm", 40}}},
       {"text_conditions", {{"plate", "wood"}, {"funnel", "steel"}}}},
      {{"id", "t2"},
       {"role", "calibrate"},
       {"angle_deg", 35},
       {"conditions", {{"mass_kg", 0.5}, {"d_min_mm", 2}, {"d_max_mm", 4}, {"W_mm", 40}}},
       {"text_conditions", {{"plate", "steel"}, {"funnel", "steel"}}}},
      {{"id", "t3"},
       {"role", "validate"},
       {"angle_deg", 35},
       {"conditions", {{"mass_kg", 1.0}, {"W_mm", 40}}},
       {"camera_height_m", 0.05},
       {"text_conditions",
        {{"plate", "wood"}, {"funnel", "steel"}, {"set:sample.psd_file", "psd/fine.toml"}}}}};
  loop["baseline"]["residuals"] = {r1, r2, r3};
  loop["final"]["residuals"] = {r1, r2, r3};
  const fs::path plots = out / "plots";
  fs::create_directories(plots);  // an earlier rendering's plot against W_mm
  write_file_atomic((plots / "residual_W_mm.dat").string(), "# stale\n");
  write_loop_html(loop, out.string());
  // The plate: categories steel (0) and wood (1); t1 and t3 on wood, t2 on steel.
  const std::string plate_gp = read_file((plots / "residual_plate.gp").string());
  EXPECT_NE(plate_gp.find("set xtics ('steel' 0, 'wood' 1)"), std::string::npos) << plate_gp;
  const std::string plate = read_file((plots / "residual_plate.dat").string());
  for (const char* row :
       {"\n1 1.25 1.25 0.2 1\n", "\n0 -0.75 -0.75 0.2 1\n", "\n1 2.5 2.5 0.2 0\n"})
    EXPECT_NE(plate.find(row), std::string::npos) << row << plate;
  // The PSD's own plot: one category per distribution.
  const std::string psd_gp = read_file((plots / "residual_PSD.gp").string());
  EXPECT_NE(psd_gp.find("set xtics ('2-4 mm' 0, '3-4 mm' 1, 'fine.toml' 2)"), std::string::npos)
      << psd_gp;
  // The declared camera height, a column kept apart from the scene's conditions, is one too.
  EXPECT_NE(
      read_file((plots / "residual_camera_height_m.dat").string()).find("\n0.05 2.5 2.5 0.2 0\n"),
      std::string::npos);
  EXPECT_FALSE(fs::exists(plots / "residual_set_sample_psd_file.dat"))
      << "the sieve-table file is shown on the PSD's plot, not twice";
  // On the mass axis, one series per distribution, named in the key.
  const std::string mass = read_file((plots / "residual_mass_kg.dat").string());
  for (const char* block : {"# series 0: PSD 2-4 mm\n0.5 -0.75", "# series 1: PSD 3-4 mm\n0.5 1.25",
                            "# series 2: PSD fine.toml\n1 2.5"})
    EXPECT_NE(mass.find(block), std::string::npos) << block << mass;
  const std::string mass_gp = read_file((plots / "residual_mass_kg.gp").string());
  for (const char* t : {"index 0", "index 2", "t 'before, PSD 3-4 mm'", "t 'after, PSD fine.toml'"})
    EXPECT_NE(mass_gp.find(t), std::string::npos) << t << mass_gp;
  // A condition every test has at one value (the outlet, the funnel) is a single column of
  // points: named on the page, not plotted (an earlier rendering's plot is gone). The camera
  // height, declared by t3 alone, is plotted.
  EXPECT_FALSE(fs::exists(plots / "residual_W_mm.dat"));
  EXPECT_FALSE(fs::exists(plots / "residual_funnel.dat"));
  EXPECT_NE(read_file((out / "index.html").string())
                .find("The same on every test, so not plotted: W_mm 40, funnel steel."),
            std::string::npos);
  if (fs::exists(plots / "residual_plate.png")) {  // gnuplot is optional
    const std::string html = read_file((out / "index.html").string());
    for (const char* s :
         {"src='plots/residual_plate.png'", "src='plots/residual_PSD.png'",
          "Residual against plate (a category each)", "one colour per size distribution"})
      EXPECT_NE(html.find(s), std::string::npos) << s;
  }
}

}  // namespace
}  // namespace reposetwin::experiments
