// A finished calibration hands its material to the export: calibrate writes the record (the base
// scene, the test's overrides with its sieve sheet, the keys, mu_r and its interval), the reader
// takes it back strictly, and the deck rebuilt from it states the calibrated value. The
// "simulations" are a closed form, angle = 20 + 50 mu_r [deg], so a target of 35 deg is mu_r 0.3.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "../../support/quiet_runner.hpp"
#include "../../support/scratch.hpp"
#include "../../support/tiny_scene.hpp"
#include "experiments/calibration/calibrate_campaign.hpp"
#include "experiments/calibration/calibration_file.hpp"
#include "experiments/calibration/campaign_target.hpp"
#include "experiments/campaign/campaign.hpp"
#include "experiments/campaign/case_runner.hpp"
#include "experiments/export/liggghts_deck.hpp"
#include "experiments/io/calibration_record.hpp"
#include "experiments/io/files.hpp"
#include "experiments/io/format.hpp"
#include "experiments/io/hash.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/scene_overrides.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;

constexpr const char* kKey = "contacts.rock-rock.rolling_friction";

CaseFn closed_form_case() {
  return [](const CaseSpec& s, const std::string&) {
    const double a = 20.0 + 50.0 * build_case_scene(s).number(kKey).value();
    return json{{"stop", {{"reason", "settled"}}},
                {"pile", {{"status", "ok"}, {"theta_hd_deg", a}, {"slice_angle_mean_deg", a}}},
                {"provenance", {{"time_step_s", 1e-6}, {"code_version", "test"}}},
                {"image", {{"theta_deg", a}, {"flank_deg", a}}},
                {"run_dir", "run"}};
  };
}

// The tiny scene, a sieve sheet beside it and a campaign that calibrates on it, in `dir`.
void write_inputs(const fs::path& dir) {
  write_file_atomic((dir / "base.toml").string(), test_support::kTinyScene);
  write_file_atomic((dir / "sieve.csv").string(),
                    "# lab sheet\nsieve_mm,passing_percent\n3.0,0\n3.4,40\n4.0,100\n");
  write_file_atomic((dir / "campaign.toml").string(),
                    "name = \"cal\"\nscene = \"base.toml\"\nseeds = [1]\n"
                    "overrides = { \"sample.psd_file\" = \"sieve.csv\", \"sample.mass_kg\" = "
                    "0.007 }\n[calibration]\nkey = \"" +
                        std::string(kKey) +
                        "\"\ntarget_deg = 35\ntarget_sd_deg = 0.3\nmu_r_range = [0.05, 0.6]\n"
                        "seeds_per_point = 2\ntolerance_deg = 0.3\nmax_simulations = 24\n"
                        "bootstrap_replicates = 200\n");
}

RunnerSettings quiet() { return test_support::quiet_runner(); }

