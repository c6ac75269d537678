// The loop's page from a loop.json written here: every section, table and test appears, values
// are escaped, and each condition gets its residual plot.
#include "experiments/report/loop_report.hpp"

#include <gtest/gtest.h>

#include <filesystem>

#include "experiments/io/input_error.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/loop/loop.hpp"
#include "experiments/report/page_check.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;

LabTest lab_test(const std::string& id, Role role, double angle_deg,
                 std::map<std::string, double> conditions) {
  LabTest t;
  t.id = id;
  t.role = role;
  t.angle_deg = angle_deg;
  t.conditions = std::move(conditions);
  return t;
}

ResidualRow residual_row(const std::string& id, Role role, double residual_deg) {
  ResidualRow r;
  r.id = id;
  r.role = role;
  r.residual_deg = residual_deg;
  r.sigma_deg = 0.2;
  r.predicted_deg = 35.25;
  return r;
}

// The refit's fields of an effect or a refit the simulations did not confirm.
RefitSummary refit_summary(const std::string& name, double linear_estimate, double mu_r) {
  RefitSummary r;
  r.name = name;
  r.linear_estimate = linear_estimate;
  r.simulated_at = linear_estimate;
  r.t = 1.57;
  r.mu_r = mu_r;
  r.trials = {{0.671, -0.0684, 1.57, 0.471, 1.594, {}}};
  return r;
}

ChosenEffect effect(const std::string& name, const std::string& kind, double value, double value_se,
                    const std::string& units, double mu_r) {
  ChosenEffect c;
  c.refit = refit_summary(name, value, mu_r);
  c.kind = kind;
  c.value = value;
  c.value_se = value_se;
  c.units = units;
  return c;
}

// Two tests, one iteration that the effect limit stopped, a jammed baseline pour and a candidate
// left out; with or without a chosen effect.
LoopRecord small_loop(bool with_effect) {
  LoopRecord loop;
  loop.provenance.data = "lab<1>.csv";
  loop.provenance.code_version = "v1";
  loop.provenance.finished = "now";
  loop.tests = {lab_test("t1", Role::kCalibrate, 35.75, {{"W_mm", 40}}),
                lab_test("t2", Role::kValidate, 36.5, {{"W_mm", 60}})};
  for (std::vector<ResidualRow>* rows : {&loop.baseline.residuals, &loop.final_model.residuals})
    *rows = {residual_row("t1", Role::kCalibrate, 0.5), residual_row("t2", Role::kValidate, 0.5)};
  loop.baseline.fit.mu = 0.1234;
  loop.baseline.fit.mu_se = 0.01;
  loop.baseline.seed_sd_deg = 0.4;
  loop.baseline.seed_se_deg = 0.1;  // the LOO margin: 1 x the seed se
  loop.baseline.curves = {{"t1", {}, {}, {}, {}, {1, 0, 1}}};
  loop.summary.rmse_calibrate_before_deg = 1.2345;
  loop.summary.rmse_calibrate_after_deg = 0.5;
  loop.summary.rmse_validate_before_deg = 1.5;
  IterationRecord it;
  it.iteration = 1;
  it.mu_r = 0.12;
  it.null.loo_rmse = 1.1;
  CandidateScore c;
  c.name = "plate_friction";
  c.coef = 0.9;
  c.coef_se = 0.1;
  c.t = 9.0;
  c.loo_rmse = 0.4;
  c.loo_gain = 0.7;
  c.explained = 0.8;
  c.accepted = true;
  it.candidates = {c};
  it.stopped = "no candidate left";
  loop.iterations = {it};
  loop.unavailable = {{"humidity", "no column"}};
  if (with_effect)
    loop.final_model.effects = {effect("plate_friction", "scene", 0.3, 0.05, "-", 0.11)};
  return loop;
}

// The page of `loop` as the loop writes it: from its loop.json, read back into the record.
std::string page(const LoopRecord& loop, const fs::path& out) {
  write_loop_html(to_json(loop), out.string());
  return read_file((out / "index.html").string());
}

