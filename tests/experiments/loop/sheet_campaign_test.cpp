// A lab's own calibration from its sheets (loop/sheet_campaign.hpp): a good test sheet and
// sieve sheet become a campaign with the two range ends first, and every bad sheet is refused
// naming the file, the row, the column and the value before anything runs.
#include "experiments/loop/sheet_campaign.hpp"

#include <gtest/gtest.h>

#include <filesystem>

#include "experiments/campaign/campaign.hpp"
#include "experiments/io/campaign_keys.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/io/scene_overrides.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;

const std::string kScene = std::string(REPOSETWIN_SOURCE_DIR) + "/data/loop/tiny_scene.toml";

fs::path dir() {
  const fs::path d = fs::temp_directory_path() / "reposetwin_sheet_campaign_test";
  fs::create_directories(d);
  return d;
}

// Writes a file in the test folder and returns its path.
std::string write(const std::string& name, const std::string& text) {
  const fs::path p = dir() / name;
  write_file_atomic(p.string(), text);
  return p.string();
}

SheetCalibrationRequest request(const std::string& tests, const std::string& sieve = "") {
  SheetCalibrationRequest r;
  r.tests_csv = tests;
  r.sieve_sheet = sieve;
  r.scene = kScene;
  r.mu_r_lo = 0.05;
  r.mu_r_hi = 0.4;
  r.campaign_file = (dir() / "out" / "campaign.toml").string();
  return r;
}

