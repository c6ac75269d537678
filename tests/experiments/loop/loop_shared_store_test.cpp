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
#include "experiments/io/input_error.hpp"
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
  const CalibrationRecord cal =
      run_calibration(c, (root / "calibration").string(), pile_case_fn(cs),
                      calibration_angle(AngleMeasure::kImage), runner);
  ASSERT_EQ(cal.simulations, 2) << to_json(cal).dump(2);

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
  // The same piles: the calibration's case folders hold run/result.json where campaigns have
  // always put it, and it is the loop's pile's result.json (a link into the store).
  for (double mu : {0.1, 0.3}) {
    const auto r = read_run_result((root / "calibration").string(), calibration_run(c, mu, 1001));
    ASSERT_TRUE(r.has_value()) << mu;
    EXPECT_EQ(r->at("result").at("run_dir"), "run");
    const fs::path run = root / "calibration" / calibration_run(c, mu, 1001).relative_dir() /
                         r->at("result").at("run_dir").get<std::string>();
    ASSERT_TRUE(fs::is_regular_file(run / "result.json")) << run;
    const SimOutcome& o = out[mu == 0.1 ? 0 : 1];
    EXPECT_EQ(fs::canonical(run / "result.json"),
              fs::canonical(fs::path(o.sim_dir) / "run" / "result.json"))
        << mu;
  }
  if (!HasFailure()) fs::remove_all(root);  // else kept: the store's request.json files say why
}

// The store key follows the scene the request pours: a field of the request that changes it
// changes the key, and the order or spelling of overrides that end in the same scene does not.
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
  // Keys that interact (a table and a key inside it) keep their order: the table then its key
  // gives sieves 3-3.6 mm, the key then the table 3-4 mm.
  PileRequest nested{scene,
                     {{"sample.psd", "{ sieve_mm = [3.0, 4.0], passing_percent = [0.0, 100.0] }"},
                      {"sample.psd.sieve_mm", "[3.0, 3.6]"}},
                     7,
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

// The key is the resolved scene's, not its file's: the same scene at two paths (the loop's
// copy of a lab's scene beside its CSV) or written otherwise (a comment, another order) is one
// pile, and an edited scene file or sieve-table file is a new one.
TEST(PileStore, KeysFollowTheResolvedSceneNotItsFile) {
  const fs::path root = fs::temp_directory_path() / "reposetwin_pile_key_scene_test";
  fs::remove_all(root);
  fs::create_directories(root / "a");
  fs::create_directories(root / "b");
  const std::string scene = std::string(REPOSETWIN_SOURCE_DIR) + "/data/loop/tiny_scene.toml";
  const std::string text = read_file(scene);
  const auto key_of = [](const fs::path& file, std::vector<Override> ov = {}) {
    return pile_key(PileRequest{file.string(), std::move(ov), 7, std::nullopt});
  };
  const std::string base = key_of(scene);
  write_file_atomic((root / "a" / "scene.toml").string(), text);
  EXPECT_EQ(key_of(root / "a" / "scene.toml"), base) << "a copy at another path";
  write_file_atomic((root / "b" / "scene.toml").string(), "# a comment\n" + text + "\n\n");
  EXPECT_EQ(key_of(root / "b" / "scene.toml"), base) << "the same scene written otherwise";
  // An edited file is another pile, and the pile the same edit made as an override.
  const std::string from = "[contacts.rock-rock]\nrestitution = 0.5\nfriction = 0.5\n"
                           "rolling_friction = 0.2\n";
  ASSERT_NE(text.find(from), std::string::npos);
  std::string edited = text;
  edited.replace(edited.find(from), from.size(),
                 "[contacts.rock-rock]\nrestitution = 0.5\nfriction = 0.5\n"
                 "rolling_friction = 0.25\n");
  write_file_atomic((root / "a" / "scene.toml").string(), edited);
  EXPECT_NE(key_of(root / "a" / "scene.toml"), base) << "an edited scene kept its stale key";
  EXPECT_EQ(key_of(root / "a" / "scene.toml"),
            key_of(scene, {{"contacts.rock-rock.rolling_friction", "0.25"}}));
  // A sieve-table file the scene names is part of the scene: editing it changes the key.
  const std::string table = "[sample.psd]\nsieve_mm = [3.0, 3.5, 4.0]\n"
                            "passing_percent = [0.0, 50.0, 100.0]\n";
  ASSERT_NE(text.find(table), std::string::npos);
  std::string with_file = text;
  with_file.replace(with_file.find(table), table.size(), "");
  with_file.replace(with_file.find("[sample]\n"), 9, "[sample]\npsd_file = \"sieve.toml\"\n");
  write_file_atomic((root / "b" / "scene.toml").string(), with_file);
  write_file_atomic((root / "b" / "sieve.toml").string(),
                    "[psd]\nsieve_mm = [3.0, 3.5, 4.0]\npassing_percent = [0.0, 50.0, 100.0]\n");
  const std::string from_file = key_of(root / "b" / "scene.toml");
  write_file_atomic((root / "b" / "sieve.toml").string(),
                    "[psd]\nsieve_mm = [3.0, 3.5, 4.0]\npassing_percent = [0.0, 60.0, 100.0]\n");
  EXPECT_NE(key_of(root / "b" / "scene.toml"), from_file) << "an edited sieve file";
  // A scene the overrides break has no key: the error names the file and the key.
  try {
    (void)key_of(scene, {{"sample.mass_kg", "-1"}});
    ADD_FAILURE() << "a negative mass was keyed";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("mass_kg"), std::string::npos) << e.what();
  }
  if (!HasFailure()) fs::remove_all(root);
}

}  // namespace
}  // namespace reposetwin::experiments