TEST(ReportLoop, PageShowsEverySectionAndTest) {
  const fs::path out = fs::temp_directory_path() / "reposetwin_loop_report_test";
  fs::remove_all(out);
  const std::string html = page(small_loop(true), out);
  for (const char* s :
       {"<title>ReposeTwin loop</title>",
        "<h1>Closing the loop</h1>",
        "Data: lab&lt;1&gt;.csv",
        "Code v1, finished now",
        "<h2>Error before and after</h2>",
        "RMSE calibration tests [deg]",
        "1.23",
        "Baseline mu_r = 0.123",
        "<h2>Chosen effects</h2>",
        "plate_friction",
        "0.3",
        "Rule: accept the best-ranked candidate with |c|/se &gt; min_t and a leave-one-test-out",
        "(min_t 3, margin 0.1 deg)",
        "<h3>Iteration 1 (mu_r 0.12; mu_r-only LOO 1.1 deg)</h3>",
        "<td>yes</td>",
        "Stopped: no candidate left.",
        "<li>t1: 2</li>",
        "<li>humidity: no column</li>",
        "<h2>Residuals</h2>",
        "<td class='l'>t2</td><td class='l'>validate</td><td>36.5</td>",
        "35.2"})
    EXPECT_NE(html.find(s), std::string::npos) << s;
  EXPECT_EQ(html.find("None: no candidate"), std::string::npos);
  EXPECT_TRUE(fs::exists(out / "plots" / "residual_W_mm.dat"));
  if (fs::exists(out / "plots" / "residual_W_mm.png")) {  // gnuplot is optional
    EXPECT_NE(html.find("src='plots/residual_W_mm.png'"), std::string::npos);
  }
  EXPECT_NE(page(small_loop(false), out).find("None: no candidate left."), std::string::npos);
}

// With no effect chosen the page says why, from the last iteration, and an iteration whose
// candidate was refitted by simulation shows its trials and the outcome: confirmed (the value),
// not confirmed (the reason), or not simulated at all (the failures).
TEST(ReportLoop, SaysWhyNoEffectWasChosenAndWhatTheRefitSimulated) {
  const fs::path out = fs::temp_directory_path() / "reposetwin_loop_report_refit_test";
  fs::remove_all(out);
  LoopRecord loop = small_loop(false);
  IterationRecord& it = loop.iterations[0];
  it.stopped.reset();
  it.offset = JointScore{};  // traced: the offset was scored
  it.offset->name = "offset";
  it.decision.statement = "no candidate meets the acceptance rule";
  EXPECT_NE(page(loop, out).find("None: no candidate beat the seed noise."), std::string::npos);
  it.decision.verdict = TraceVerdict::kMeasurementSuspected;
  EXPECT_NE(
      page(loop, out).find("None: the trace suspects a measurement or declared-condition error"),
      std::string::npos);
  it.decision.verdict = TraceVerdict::kIndistinguishable;
  EXPECT_NE(page(loop, out).find("explain the residual alike and none is named"),
            std::string::npos);
  // An iteration that could not trace (no offset scored) gives its decision's statement.
  it.offset.reset();
  EXPECT_NE(page(loop, out).find("None: no candidate meets the acceptance rule."),
            std::string::npos);
  it.offset = JointScore{};

  // Named, refitted, and not borne out by the simulations: never "no candidate beat the noise".
  it.decision.verdict = TraceVerdict::kNamed;
  it.not_confirmed = NotConfirmed{refit_summary("plate_friction", 0.671, 0.471), 1.594,
                                  "RMSE 2.55 to 1.59 deg, not by more than the seed noise 1.05"};
  std::string html = page(loop, out);
  for (const char* s :
       {"None: plate_friction was refitted by simulation, and the simulations did not confirm it "
        "(iteration 1).",
        "Refit by simulation: plate_friction, linear estimate 0.671, simulated on the whole grid; "
        "not confirmed: RMSE 2.55 to 1.59 deg, not by more than the seed noise 1.05. Nothing "
        "chosen.",
        "<th>simulated at</th>", "<td>-0.0684</td>", "<td>1.59</td>"})
    EXPECT_NE(html.find(s), std::string::npos) << s;
  EXPECT_EQ(html.find("no candidate beat the seed noise"), std::string::npos);

  it.not_confirmed.reset();
  it.refit_failed = RefitFailed{"plate_friction", "at 0.67: test s4 formed no pile; ", 0.671};
  html = page(loop, out);
  for (const char* s :
       {"None: plate_friction&apos;s refit could not be simulated (iteration 1).",
        "could not be simulated: at 0.67: test s4 formed no pile; . Nothing chosen."})
    EXPECT_NE(html.find(s), std::string::npos) << s;

  // Confirmed: the value with its units (none for a friction), and the trials.
  it.refit_failed.reset();
  it.chosen = effect("cohesion", "physics", 850.0, 120.0, "J/m^3", 0.2);
  loop.final_model.effects = {*it.chosen};
  html = page(loop, out);
  EXPECT_NE(html.find("confirmed: cohesion 850 \u00b1 120 J/m^3 at mu_r 0.2."), std::string::npos);
  EXPECT_EQ(html.find("None:"), std::string::npos);
}

