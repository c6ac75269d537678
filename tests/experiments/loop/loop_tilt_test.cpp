// A tilted lab camera hidden in a twin-made dataset is refused when the dataset is read, before
// the loop simulates anything: the synthetic lab's true camera stands 25 mm above the plate,
// pitched down at the pile's axis foot (as a person holds a camera), while its sidecars declare it
// level. Vision reads the pose from the pile's base ellipse (vision/camera_pose.hpp) and
// read_lab_csv refuses the test, naming the photo and giving the estimated and the declared
// pitch. The same pile photographed by a level camera reads. The design comes through the
// design file's [camera] table, whose bad values are errors naming the file, key and value.
//
// Scene: data/loop/tiny_scene.toml with 25 g (a 6 g pile of 2-3 layers lies wholly below the
// plate's far edge seen from 15 mm up or more, and vision finds no pile at all), one pile (seed
// 7001), two views, the twin's framing (12 pile radii, 0.50 m). Measured: the refusal is the toe
// line cutting through the pile's base (29 px above the ellipse's ends), the pitch the ellipse
// gives 1.8 +- 0.1 deg against the closed form 2.9 deg; at 20 and 30 mm it gave 0.9 and 2.6
// against 2.3 and 3.4 deg. On these loose sphere piles the estimate runs 0.8-1.4 deg low and its
// stated sigma is far too small (on a hand-made cone, LoopCamera reads it within 1 deg), hence the
// 1.5 deg tolerance here.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "camera/camera.hpp"
#include "experiments/io/hash.hpp"
#include "experiments/io/csv.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/loop/loop_data.hpp"
#include "experiments/loop/loop_effects.hpp"
#include "experiments/loop/loop_synth.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;

const std::string kScene = std::string(REPOSETWIN_SOURCE_DIR) + "/data/loop/tiny_scene.toml";
constexpr double kRaise = 0.025;  // true camera height above the plate [m]

fs::path test_dir() { return fs::temp_directory_path() / "reposetwin_loop_tilt_test"; }

std::string write_design(const std::string& name, const std::string& camera_table) {
  fs::create_directories(test_dir());
  const fs::path p = test_dir() / (name + ".toml");
  write_file_atomic(p.string(), "scene = \"" + kScene + "\"\nmu_r = 0.2\nseeds = [7001]\n" +
                                    "[camera]\n" + camera_table +
                                    "[[test]]\nid = \"t1\"\nrole = \"calibrate\"\nmass_kg = 0.025\n");
  return p.string();
}

