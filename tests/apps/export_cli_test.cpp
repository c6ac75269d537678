// `reposetwin export` as a user types it: a calibration's folder (nothing retyped), or a scene
// file with --set as before; a folder that holds no calibration record is refused before
// anything is written, naming the file and the key.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_support.hpp"
#include "experiments/io/hash.hpp"
#include "tests/support/scratch.hpp"
#include "tests/support/tiny_scene.hpp"

namespace reposetwin::test_support {
namespace {

bool has(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// A finished calibration of the tiny scene with a sieve sheet, as `calibrate` leaves it:
// mu_r 0.297 (95% 0.258 to 0.339) for a target of 31.5 deg. Returns its folder.
fs::path write_calibration(const fs::path& dir) {
  const fs::path cal = dir / "cal1";
  write_text(dir / "base.toml", kTinyScene);
  write_text(dir / "sieve.csv", "sieve_mm,passing_percent\n3.0,0\n3.6,50\n4.0,100\n");
  const nlohmann::json material = {
      {"scene", (dir / "base.toml").string()},
      {"scene_fnv1a", experiments::fnv1a_hex(kTinyScene)},
      {"overrides",
       {{{"key", "sample.psd_file"}, {"value", "\"" + (dir / "sieve.csv").string() + "\""}}}},
      {"keys", {"contacts.rock-rock.rolling_friction"}},
      {"mu_r", 0.297},
      {"mu_r_interval", {0.258, 0.339}},
      {"target_deg", 31.5},
      {"angle", "image"},
      {"sieve_sheet", (dir / "sieve.csv").string()}};
  // A whole calibration record around it, as `reposetwin calibrate` writes one.
  const nlohmann::json record = {
      {"status", "calibrated"},
      {"message", "converged"},
      {"target", {{"angle_deg", 31.5}, {"sd_deg", 0.5}}},
      {"mu_r", 0.297},
      {"mu_r_interval", {0.258, 0.339}},
      {"interval_level", 0.95},
      {"interval_open", {false, false}},
      {"fitted_angle_deg", 31.5},
      {"fitted_angle_halfwidth_deg", 0.2},
      {"reachable_deg", {25.0, 40.0}},
      {"method", "sequential"},
      {"simulations", 6},
      {"fit",
       {{"method", "isotonic"},
        {"points", nlohmann::json::array()},
        {"noise_sd_deg", 0.3},
        {"noise_dof", 3}}},
      {"observations", nlohmann::json::array()},
      {"excluded_search_observations", nlohmann::json::array()},
      {"campaign", (dir / "c.toml").string()},
      {"campaign_name", "c"},
      {"keys", {"contacts.rock-rock.rolling_friction"}},
      {"mu_r_range", {0.05, 0.6}},
      {"tolerance_deg", 0.3},
      {"seeds_per_point", 2},
      {"table1_sample", nullptr},
      {"scene", (dir / "base.toml").string()},
      {"rolling_model", {{"keyword", "epsd"}, {"stated_in_scene", false}}},
      {"angle_method", "vision on renders"},
      {"created_utc", "2026-12-08T00:00:00Z"},
      {"material", material}};
  write_text(cal / "calibration.json", record.dump(2));
  return cal;
}

TEST(ExportCli, FromACalibrationFolderNothingRetyped) {
  const UniqueTempDir d("export_cli");
  const fs::path cal = write_calibration(d.path());
  const CliResult r = run_cli_argv({"export", cal.string()}, d.path());
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(has(r.out, "at the calibrated mu_r 0.297 (95% 0.258 to 0.339")) << r.out;
  const std::string notes = read_text(cal / "liggghts" / "README.md");
  EXPECT_TRUE(has(notes, "mu_r = 0.297, 95% interval 0.258 to 0.339")) << notes;
  EXPECT_TRUE(has(notes, "sieve.csv")) << notes;
  const std::string deck = read_text(cal / "liggghts" / "in.pile");
  EXPECT_TRUE(has(deck, "coefficientRollingFriction peratomtypepair 3 0.297")) << deck;

  // --set still applies on top, and the deck says its value is not the calibrated one.
  const CliResult set = run_cli_argv({"export", cal.string(), "--out", "other", "--set",
                                      "contacts.rock-rock.rolling_friction=0.25"},
                                     d.path());
  ASSERT_EQ(set.code, 0) << set.out;
  EXPECT_TRUE(has(read_text(d.path() / "other" / "README.md"), "NOT the calibrated 0.297"));
}

TEST(ExportCli, AFolderWithoutARecordIsRefusedNamingFileAndKey) {
  const UniqueTempDir d("export_cli_bad");
  const fs::path cal = d.path() / "cal1";
  fs::create_directories(cal);
  const CliResult none = run_cli_argv({"export", cal.string()}, d.path());
  EXPECT_NE(none.code, 0);
  EXPECT_TRUE(has(none.out, "holds no calibration.json")) << none.out;
  write_text(cal / "calibration.json", "{}");
  const CliResult empty = run_cli_argv({"export", cal.string()}, d.path());
  EXPECT_NE(empty.code, 0);
  EXPECT_TRUE(has(empty.out, (cal / "calibration.json").string() + ": key \"status\": missing"))
      << empty.out;
  EXPECT_FALSE(fs::exists(cal / "liggghts"));
}

TEST(ExportCli, ASceneFileWithSetStillExports) {
  const UniqueTempDir d("export_cli_scene");
  write_text(d.path() / "s.toml", kTinyScene);
  const CliResult r = run_cli_argv(
      {"export", "s.toml", "--out", "deck", "--set", "contacts.rock-rock.rolling_friction=0.2"},
      d.path());
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(has(read_text(d.path() / "deck" / "in.pile"),
                  "coefficientRollingFriction peratomtypepair 3 0.2"));
  const CliResult no_out = run_cli_argv({"export", "s.toml"}, d.path());
  EXPECT_NE(no_out.code, 0);
  EXPECT_TRUE(has(no_out.out, "--out is required")) << no_out.out;
}

// A misspelt option is named with the one meant, from the options that command takes.
TEST(ExportCli, AMisspeltOptionGetsDidYouMean) {
  const UniqueTempDir d("export_cli_option");
  write_text(d.path() / "s.toml", kTinyScene);
  const CliResult r = run_cli_argv(
      {"export", "s.toml", "--out", "deck", "--sett", "contacts.rock-rock.rolling_friction=0.2"},
      d.path());
  EXPECT_NE(r.code, 0);
  EXPECT_TRUE(has(r.out, "--sett: not an option of reposetwin export; did you mean '--set'?"))
      << r.out;
  EXPECT_FALSE(fs::exists(d.path() / "deck"));
}

// The field deck from the same folder: the calibrated mu_r, the decomposition for two ranks, the
// scaling table printed; an existing deck is kept unless --force.
TEST(ExportCli, FieldDumpFromACalibrationFolder) {
  const UniqueTempDir d("export_cli_field");
  const fs::path cal = write_calibration(d.path());
  const CliResult r =
      run_cli_argv({"export", cal.string(), "--field", "dump", "--ranks", "2"}, d.path());
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(has(r.out, "What the field deck scales and how:")) << r.out;
  EXPECT_TRUE(has(r.out, "processors 2 1 1")) << r.out;
  EXPECT_TRUE(has(r.out, "mpirun -np 2 liggghts -in in.dump")) << r.out;
  const fs::path out = cal / "liggghts_dump";
  const std::string deck = read_text(out / "in.dump");
  EXPECT_TRUE(has(deck, "coefficientRollingFriction peratomtypepair 3 0.297")) << deck;
  EXPECT_TRUE(has(deck, "\nprocessors 2 1 1\n")) << deck;
  EXPECT_TRUE(has(read_text(out / "README.md"), "mu_r = 0.297, 95% interval 0.258 to 0.339"));
  EXPECT_FALSE(fs::exists(out / "container.stl"));
  const CliResult again =
      run_cli_argv({"export", cal.string(), "--field", "dump", "--ranks", "4"}, d.path());
  EXPECT_NE(again.code, 0);
  EXPECT_TRUE(has(again.out, "holds a deck already (in.dump); --force replaces it")) << again.out;
  EXPECT_TRUE(has(read_text(out / "in.dump"), "\nprocessors 2 1 1\n"));
  const CliResult forced = run_cli_argv(
      {"export", cal.string(), "--field", "dump", "--ranks", "4", "--force"}, d.path());
  ASSERT_EQ(forced.code, 0) << forced.out;
  EXPECT_TRUE(has(read_text(out / "in.dump"), "\nprocessors 2 2 1\n"));
}

// A bad field option is refused naming it and its value, with a non-zero exit, before anything
// is written.
TEST(ExportCli, ABadFieldOptionIsRefusedNamingItBeforeWriting) {
  const UniqueTempDir d("export_cli_field_bad");
  write_text(d.path() / "s.toml", kTinyScene);
  const struct {
    std::vector<std::string> args;
    std::string says;
  } cases[] = {
      {{"--field", "dump", "--dump-mass-kg", "-1"}, "--dump-mass-kg -1: must be a positive"},
      {{"--field", "dump", "--size-scale", "5"}, "--size-scale 5: "},
      {{"--field", "dump", "--dump-height-m", "0.01"}, "--dump-height-m 0.01: "},
      {{"--field", "stope"}, "--field stope: not a field deck"},
      {{"--field", "dump", "--ranks", "two"}, "--ranks"},
      {{"--dump-mass-kg", "1"}, "--field"},
  };
  for (const auto& c : cases) {
    std::vector<std::string> argv = {"export", "s.toml", "--out", "deck"};
    argv.insert(argv.end(), c.args.begin(), c.args.end());
    const CliResult r = run_cli_argv(argv, d.path());
    EXPECT_NE(r.code, 0) << c.args.front();
    EXPECT_TRUE(has(r.out, c.says)) << r.out;
    EXPECT_FALSE(fs::exists(d.path() / "deck")) << c.args.front();
  }
}

}  // namespace
}  // namespace reposetwin::test_support