// A loop.json with a field missing or of the wrong type makes no page: the error names the
// folder's loop.json and the field's JSON pointer.
TEST(ReportLoop, ALoopJsonWithAMissingOrMistypedFieldIsRefusedByPointer) {
  const fs::path out = fs::temp_directory_path() / "reposetwin_loop_report_refused_test";
  fs::remove_all(out);
  LoopRecord loop = small_loop(false);
  loop.iterations[0].chosen = effect("cohesion", "physics", 850.0, 120.0, "J/m^3", 0.2);
  json j = to_json(loop);
  j["iterations"][0]["chosen"].erase("linear_estimate");
  auto refusal = [&](const json& bad) -> std::string {
    try {
      write_loop_html(bad, out.string());
    } catch (const InputError& e) {
      return e.what();
    }
    return "written";
  };
  const std::string file = (out / "loop.json").string();
  EXPECT_EQ(refusal(j), file + ": /iterations/0/chosen/linear_estimate: missing");
  EXPECT_FALSE(fs::exists(out / "index.html"));
  j = to_json(loop);
  j["tests"][1]["conditions"] = "W_mm 60";
  EXPECT_EQ(refusal(j), file + ": /tests/1/conditions: has the wrong type (string)");
}

// A loop that traced jointly: the design's statements, the grid, the joint table and the
// decision appear.
TEST(ReportLoop, PageShowsTheDesignTheGridAndTheJointDecision) {
  LoopRecord loop = small_loop(false);
  loop.design.can = {"mu_r is fitted on the 1 calibration test(s)"};
  loop.design.cannot = {"the held-out RMSE after the refit is in-sample"};
  loop.grid.statement = "mu_r 0.05 lies inside the grid extended by 0.05";
  JointScore score;
  score.name = "lift_speed";
  score.coef = 0.8;
  score.coef_se = 0.1;
  score.t = 8.0;
  score.chi2 = 48.8;
  score.loo_chi2 = 62.4;
  score.rows = 24;
  IterationRecord& it = loop.iterations[0];
  it.channels = {"angle", "H", "D"};
  it.joint = {score};
  it.offset = score;
  it.offset->name = "offset";
  it.decision.statement = "indistinguishable within the noise, none named";
  const fs::path out = fs::temp_directory_path() / "reposetwin_loop_report_joint_test";
  fs::remove_all(out);
  const std::string html = page(loop, out);
  for (const char* s : {"<li>mu_r is fitted on the 1 calibration test(s)</li>",
                        "<li>the held-out RMSE after the refit is in-sample</li>",
                        "mu_r grid: mu_r 0.05 lies inside the grid extended by 0.05.",
                        "Traced jointly on angle, H, D:", "48.8", "62.4", "offset",
                        "Decision: indistinguishable within the noise, none named."})
    EXPECT_NE(html.find(s), std::string::npos) << s;
  EXPECT_EQ(html.find("Nothing was traced"), std::string::npos);
  loop.not_traced = "with 2 test(s) nothing can be traced";
  EXPECT_NE(page(loop, out).find(
                "<strong>Nothing was traced</strong>: with 2 test(s) nothing can be traced."),
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
  LoopRecord loop = small_loop(false);
  EXPECT_EQ(page(loop, out).find("crest measured"), std::string::npos);
  loop.tests[0].crest_mm = 6.25;
  loop.tests[0].crest_source = "typed";
  loop.baseline.residuals[0].predicted_crest_mm = 4.75;
  loop.final_model.residuals[0].predicted_crest_mm = 5.5;
  const std::string html = page(loop, out);
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
  LoopRecord loop = small_loop(false);
  auto view = [](const std::string& who, int w, int h, double mm) {
    return PhotoView{"photos/t1/" + who + ".png",
                     "photos/t1/" + who + ".measured.png",
                     "/lab/" + who + ".png",
                     mm,
                     w,
                     h,
                     33.5};
  };
  loop.photo_pairs = {{"t1",
                       view("lab", 400, 300, 0.2),
                       view("twin", 960, 720, 0.1),
                       0.15,
                       1001,
                       {{"plate_friction", 0.4}},
                       ""},
                      {"t2",
                       view("lab", 400, 300, 0.2),
                       std::nullopt,
                       0.15,
                       1001,
                       {},
                       "no view of the twin's photograph could be measured"},
                      {"t3", std::nullopt, view("twin", 960, 720, 0.1), 0.15, 1001, {}, ""}};
  const std::string html = page(loop, out);
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
  EXPECT_EQ(page(small_loop(false), out).find("like for like"), std::string::npos);

  // Rebuilt after the photos were left out of the folder (results/ keeps loop.json and the page,
  // not the photos): no image or link points at a missing file, the scales and angles stay,
  // and the page says the photos are not there.
  fs::remove_all(out / "photos");
  const std::string pruned = page(loop, out);
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
  LoopRecord loop = small_loop(false);
  loop.tests = {lab_test("t1", Role::kCalibrate, 35,
                         {{"mass_kg", 0.5}, {"d_min_mm", 3}, {"d_max_mm", 4}, {"W_mm", 40}}),
                lab_test("t2", Role::kCalibrate, 35,
                         {{"mass_kg", 0.5}, {"d_min_mm", 2}, {"d_max_mm", 4}, {"W_mm", 40}}),
                lab_test("t3", Role::kValidate, 35, {{"mass_kg", 1.0}, {"W_mm", 40}})};
  loop.tests[0].text_conditions = {{"plate", "wood"}, {"funnel", "steel"}};
  loop.tests[1].text_conditions = {{"plate", "steel"}, {"funnel", "steel"}};
  loop.tests[2].text_conditions = {
      {"plate", "wood"}, {"funnel", "steel"}, {"set:sample.psd_file", "psd/fine.toml"}};
  loop.tests[2].camera_height_m = 0.05;
  for (std::vector<ResidualRow>* rows : {&loop.baseline.residuals, &loop.final_model.residuals}) {
    *rows = {residual_row("t1", Role::kCalibrate, 1.25),
             residual_row("t2", Role::kCalibrate, -0.75), residual_row("t3", Role::kValidate, 2.5)};
    for (ResidualRow& r : *rows) r.predicted_deg = 35.0;
  }
  const fs::path plots = out / "plots";
  fs::create_directories(plots);  // an earlier rendering's plot against W_mm
  write_file_atomic((plots / "residual_W_mm.dat").string(), "# stale\n");
  page(loop, out);
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
