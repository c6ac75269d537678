// One pile store for calibration and loop (campaign/pile_service.hpp): a calibration of a lab
// test's conditions poured into a store, then the loop asking for the same test at the same
// mu_r and seed from that store, pours nothing; it only photographs the piles its own way (the
// loop's photo settings differ from a campaign's, so its photographs are new). Two tiny piles.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "experiments/calibration/calibrate_campaign.hpp"
#include "experiments/calibration/campaign_target.hpp"
#include "experiments/campaign/case_runner.hpp"
#include "experiments/campaign/pile_service.hpp"
#include "experiments/io/campaign_file.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/loop/loop.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;

TEST(PileStore, ACalibrationFollowedByALoopOnTheSameTestPoursNoPileAgain) {
  const fs::path root = fs::temp_directory_path() /
                        ("reposetwin_shared_store_test_" + sha256_hex(code_version()).substr(0, 12));
  fs::remove_all(root);
  fs::create_directories(root);
  const LabData data =
      read_lab_csv(std::string(REPOSETWIN_SOURCE_DIR) + "/data/loop/example.csv");
  const LabTest& test = data.tests.at(0);
  const std::string mu_key = "contacts.{sample}-{sample}.rolling_friction";

  // The calibration of the test's conditions: the same scene and overrides, the loop's first
  // seed, mu_r at the ends of its range (the sequential driver's first two runs; a target no
  // tiny pile reaches ends it there).
  std::string overrides;
  for (const auto& [k, v] : test.overrides)
    overrides += (overrides.empty() ? "" : ", ") + ("\"" + k + "\" = " + v);
  const fs::path file = root / "calibration.toml";
  std::ofstream(file) << "name = \"shared_store\"\nscene = \"" << test.scene_path
                      << "\"\nseeds = [1001]\noverrides = { " << overrides << " }\n"
                      << "[calibration]\nkey = \"contacts.rock-rock.rolling_friction\"\n"
                      << "target_deg = 80.0\nmu_r_range = [0.1, 0.3]\nseeds_per_point = 1\n"
                      << "max_simulations = 4\nfirst_seed = 1001\n";
  const Campaign c = load_campaign(file.string());
  const fs::path store = root / "store";
  CaseRunSettings cs;
  cs.image.width_px = 480;  // a campaign's own photo settings, small to keep the test fast
  cs.image.height_px = 360;
  cs.image.side_views = 1;
  cs.image.top_view = false;
  cs.store = store.string();
  RunnerSettings runner;
  runner.workers = 2;
  runner.progress = false;
  runner.rank = std::nullopt;
  runner.mode = WorkerMode::kThreads;  // this test binary may have rendered before: no fork
  const nlohmann::json cal = run_calibration(c, (root / "calibration").string(), pile_case_fn(cs),
                                             calibration_angle(AngleMeasure::kImage), runner);
  ASSERT_EQ(cal.at("simulations").get<int>(), 2) << cal.dump(2);

  // The loop on the same test, grid and seed, from the same store.
  SimCache cache(store.string(), {2, false});
  ImageVariant image;
  image.width_px = 480;
  image.height_px = 360;
  const std::vector<SimRequest> requests = {make_request(test, mu_key, 0.1, 1001, {}, image),
                                            make_request(test, mu_key, 0.3, 1001, {}, image)};
  const std::vector<SimOutcome> out = cache.run(requests);
  EXPECT_EQ(cache.simulations_started(), 0) << "the loop poured a pile the calibration poured";
  EXPECT_EQ(cache.photos_started(), 2) << "the loop's photographs are its own";
  ASSERT_EQ(out.size(), 2u);
  for (const SimOutcome& o : out) {
    EXPECT_TRUE(o.pile) << o.sim_dir;
    EXPECT_TRUE(fs::exists(fs::path(o.sim_dir) / "run" / "result.json")) << o.sim_dir;
  }
  // The same piles: the calibration's case records point at the loop's pile folders.
  for (double mu : {0.1, 0.3}) {
    const auto r = read_run_result((root / "calibration").string(), calibration_run(c, mu, 1001));
    ASSERT_TRUE(r.has_value()) << mu;
    const fs::path run = fs::weakly_canonical(
        root / "calibration" / calibration_run(c, mu, 1001).relative_dir() /
        r->at("result").at("run_dir").get<std::string>());
    const SimOutcome& o = out[mu == 0.1 ? 0 : 1];
    EXPECT_EQ(run, fs::weakly_canonical(fs::path(o.sim_dir) / "run")) << mu;
  }
  if (!HasFailure()) fs::remove_all(root);  // else kept: the store's request.json files say why
}

// The store key is the request's canonical JSON: a field of the request changes it, and the
// order of overrides that cannot interact does not.
TEST(PileStore, KeysFollowTheRequestRecord) {
  const std::string scene = std::string(REPOSETWIN_SOURCE_DIR) + "/data/loop/tiny_scene.toml";
  PileRequest a{scene, {{"sample.mass_kg", "0.005"}, {"procedure.lift_speed_m_s", "0.05"}}, 7,
                std::nullopt};
  PileRequest swapped = a;
  std::swap(swapped.overrides[0], swapped.overrides[1]);
  EXPECT_EQ(pile_key(a), pile_key(swapped));
  PileRequest seed = a;
  seed.seed = 8;
  EXPECT_NE(pile_key(a), pile_key(seed));
  PileRequest spelling = a;  // one value, spelt otherwise
  spelling.overrides[0].value = "0.0050000000000000001";
  EXPECT_EQ(pile_key(a), pile_key(spelling));
  PileRequest value = a;
  value.overrides[0].value = "0.006";
  EXPECT_NE(pile_key(a), pile_key(value));
  EXPECT_EQ(pile_key(a).size(), 64u);
  // Keys that interact (a table and a key inside it) keep their order.
  PileRequest nested{scene, {{"sample", "{ mass_kg = 0.005 }"}, {"sample.mass_kg", "0.006"}}, 7,
                     std::nullopt};
  PileRequest nested_swapped = nested;
  std::swap(nested_swapped.overrides[0], nested_swapped.overrides[1]);
  EXPECT_NE(pile_key(nested), pile_key(nested_swapped));
  // A photograph is keyed by its pile and every photo setting.
  a.photo = PhotoRequest{};
  PileRequest other_photo = a;
  other_photo.photo->settings.noise_sd = 1.0;
  EXPECT_EQ(pile_key(a), pile_key(other_photo));
  EXPECT_NE(photo_key(a), photo_key(other_photo));
  other_photo = a;
  other_photo.photo->settings.lab_cameras.emplace_back();
  EXPECT_NE(photo_key(a), photo_key(other_photo)) << "a photo through another camera";
  EXPECT_THROW(photo_key(seed), std::invalid_argument);
  // SHA-256 of "abc" (FIPS 180-2, appendix B.1).
  EXPECT_EQ(sha256_hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
}

}  // namespace
}  // namespace reposetwin::experiments