std::string design_error(const std::string& name, const std::string& camera_table) {
  try {
    (void)read_synth_design(write_design(name, camera_table));
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

// The truth a validation compares the loop's answer with (reposetwin loop-synth --truth) is the
// design file's hidden settings, with each effect's units and key from the registry.
TEST(LoopSynthTruth, TheTruthIsTheDesignsHiddenSettings) {
  fs::create_directories(test_dir());
  const fs::path p = test_dir() / "truth_design.toml";
  write_file_atomic(p.string(), "scene = \"" + kScene + "\"\nmu_r = 0.15\nseeds = [7001, 7004]\n" +
                                    "[camera]\nnoise_sd = 3.0\nheight_m = 0.02\n" +
                                    "[hidden]\ncohesion = 24000.0\n" +
                                    "[[test]]\nid = \"t1\"\nmass_kg = 0.025\n");
  const nlohmann::json t = synth_truth_json(read_synth_design(p.string()), p.string());
  EXPECT_EQ(t.at("design").get<std::string>(), p.string());
  EXPECT_DOUBLE_EQ(t.at("mu_r").get<double>(), 0.15);
  ASSERT_EQ(t.at("hidden").size(), 1u);
  EXPECT_EQ(t.at("hidden")[0].at("name").get<std::string>(), "cohesion");
  EXPECT_DOUBLE_EQ(t.at("hidden")[0].at("value").get<double>(), 24000.0);
  EXPECT_EQ(t.at("hidden")[0].at("units").get<std::string>(), find_effect("cohesion").units);
  EXPECT_EQ(t.at("seeds"), nlohmann::json({7001, 7004}));
  EXPECT_DOUBLE_EQ(t.at("camera").at("noise_sd").get<double>(), 3.0);
  EXPECT_DOUBLE_EQ(t.at("camera").at("height_m").get<double>(), 0.02);
}

TEST(LoopTilt, DesignFileCameraPoseAndItsBadValues) {
  const SynthDesign d = read_synth_design(write_design(
      "good", "side_views = 2\nnoise_sd = 2.0\nheight_m = 0.025\naim_at_axis_foot = true\n"));
  EXPECT_DOUBLE_EQ(d.camera.camera_height_m, 0.025);
  EXPECT_TRUE(d.camera.aim_at_axis_foot);
  EXPECT_EQ(d.camera.side_views, 2);
  // The lab declares a level, undistorted camera whatever the truth.
  EXPECT_DOUBLE_EQ(d.camera.declared_height_m, 0.0);
  EXPECT_DOUBLE_EQ(d.camera.declared_k1, 0.0);
  const std::string file = (test_dir() / "bad.toml").string();
  const std::pair<const char*, const char*> bad[] = {
      {"height_m = -0.01\n", "camera.height_m = -0.01 must be in [0, 1] m"},
      {"aim_at_axis_foot = 1\n", "camera.aim_at_axis_foot must be true or false, got 1"},
      {"side_views = 0\n", "camera.side_views = 0 must be a whole number in [1, 36]"},
      {"distance_radii = 9.5\n", "camera.distance_radii = 9.5 must be in [10, 1000] pile radii"},
      {"noise_sd = -3.0\n", "camera.noise_sd = -3 must be in [0, 128] grey levels"},
      {"width_px = 10\n", "camera.width_px = 10 must be a whole number in [64, 8192]"},
      {"k1 = 0.9\n", "camera.k1 = 0.9 must be in [-0.5, 0.5]"},
      {"pitch_deg = 5.0\n", "camera.pitch_deg"},
  };
  for (const auto& [table, want] : bad) {
    const std::string e = design_error("bad", table);
    EXPECT_NE(e.find(file + ": " + want), std::string::npos) << table << " -> " << e;
  }
}

TEST(LoopTilt, AHiddenTiltedCameraIsRefusedWithBothPitches) {
  SimCache cache(
      (fs::temp_directory_path() / ("reposetwin_loop_tilt_cache_" + fnv1a_hex(code_version())))
          .string(),
      {2, false});
  const SynthDesign tilted = read_synth_design(write_design(
      "tilted", "side_views = 2\nnoise_sd = 2.0\nheight_m = 0.025\naim_at_axis_foot = true\n"));
  const fs::path out = test_dir() / "tilted";
  fs::remove_all(out);
  const std::string csv = make_synthetic_dataset(tilted, out.string(), cache);
  // The lab's twin could not measure its photos through the declared camera either: nothing
  // typed, the photos given.
  const CsvTable table = parse_csv(read_file(csv), csv);
  ASSERT_EQ(table.rows.size(), 1u);
  for (std::size_t k = 0; k < table.header.size(); ++k) {
    const std::string& c = table.header[k];
    if (c == "H_mm" || c == "D_mm" || c == "angle_deg") {
      EXPECT_EQ(table.rows[0].fields[k], "") << c;
    }
  }
  std::string what;
  try {
    (void)read_lab_csv(csv);
    ADD_FAILURE() << "a photo pitched down and declared level was measured";
  } catch (const std::invalid_argument& e) {
    what = e.what();
  }
  std::printf("refused: %s\n", what.c_str());
  EXPECT_NE(what.find("measured.csv line 3 (test t1), column photo"), std::string::npos) << what;
  const std::string photo = (out / "photos" / "t1_pile1_side_az000.png").string();
  EXPECT_NE(what.find(photo), std::string::npos) << what;
  // Each photo is refused by the camera check, naming it, with the pitch the photo implies.
  EXPECT_NE(what.find(photo + ": refused by the camera_mismatch check"), std::string::npos)
      << what;
  EXPECT_NE(what.find("not measured through the declared camera"), std::string::npos) << what;
  EXPECT_NE(what.find("the photo implies a camera pitched"), std::string::npos) << what;

  // The same pile, photographed by a level camera, reads (the refusal is the camera's).
  SynthDesign level = tilted;
  level.camera.camera_height_m = 0.0;
  level.camera.aim_at_axis_foot = false;
  const std::string level_csv =
      make_synthetic_dataset(level, (test_dir() / "level").string(), cache);
  const LabData data = read_lab_csv(level_csv);
  ASSERT_EQ(data.tests.size(), 1u);
  EXPECT_GT(data.tests[0].angle_deg, 5.0);
  EXPECT_LT(data.tests[0].angle_deg, 60.0);
  EXPECT_EQ(data.tests[0].crest_source, "photo");
  std::printf("level camera: angle %.2f deg, crest %.2f +- %.2f mm\n", data.tests[0].angle_deg,
              data.tests[0].crest_mm.value_or(-1.0), data.tests[0].crest_sigma_mm.value_or(-1.0));
}

}  // namespace
}  // namespace reposetwin::experiments