// The message of making the campaign from `csv_text`, or "" when it is made.
std::string error_of(const std::string& name, const std::string& csv_text) {
  try {
    (void)sheet_campaign(request(write(name, csv_text)));
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

const char* kSieve = "# the lab's sieve sheet\nsieve_mm,passing_percent\n3.0,0\n3.4,40\n4.0,100\n";

TEST(SheetCampaign, SheetsBecomeACampaignWithTheEndsFirst) {
  const std::string sieve = write("sieve.csv", kSieve);
  const std::string tests = write("good.csv",
                                  "id,mass_g,W_mm,funnel_top_mm,H_mm,D_mm,angle_deg\n"
                                  "t1,6,20,50,10,40,\n"
                                  "t2,5,22,50,,,28.5\n");
  const SheetCampaign sc = sheet_campaign(request(tests, sieve));
  const Campaign& c = sc.campaign;
  ASSERT_TRUE(c.calibration.has_value());
  const CampaignCalibration& cc = *c.calibration;
  EXPECT_EQ(c.name, "good");
  EXPECT_EQ(cc.method, CalibrationMethod::kBracket);
  EXPECT_TRUE(cc.bracket.ends_first);
  EXPECT_EQ(cc.bracket.mu_r_lo, 0.05);
  EXPECT_EQ(cc.bracket.mu_r_hi, 0.4);
  EXPECT_EQ(cc.bracket.seeds.size(), 2u);
  // No role column: the first row is the target (atan(2H/D) of its typed H and D), the second
  // a prediction with its own conditions.
  EXPECT_NEAR(cc.target.angle_deg, std::atan(2.0 * 10.0 / 40.0) * 180.0 / M_PI, 1e-9);
  ASSERT_EQ(c.predictions.size(), 1u);
  EXPECT_EQ(c.predictions[0].name, "t2");
  EXPECT_DOUBLE_EQ(c.predictions[0].measured.angle_deg, 28.5);
  // The calibration runs are the base scene with the row's conditions and the sieve sheet in
  // place of the scene's own sieve table.
  const SceneConfig s = build_case_scene(calibration_run(c, 0.05, 1)).config();
  EXPECT_NEAR(s.mass, 0.006, 1e-12);
  EXPECT_NEAR(s.container.bottom_diameter, 0.020, 1e-12);
  EXPECT_NEAR(s.container.top_diameter, 0.050, 1e-12);
  ASSERT_EQ(s.psd.spec.table.size.size(), 3u);
  EXPECT_NEAR(s.psd.spec.table.size[1], 3.4e-3, 1e-12);
  const SceneConfig p = build_case_scene(prediction_run(c, c.predictions[0], 0.05, 1)).config();
  EXPECT_NEAR(p.mass, 0.005, 1e-12);
  EXPECT_NEAR(p.container.bottom_diameter, 0.022, 1e-12);
  EXPECT_NEAR(p.psd.spec.table.size[1], 3.4e-3, 1e-12);
  // The text is an ordinary campaign file: parsed again, it asks the same.
  const Campaign again = parse_campaign(sc.text, (dir() / "again.toml").string());
  EXPECT_EQ(again.calibration->target.angle_deg, cc.target.angle_deg);
  EXPECT_NE(sc.text.find("ends_first = true"), std::string::npos) << sc.text;
}

TEST(SheetCampaign, AMissingColumnIsNamedWithItsLine) {
  const std::string e = error_of("nocol.csv", "mass_g,angle_deg\n6,30\n");
  EXPECT_NE(e.find("nocol.csv line 1: the required column \"id\" is missing"), std::string::npos)
      << e;
}

TEST(SheetCampaign, AnUnknownColumnIsNamed) {
  const std::string e = error_of("unknown.csv", "id,mass_g,angel_deg\nt1,6,30\n");
  EXPECT_NE(e.find("unknown.csv line 1: unknown column \"angel_deg\""), std::string::npos) << e;
}

TEST(SheetCampaign, ANonNumericCellIsNamedWithRowColumnAndValue) {
  const std::string e = error_of("word.csv", "id,mass_g,angle_deg\nt1,heavy,30\n");
  EXPECT_NE(e.find("word.csv line 2 (test t1), column mass_g: \"heavy\" is not a number"),
            std::string::npos)
      << e;
}

TEST(SheetCampaign, AMissingPhotoIsNamedBeforeAnythingIsMeasured) {
  const std::string e = error_of("photo.csv", "id,mass_g,photo\nt1,6,lab/side_0.png\n");
  EXPECT_NE(e.find("photo.csv line 2 (test t1), column photo: \""), std::string::npos) << e;
  EXPECT_NE(e.find("lab/side_0.png\" does not exist"), std::string::npos) << e;
}

TEST(SheetCampaign, APredictionMustSetTheCalibrationRowsConditions) {
  const std::string e =
      error_of("gap.csv", "id,mass_g,W_mm,angle_deg\nt1,6,20,30\nt2,5,,29\n");
  EXPECT_NE(e.find("gap.csv line 3 (test t2), column W_mm"), std::string::npos) << e;
  EXPECT_NE(e.find("calibration test t1"), std::string::npos) << e;
}

TEST(SheetCampaign, OneRowCalibrates) {
  const std::string e = error_of("two.csv",
                                 "id,role,angle_deg\nt1,calibrate,30\nt2,calibrate,31\n");
  EXPECT_NE(e.find("two.csv line 3 (test t2), column role"), std::string::npos) << e;
  const std::string none = error_of("none.csv", "id,role,angle_deg\nt1,validate,30\n");
  EXPECT_NE(none.find("no row has role \"calibrate\""), std::string::npos) << none;
}

TEST(SheetCampaign, ABadSieveSheetIsNamed) {
  const std::string sieve = write("badsieve.csv", "sieve_mm,passing\n3.0,0\n4.0,100\n");
  const std::string tests = write("forsieve.csv", "id,angle_deg\nt1,30\n");
  try {
    (void)sheet_campaign(request(tests, sieve));
    FAIL() << "a sieve sheet with an unknown column was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("badsieve.csv"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("passing"), std::string::npos) << e.what();
  }
}

// A sieve sheet the scene cannot take (its sieves do not reach 100 % passing) is named as the
// command's --sieve with the sheet's own file, not blamed on the test sheet's scene column.
TEST(SheetCampaign, ASieveSheetsErrorNamesTheSieveSheetNotTheSceneColumn) {
  const std::string sieve = write("short.csv", "sieve_mm,passing_percent\n4.0,90\n3.0,0\n");
  const std::string tests = write("forshort.csv", "id,angle_deg\nt1,30\n");
  try {
    (void)sheet_campaign(request(tests, sieve));
    FAIL() << "a sieve sheet short of 100 % was accepted";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("--sieve " + sieve + ": ", 0), 0u) << what;
    EXPECT_NE(what.find("short.csv"), std::string::npos) << what;
    EXPECT_EQ(what.find("column scene"), std::string::npos) << what;
  }
}

// Every key the campaign readers allow is in the reference, and the reference is what
// docs/calibration.md shows.
TEST(CampaignKeys, TheReferenceIsTheReadersListAndTheDocsPage) {
  for (const char* table : {"", "case", "sweep", "calibration", "predict"})
    EXPECT_FALSE(campaign_table_keys(table).empty()) << table;
  EXPECT_TRUE(campaign_table_keys("calibration").count("ends_first"));
  EXPECT_TRUE(campaign_table_keys("calibration").count("target_photos"));
  EXPECT_TRUE(campaign_table_keys("").count("calibration"));
  const std::string doc = read_file(std::string(REPOSETWIN_SOURCE_DIR) + "/docs/calibration.md");
  EXPECT_NE(doc.find(campaign_keys_markdown()), std::string::npos)
      << "docs/calibration.md is not current: paste `reposetwin keys --campaign --markdown`";
  EXPECT_NE(doc.find(test_sheet_markdown()), std::string::npos)
      << "docs/calibration.md is not current: paste `reposetwin keys --campaign --markdown`";
}

}  // namespace
}  // namespace reposetwin::experiments
