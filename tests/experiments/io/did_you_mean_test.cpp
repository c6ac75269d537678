// "Did you mean": one helper (io/suggest.hpp) names the nearest known name in every strict
// reader's refusal: a scene key, a sieve table's key, a campaign key, a calibration record's key,
// a sieve sheet's column and a test sheet's column. A name far from every known one gets no guess.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "../../support/scratch.hpp"
#include "../../support/tiny_scene.hpp"
#include "experiments/calibration/campaign_target.hpp"
#include "experiments/calibration/calibration_file.hpp"
#include "experiments/io/calibration_record.hpp"
#include "experiments/io/files.hpp"
#include "experiments/io/psd_file.hpp"
#include "experiments/io/scene.hpp"
#include "experiments/io/suggest.hpp"
#include "experiments/loop/loop_data.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;

template <class F>
std::string refusal(F&& read) {
  try {
    read();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(DidYouMean, NearNamesOnlyAndTiesInOrder) {
  const std::vector<std::string> known = {"rolling_friction", "friction", "restitution"};
  EXPECT_EQ(closest_name("rolling_frction", known), "rolling_friction");
  EXPECT_EQ(closest_name("fricton", known), "friction");
  EXPECT_EQ(closest_name("colour", known), "");
  EXPECT_EQ(did_you_mean("restitutoin", known), "; did you mean restitution?");
  EXPECT_EQ(did_you_mean("colour", known), "");
  EXPECT_EQ(did_you_mean("--sett", std::vector<std::string>{"--set", "--seed"}, "'"),
            "; did you mean '--set'?");
}

TEST(DidYouMean, EveryStrictReaderNamesTheNearestKnownName) {
  const test_support::UniqueTempDir d("did_you_mean");
  const auto file = [&](const std::string& name, const std::string& text) {
    write_file_atomic((d.path() / name).string(), text);
    return (d.path() / name).string();
  };
  // A scene key (the TOML reader's finish(): the keys the table's reader asked for).
  const std::string scene = refusal([&] {
    parse_scene_text(std::string(test_support::kTinyScene) + "[output]\nframe_intervl_s = 1.0\n",
                     "s.toml");
  });
  EXPECT_NE(scene.find("did you mean frame_interval_s?"), std::string::npos) << scene;
  // A sieve table's key.
  const std::string psd = refusal([&] {
    read_psd_file(file("p.toml", "[psd]\nsieve_mm = [1, 2]\npassing_percnt = [0, 100]\n"));
  });
  EXPECT_NE(psd.find("did you mean passing_percent?"), std::string::npos) << psd;
  // A campaign file's key.
  file("base.toml", test_support::kTinyScene);
  const std::string campaign = refusal(
      [&] { load_campaign(file("c.toml", "name = \"c\"\nscene = \"base.toml\"\nseedz = [1]\n")); });
  EXPECT_NE(campaign.find("did you mean seeds?"), std::string::npos) << campaign;
  // A sieve sheet's column.
  const std::string sieve =
      refusal([&] { read_psd_file(file("s.csv", "sieve_mm,pasing_percent\n1,0\n2,100\n")); });
  EXPECT_NE(sieve.find("did you mean \"passing_percent\"?"), std::string::npos) << sieve;
  // A test sheet's column.
  LabSheetForm form;
  form.base_scene = (d.path() / "base.toml").string();
  form.role_required = false;
  const std::string tests =
      refusal([&] { read_lab_csv(file("t.csv", "id,angel_deg\nt1,30\n"), form); });
  EXPECT_NE(tests.find("did you mean \"angle_deg\"?"), std::string::npos) << tests;
  // A calibration record's key.
  fs::create_directories(d.path() / "cal");
  CalibrationRecord reached;
  reached.mu_r = 0.3;
  reached.fitted_angle_deg = 30.0;
  reached.keys = {"contacts.rock-rock.rolling_friction"};
  nlohmann::json cal = to_json(reached);
  cal["material"] = {{"scen", "x"}};
  file("cal/calibration.json", cal.dump());
  const std::string record =
      refusal([&] { read_calibrated_material((d.path() / "cal").string()); });
  EXPECT_NE(record.find("did you mean scene?"), std::string::npos) << record;
}

}  // namespace
}  // namespace reposetwin::experiments