std::string refusal(const std::string& folder) {
  try {
    read_calibrated_material(folder);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(ExportFromCalibration, TheDeckCarriesWhatWasCalibratedNothingRetyped) {
  const test_support::UniqueTempDir d("export_cal");
  write_inputs(d.path());
  const Campaign c = load_campaign((d.path() / "campaign.toml").string());
  const fs::path out = d.path() / "out";
  const CalibrationRecord cal = run_calibration(c, out.string(), closed_form_case(),
                                                calibration_angle(AngleMeasure::kImage), quiet());
  ASSERT_TRUE(cal.mu_r) << to_json(cal).dump(2);

  const CalibratedMaterial m = read_calibrated_material(out.string());
  EXPECT_EQ(cal.material, m);
  EXPECT_DOUBLE_EQ(m.mu_r, *cal.mu_r);
  EXPECT_NEAR(m.mu_r, 0.3, 0.02);
  EXPECT_DOUBLE_EQ(m.mu_r_lo, cal.mu_r_lo);
  EXPECT_DOUBLE_EQ(m.mu_r_hi, cal.mu_r_hi);
  EXPECT_LT(m.mu_r_lo, m.mu_r_hi);
  EXPECT_EQ(m.keys, std::vector<std::string>{kKey});
  EXPECT_EQ(m.scene, fs::absolute(d.path() / "base.toml").lexically_normal().string());
  EXPECT_EQ(m.sieve_sheet, fs::absolute(d.path() / "sieve.csv").lexically_normal().string());
  EXPECT_DOUBLE_EQ(m.target_deg, 35.0);
  EXPECT_EQ(m.angle, "image");

  // The scene rebuilt from the record is the calibration test's at mu_r: its sieve sheet, its
  // mass, the calibrated key.
  const SceneConfig scene = SceneDoc(m.scene, m.scene_overrides(), "test").config();
  EXPECT_EQ(scene.psd.source, m.sieve_sheet);
  EXPECT_DOUBLE_EQ(scene.mass, 0.007);
  EXPECT_DOUBLE_EQ(scene.contacts.at({"rock", "rock"}).rolling_friction, m.mu_r);

  DeckCalibration dc{&m, (out / "calibration.json").string(), {{kKey, m.mu_r}}};
  LiggghtsDeckSettings s;
  s.calibration = &dc;
  const LiggghtsDeck deck = liggghts_deck(scene, s);
  std::ostringstream mu;
  mu.precision(10);
  mu << "mu_r = " << m.mu_r << ", 95% interval " << m.mu_r_lo << " to " << m.mu_r_hi;
  EXPECT_NE(deck.notes.find(mu.str()), std::string::npos) << deck.notes;
  EXPECT_NE(deck.notes.find("the sieve sheet `" + m.sieve_sheet + "`"), std::string::npos);
  EXPECT_NE(deck.notes.find("(the calibrated value)"), std::string::npos);
  EXPECT_NE(deck.input.find("# calibrated: mu_r "), std::string::npos);
  std::ostringstream coeff;
  coeff.precision(10);
  coeff << "coefficientRollingFriction peratomtypepair 3 " << m.mu_r;
  EXPECT_NE(deck.input.find(coeff.str()), std::string::npos) << deck.input;

  // A deck at another value than the calibrated one says so.
  dc.deck_values = {{kKey, 0.5}};
  EXPECT_NE(liggghts_deck(scene, s).notes.find("NOT the calibrated"), std::string::npos);

  // The base scene edited since: refused, naming the record's key and the scene.
  std::ofstream(d.path() / "base.toml", std::ios::app) << "# edited\n";
  const std::string edited = refusal(out.string());
  EXPECT_NE(edited.find("material.scene"), std::string::npos) << edited;
  EXPECT_NE(edited.find("edited since"), std::string::npos) << edited;
}

// A folder without a record, an empty record, a calibration that reached nothing and a record
// with a misspelt, a missing or a mistyped key are refused, naming the file, the key and the
// value.
TEST(ExportFromCalibration, BadRecordsNameTheFileTheKeyAndTheValue) {
  const test_support::UniqueTempDir d("export_bad");
  write_file_atomic((d.path() / "base.toml").string(), test_support::kTinyScene);
  const std::string file = (d.path() / "calibration.json").string();
  EXPECT_NE(refusal((d.path() / "none").string()).find("not a calibration folder"),
            std::string::npos);
  EXPECT_NE(refusal(d.path().string()).find("holds no calibration.json"), std::string::npos);
  write_file_atomic(file, "{}");
  EXPECT_NE(refusal(d.path().string()).find(file + ": key \"status\": missing"), std::string::npos)
      << refusal(d.path().string());
  // A whole calibration record around the material (calibration_file.hpp reads all of it).
  CalibrationRecord unreached;
  unreached.status = CalibrationStatus::kCannotReachHigh;
  unreached.target = {35.0, 0.3};
  unreached.keys = {kKey};
  write_file_atomic(file, to_json(unreached).dump());
  EXPECT_NE(refusal(d.path().string()).find("status \"cannot_reach_high\""), std::string::npos)
      << refusal(d.path().string());
  CalibrationRecord reached = unreached;
  reached.status = CalibrationStatus::kCalibrated;
  reached.mu_r = 0.3;
  reached.mu_r_lo = 0.25;
  reached.mu_r_hi = 0.35;
  reached.fitted_angle_deg = 35.0;
  write_file_atomic(file, to_json(reached).dump());
  EXPECT_NE(refusal(d.path().string()).find("written before calibrations recorded their material"),
            std::string::npos)
      << refusal(d.path().string());

  CalibratedMaterial m;
  m.scene = "base.toml";  // relative: beside the record
  m.scene_fnv1a = fnv1a_hex(read_file((d.path() / "base.toml").string()));
  m.keys = {kKey};
  m.mu_r = 0.3;
  m.mu_r_lo = 0.25;
  m.mu_r_hi = 0.35;
  m.target_deg = 35.0;
  m.angle = "image";
  const json good = to_json(m);
  const auto with_material = [&](const json& material) {
    json j = to_json(reached);
    j["material"] = material;
    return j.dump();
  };
  write_file_atomic(file, with_material(good));
  EXPECT_EQ(refusal(d.path().string()), "(accepted)");

  struct Bad {
    json record;
    std::string says;
  };
  json typo = good, missing = good, wrong = good, outside = good;
  typo["mu_rr"] = typo["mu_r"];
  typo.erase("mu_r");
  missing.erase("keys");
  wrong["mu_r"] = "0.3";
  outside["mu_r_interval"] = {0.4, 0.5};
  for (const Bad& b :
       {Bad{typo,
            file + ": key \"material.mu_rr\": is not a known key (value 0.3); did you mean mu_r?"},
        Bad{missing, file + ": key \"material.keys\": missing"},
        Bad{wrong, file + ": key \"material.mu_r\" = \"0.3\": is string, not a number"},
        Bad{outside, file + ": key \"material.mu_r_interval\" = [0.4,0.5]: must be two finite"}}) {
    write_file_atomic(file, with_material(b.record));
    const std::string what = refusal(d.path().string());
    EXPECT_EQ(what.substr(0, b.says.size()), b.says) << what;
  }
}

// After a calibration: its page, and the export of its material when it reached a mu_r, on the
// folder's path quoted for a shell when it needs to be.
TEST(ExportFromCalibration, NextStepsNameTheFolder) {
  const auto reached = calibration_next_steps("runs/cal 1", true);
  ASSERT_EQ(reached.size(), 2u);
  EXPECT_EQ(reached[0].command, "reposetwin report 'runs/cal 1'");
  EXPECT_EQ(reached[1].command, "reposetwin export 'runs/cal 1'");
  const auto none = calibration_next_steps("runs/cal1", false);
  ASSERT_EQ(none.size(), 1u);
  EXPECT_EQ(none[0].command, "reposetwin report runs/cal1");
  EXPECT_EQ(shell_word("it's"), "'it'\\''s'");
}

}  // namespace
}  // namespace reposetwin::experiments
