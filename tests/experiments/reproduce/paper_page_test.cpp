// The paper page over a tiny fake results tree: every item has its section, the paper's values
// and ours are shown, "not yet run" where nothing exists, images exist and links are relative,
// and no raw JSON reaches the page.
#include "experiments/reproduce/paper_page.hpp"
#include "experiments/report/page_check.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <regex>

#include "../../support/tiny_scene.hpp"
#include "experiments/calibration/calibration_file.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/provenance.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;

constexpr const char* kIndex = R"TOML(title = "fake paper"
budget_cpu_hours = 1.0
[[item]]
name = "mass"
paper = "Fig. 8"
kind = "campaign"
file = "mass.toml"
reductions = "the tiny scene"
x_key = "sample.mass_kg"
x_label = "mass [g]"
x_scale = 1000.0
trend = "the angle rises with mass, then levels off"
[[item]]
name = "cal"
paper = "Table 3"
kind = "calibration"
file = "cal.toml"
reductions = "the tiny scene"
[item.paper_points]
x_label = "mu_r (EDEM)"
x = [0.15]
y = [33.64]
source = "Table 3"
[[item]]
name = "never"
paper = "Fig. 18"
kind = "campaign"
file = "mass.toml"
reductions = "the tiny scene, never run here"
trend = "stabilises near 36.5 deg"
)TOML";

// A finished run's result.json, shaped as the campaign runner writes it.
json fake_run(const std::string& case_name, double mass, std::uint64_t seed, double angle,
              const std::string& status = "ok") {
  return {
      {"spec", {{"case", case_name}, {"seed", seed}, {"overrides", {{"sample.mass_kg", mass}}}}},
      {"result",
       {{"stop", {{"reason", status == "ok" ? "settled" : "clogged"}}},
        {"pile", {{"status", status}, {"theta_hd_deg", angle}, {"slice_angle_mean_deg", angle}}},
        {"image", {{"theta_deg", angle}, {"flank_deg", angle + 4.0}}},
        {"provenance", {{"code_version", "test"}}},
        {"run_dir", "run"}}}};
}

struct Tree {
  Tree() {
    root = fs::temp_directory_path() / ("reposetwin_paper_page_test_" + std::to_string(::getpid()));
    fs::remove_all(root);
    fs::create_directories(root);
    write_file_atomic((root / "tiny.toml").string(), test_support::kTinyScene);
    write_file_atomic((root / "mass.toml").string(),
                      "name = \"mass\"\nscene = \"tiny.toml\"\nseeds = [1, 2]\n[sweep]\n"
                      "key = \"sample.mass_kg\"\nvalues = [0.004, 0.006]\nname = \"m\"\n");
    write_file_atomic((root / "cal.toml").string(),
                      "name = \"cal\"\nscene = \"tiny.toml\"\n[calibration]\n"
                      "key = \"contacts.rock-rock.rolling_friction\"\ntarget_deg = 33.47\n"
                      "mu_r_range = [0.1, 0.5]\nmethod = \"bracket\"\n");
    write_file_atomic((root / "index.toml").string(), kIndex);
    const fs::path out = root / "out";
    const auto put = [&](const std::string& rel, const json& j) {
      write_json_atomic((out / rel).string(), j);
    };
    put("mass/cases/m_0.004/seed_1/result.json", fake_run("m_0.004", 0.004, 1, 20.0));
    put("mass/cases/m_0.004/seed_2/result.json", fake_run("m_0.004", 0.004, 2, 22.0));
    put("mass/cases/m_0.006/seed_1/result.json", fake_run("m_0.006", 0.006, 1, 25.0));
    put("mass/cases/m_0.006/seed_2/result.json", fake_run("m_0.006", 0.006, 2, 0.0, "no pile"));
    // A bracketing calibration's record, written by its one writer.
    CalibrationRecord cal;
    cal.status = CalibrationStatus::kCalibrated;
    cal.target = {33.0, 0.5};
    cal.method = CalibrationMethod::kBracket;
    cal.mu_r = 0.31;
    cal.mu_r_lo = 0.29;
    cal.mu_r_hi = 0.33;
    cal.fitted_angle_deg = 33.5;
    cal.simulations = 6;
    cal.keys = {"contacts.rock-rock.rolling_friction"};
    cal.rolling_model.keyword = "epsd";
    cal.observations = {{0.3, 1, 33.0}};
    cal.fit.points = {{0.3, 1, 33.0, 0.0, 33.0}, {0.35, 1, 34.0, 0.0, 34.0}};
    cal.pour_counts = {{0.3, 2, 1, 1, 0, 0, 0, 0.5, true}};
    put("cal/calibration.json", to_json(cal));
  }
  ~Tree() {
    std::error_code ec;
    fs::remove_all(root, ec);
  }
  fs::path root;
};

TEST(PaperPage, ShowsThePaperBesideOursOnAFakeTree) {
  const Tree t;
  const PaperIndex idx = load_paper_index((t.root / "index.toml").string());
  const fs::path out = t.root / "out";
  const std::string page = build_paper_page(idx, out.string(), false);
  ASSERT_TRUE(fs::exists(page));
  const std::string html = read_file(page);
  // Every item has its section, and the unrun one says so.
  for (const char* anchor : {"id='mass'", "id='cal'", "id='never'"})
    EXPECT_NE(html.find(anchor), std::string::npos) << anchor;
  EXPECT_NE(html.find("Not yet run"), std::string::npos);
  // The paper's values and trends; ours with the seed spread over the piles only (20 and 22:
  // 21.00 +- 1.41), the run without a pile counted by its reason.
  EXPECT_NE(html.find("33.64"), std::string::npos);
  EXPECT_NE(html.find("levels off"), std::string::npos);
  EXPECT_NE(html.find("21.00 \u00b1 1.41"), std::string::npos);
  EXPECT_NE(html.find("1 jam"), std::string::npos);
  EXPECT_NE(html.find("0.310 [0.290, 0.330]"), std::string::npos);
  EXPECT_NE(html.find("jam rate 0.50"), std::string::npos);
  // The reductions and the planned cost of each item.
  EXPECT_NE(html.find("never run here"), std::string::npos);
  EXPECT_NE(html.find("CPU-h"), std::string::npos);
  // No raw JSON on the page.
  EXPECT_EQ(html.find("{\""), std::string::npos);
  EXPECT_EQ(html.find("\"mu_r\""), std::string::npos);
  EXPECT_EQ(html.find("{&quot;"), std::string::npos);
  // Every image exists beside the page, by a relative link.
  const std::regex img("<img src='([^']+)'");
  int images = 0;
  for (auto it = std::sregex_iterator(html.begin(), html.end(), img); it != std::sregex_iterator();
       ++it) {
    const std::string src = (*it)[1];
    EXPECT_FALSE(fs::path(src).is_absolute()) << src;
    EXPECT_TRUE(fs::exists(fs::path(page).parent_path() / src)) << src;
    ++images;
  }
  if (std::system("gnuplot --version > /dev/null 2>&1") == 0) {
    EXPECT_GE(images, 2);
  }
  // Nothing a reader of a copied page cannot open: no absolute link or path, no missing file, plot
  // scripts that name their files by name only.
  for (const report::PageProblem& p : report::page_problems(page))
    ADD_FAILURE() << report::to_string(p.kind) << ": " << p.what;
  // A calibration item's plot shows the fit and the calibrated mu_r.
  const std::string gp = read_file((fs::path(page).parent_path() / "cal.gp").string());
  EXPECT_NE(gp.find("cal_fit.dat"), std::string::npos) << gp;
  EXPECT_NE(gp.find("calibrated mu_r 0.310"), std::string::npos) << gp;
  // Every anchor link points at a section of the page.
  EXPECT_NE(html.find("href='#mass'"), std::string::npos);
  // An earlier page is kept unless forced.
  EXPECT_THROW(build_paper_page(idx, out.string(), false), InputError);
  EXPECT_NO_THROW(build_paper_page(idx, out.string(), true));
}

}  // namespace
}  // namespace reposetwin::experiments
