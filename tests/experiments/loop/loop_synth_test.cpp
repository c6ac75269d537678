// The loop end to end on synthetic lab datasets with an undeclared effect: it must name the
// hidden effect, cut the calibration RMSE by at least 70%, and name nothing on a dataset
// without an effect. All tests share one simulation cache (keyed by the engine's and imaging's
// source hashes, as the loop's cache is), so the baseline grid and the fingerprints are
// simulated once for all datasets, whichever test runs first; a test run alone still computes
// everything it needs.
//
// The suite keeps the cases that share one design and one fingerprint node (the smooth plate,
// traced from all tests and from one calibration test) and the two that must name nothing (no
// effect; a uniform offset). The hidden fast lift, cohesion and size-dependent rolling cases
// each need their own refits and fingerprints and would take the suite past ten minutes on two
// cores; they run as the loop's validation experiment with the same settings
// (experiments/loop_validation/run.sh, results/loop_validation/summary.csv).
//
// Design (docs/loop.md "Synthetic end-to-end tests"):
//  * Scene: data/loop/small_scene.toml, 15 or 35 g of 3-4 mm spheres (piles 3-5 layers high).
//    One photographed pile scatters by about 1.2 deg (seed_sd_deg in
//    results/loop_validation/plate/loop.json), so with 3 lab piles per test and 3 twin seeds the
//    residual floor after a perfect refit is 1.2 sqrt(1/3 + 1/3) = 1.0 deg.
//  * Conditions: mass (15, 35 g) x plate (steel, declared friction 0.5; wood, 0.25) x declared
//    lift speed (0.03, 0.1 m/s), eight tests, one held out (data/loop/synth_plate.toml is the
//    same design as a loop-synth file). A smooth plate changes steel more than wood, which a
//    faster lift or cohesion (the candidates it must beat) do not.
//  * The lab is the twin with hidden mu_r 0.25 (between grid points), other seeds, a different
//    camera (14 instead of 12 pile radii away, three views instead of two, image noise); the
//    twin keeps its own framing here (use_lab_cameras = false), since like for like through the
//    lab's cameras is LoopCamera's test.

#include "experiments/io/hash.hpp"
#include "experiments/loop/loop_synth.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "experiments/loop/loop.hpp"
#include "experiments/io/provenance.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;

const std::string kScene = std::string(REPOSETWIN_SOURCE_DIR) + "/data/loop/small_scene.toml";
const std::string kSizeScene = std::string(REPOSETWIN_SOURCE_DIR) + "/data/loop/size_scene.toml";

fs::path test_root() {
  return fs::temp_directory_path() /
         ("reposetwin_loop_test_" + fnv1a_hex(engine_version() + imaging_version()));
}

// The lab's hidden camera and pile seeds, shared by both designs.
SynthDesign lab(const std::string& scene, double mu_r,
                const std::vector<std::pair<std::string, double>>& hidden) {
  SynthDesign d;
  d.scene = scene;
  d.mu_r = mu_r;
  d.seeds = {7001, 7002, 7003};
  d.hidden = hidden;
  d.camera.width_px = 960;
  d.camera.height_px = 720;
  d.camera.side_views = 3;
  d.camera.distance_radii = 14.0;
  d.camera.noise_sd = 4.0;
  return d;
}

SynthDesign design(const std::vector<std::pair<std::string, double>>& hidden) {
  SynthDesign d = lab(kScene, 0.25, hidden);
  for (const char* plate : {"steel", "wood"})
    for (double lift : {0.03, 0.1})
      for (double mass : {0.015, 0.035}) {
        SynthTest t;
        t.id = "m" + std::to_string(static_cast<int>(mass * 1e3 + 0.5)) + "_" + plate + "_l" +
               std::to_string(static_cast<int>(lift * 1e2 + 0.5));
        t.role = (mass == 0.035 && lift == 0.03 && std::string(plate) == "wood") ? "validate"
                                                                                 : "calibrate";
        t.conditions = {{"mass_kg", mass}, {"lift_speed_m_s", lift}};
        t.labels = {{"plate", plate}};
        d.tests.push_back(t);
      }
  return d;
}

LoopSettings settings(std::vector<double> mu_grid = {0.1, 0.2, 0.35}) {
  LoopSettings s;
  s.mu_grid = mu_grid;
  s.seeds = {1001, 1002, 1003};
  s.image.width_px = 960;
  s.image.height_px = 720;
  s.image.side_views = 2;
  // The synthetic labs photograph with their own hidden camera (distance, noise) and write its
  // declared sidecars; these tests trace with the loop's own framing, a camera other than the
  // lab's, as they were designed (like for like through the sidecars is LoopCamera's).
  s.image.use_lab_cameras = false;
  s.max_effects = 1;
  // Every candidate but lens_k1, whose fingerprint on these piles (0.06 deg RMS at its largest
  // probe, against 0.7 deg of seed noise) never stands out and whose three probes cost 72
  // photographs per fingerprint node; the validation experiment keeps the whole registry.
  s.candidates = {"plate_friction", "lift_speed", "cohesion", "camera_height", "rolling_size",
                  "fines"};
  // These designs put mu_r on the grid's bound whenever an effect is hidden (a smooth plate or a
  // fast lift at its low end, cohesion at its top): they test the tracing of what mu_r cannot
  // take up, with the correction held inside the grid. Extending it would simulate mu_r = 0 (or
  // 0.5), where the 15 g piles spread too thin to photograph.
  s.at_bound = GridBound::kTrace;
  s.grid_extensions = 0;
  s.workers = 2;
  s.progress = false;
  s.force = true;
  s.html = false;
  s.cache_dir = (test_root() / "cache").string();
  return s;
}

// Makes the dataset with the hidden settings, reads it as a lab would, and runs the loop.
nlohmann::json run_case(const std::string& name, const SynthDesign& lab_design,
                        const LoopSettings& loop_settings = settings()) {
  SimCache cache((test_root() / "cache").string(), {2, false});
  const std::string csv =
      make_synthetic_dataset(lab_design, (test_root() / name / "data").string(), cache);
  const LabData data = read_lab_csv(csv);
  const nlohmann::json loop = run_loop(data, (test_root() / name / "loop").string(), loop_settings);
  std::cerr << name << ": " << loop["summary"].dump() << "\n";
  if (!loop["final"]["effects"].empty())
    std::cerr << name << ": fitted " << loop["final"]["effects"][0]["value"] << " +- "
              << loop["final"]["effects"][0]["value_se"] << ", mu_r " << loop["final"]["mu_r"]
              << "\n";
  return loop;
}

// The loop names `effect`, fits it on the side of its off value where the hidden value lies,
// and cuts the calibration RMSE by at least `min_cut` (70% unless the test says why not).
void expect_found(const nlohmann::json& loop, const std::string& effect, bool above_off,
                  double min_cut = 0.70) {
  const nlohmann::json& s = loop.at("summary");
  ASSERT_FALSE(s["chosen"].is_null()) << loop["iterations"].dump(1);
  EXPECT_EQ(s["chosen"], effect) << loop["iterations"].dump(1);
  const nlohmann::json& e = loop["final"]["effects"].at(0);
  if (above_off)
    EXPECT_GT(e["value"].get<double>(), e["off"].get<double>()) << e.dump();
  else
    EXPECT_LT(e["value"].get<double>(), e["off"].get<double>()) << e.dump();
  EXPECT_GE(s["reduction"].get<double>(), min_cut) << s.dump();
}

// A smooth steel plate (friction 0.16 where 0.5 is declared; wood's 0.25 becomes 0.16 too).
TEST(LoopSynth, HiddenSmoothPlateIsFound) {
  expect_found(run_case("plate", design({{"plate_friction", 0.16}})), "plate_friction", false);
  // With no effect allowed (--max-effects 0) the loop traces and ranks only: it names the
  // candidate that meets the rule, refits nothing and reports the baseline as final (from the
  // cache: no new simulation).
  LoopSettings trace_only = settings();
  trace_only.max_effects = 0;
  const nlohmann::json loop = run_case("plate_trace_only", design({{"plate_friction", 0.16}}),
                                       trace_only);
  ASSERT_EQ(loop["iterations"].size(), 1u);
  EXPECT_TRUE(loop["summary"]["chosen"].is_null());
  EXPECT_NE(loop["iterations"][0].value("stopped", "").find("plate_friction meets"),
            std::string::npos)
      << loop["iterations"].dump(1);
  EXPECT_EQ(loop["summary"]["rmse_calibrate_after_deg"],
            loop["summary"]["rmse_calibrate_before_deg"]);
  EXPECT_EQ(loop["simulations"]["pile_runs_started"], 0);
  // Declaring the effect the trace names anyway (--refit plate_friction) changes nothing but the
  // record: the same refit from the cache, named by the trace, the declaration noted.
  LoopSettings declared = settings();
  declared.refit = "plate_friction";
  const nlohmann::json again =
      run_case("plate_declared", design({{"plate_friction", 0.16}}), declared);
  EXPECT_EQ(again["summary"]["chosen"], "plate_friction");
  EXPECT_EQ(again["summary"]["verdict"], "named");
  EXPECT_NE(again["iterations"][0].value("declared", "").find("names it too"), std::string::npos)
      << again["iterations"][0].dump(1);
  EXPECT_FALSE(again["final"]["effects"][0]["declared"].get<bool>());
  EXPECT_EQ(again["simulations"]["pile_runs_started"], 0);
}

// The size-dependent rolling resistance is defined around the calibration tests' typical grain:
// d_ref is the geometric mean of their mass-median diameters (the size scene's sieve table is
// linear from 2 to 5 mm, so a band's d50 is its middle), and the candidate sets it with the
// exponent. Held-out tests do not move it; a test outside a dataset uses its own d50.
TEST(LoopSynth, RollingSizeReferenceIsTheCalibrationTestsTypicalGrain) {
  auto band = [](const std::string& id, Role role, double lo_mm, double hi_mm) {
    LabTest t;
    t.id = id;
    t.role = role;
    t.scene_path = kSizeScene;
    t.overrides = {{"sample.d_min_mm", std::to_string(lo_mm)},
                   {"sample.d_max_mm", std::to_string(hi_mm)}};
    return t;
  };
  std::vector<LabTest> tests = {band("fine", Role::kCalibrate, 2.0, 2.5),
                                band("coarse", Role::kCalibrate, 4.5, 5.0),
                                band("all", Role::kValidate, 2.0, 5.0)};
  EXPECT_NEAR(median_grain_diameter(tests[0]), 2.25e-3, 1e-12);
  EXPECT_NEAR(median_grain_diameter(tests[1]), 4.75e-3, 1e-12);
  EXPECT_NEAR(median_grain_diameter(tests[2]), 3.5e-3, 1e-12);
  const double d_ref = reference_grain_diameter(tests);
  EXPECT_NEAR(d_ref, std::sqrt(2.25e-3 * 4.75e-3), 1e-12);
  const CandidateEffect& e = find_effect("rolling_size");
  auto value_of = [](const SimRequest& r, const std::string& key) {
    for (const auto& [k, v] : r.extra)
      if (k == key) return std::stod(v);
    ADD_FAILURE() << "no override " << key;
    return 0.0;
  };
  const std::string ref_key = "contacts.rock-rock.rolling_reference_diameter_m";
  // Outside a dataset: the test's own d50.
  SimRequest r = make_request(tests[1], "contacts.{sample}-{sample}.rolling_friction", 0.3, 1,
                              {{&e, 2.0}}, ImageVariant{});
  EXPECT_NEAR(value_of(r, ref_key), 4.75e-3, 1e-12);
  EXPECT_EQ(value_of(r, "contacts.rock-rock.rolling_size_exponent"), 2.0);
  for (LabTest& t : tests) t.reference_diameter_m = d_ref;
  r = make_request(tests[1], "contacts.{sample}-{sample}.rolling_friction", 0.3, 1, {{&e, 2.0}},
                   ImageVariant{});
  EXPECT_NEAR(value_of(r, ref_key), d_ref, 1e-10 * d_ref);  // 12 digits in the override
}

// The lab's design: one calibration test (m35_steel_l10), seven predicted. mu_r is matched on
// that one test; the smooth plate is traced from the prediction residuals, refitted with mu_r
// on every test (the design statement says the held-out RMSE after is then in-sample).
TEST(LoopSynth, OneCalibrationTestTracesAPlantedPlateEffect) {
  SynthDesign d = design({{"plate_friction", 0.16}});
  for (SynthTest& t : d.tests) t.role = t.id == "m35_steel_l10" ? "calibrate" : "validate";
  const nlohmann::json loop = run_case("plate_one_calibration", d);
  EXPECT_EQ(loop["design"]["n_calibrate"], 1);
  EXPECT_TRUE(loop["design"]["refit_on_all_tests"].get<bool>());
  ASSERT_TRUE(loop["design"]["can_trace"].get<bool>());
  ASSERT_FALSE(loop["iterations"].empty());
  EXPECT_EQ(loop["iterations"][0]["candidates"].size(), loop["iterations"][0]["joint"].size());
  EXPECT_EQ(loop["summary"]["chosen"], "plate_friction") << loop["iterations"].dump(1);
  const nlohmann::json& e = loop["final"]["effects"].at(0);
  EXPECT_LT(e["value"].get<double>(), e["off"].get<double>()) << e.dump();
  const double before = loop["summary"]["rmse_all_before_deg"].get<double>();
  const double after = loop["summary"]["rmse_all_after_deg"].get<double>();
  EXPECT_LT(after, 0.5 * before) << loop["summary"].dump();
}

// A measurement wrong everywhere: the null dataset with 6 deg taken from every lab angle (H and
// D as measured). mu_r goes to the grid's bottom and cannot take the rest up; the residual is
// flagged as a suspected measurement error and no physical effect is named, although a smooth
// plate, whose fingerprint is simulated at that end of the grid (and shared with the plate
// tests), lowers every angle too.
TEST(LoopSynth, AUniformMeasurementOffsetIsFlaggedNotNamed) {
  SimCache cache((test_root() / "cache").string(), {2, false});
  const std::string csv =
      make_synthetic_dataset(design({}), (test_root() / "offset" / "data").string(), cache);
  LabData data = read_lab_csv(csv);
  for (LabTest& t : data.tests) {
    ASSERT_TRUE(t.height_mm && t.diameter_mm) << t.id;
    t.angle_deg -= 6.0;
    t.photos.clear();  // the angle as typed: the photos would give it back as measured
    // The lab typed angle, H and D only: no crest (the photos' would be a fourth channel).
    t.crest_mm.reset();
    t.crest_sigma_mm.reset();
    t.crest_source.clear();
  }
  const nlohmann::json loop = run_loop(data, (test_root() / "offset" / "loop").string(), settings());
  std::cerr << "offset: " << loop["summary"].dump() << "\n";
  EXPECT_TRUE(loop["summary"]["chosen"].is_null()) << loop["iterations"].dump(1);
  EXPECT_EQ(loop["summary"]["verdict"], "measurement_suspected") << loop["iterations"].dump(1);
  EXPECT_TRUE(loop["grid"]["mu_r_at_bound"].get<bool>());
  const nlohmann::json& it = loop["iterations"].at(0);
  EXPECT_EQ(it["channels"].size(), 3u);
  EXPECT_NEAR(it["offset"]["coef"].get<double>(), -5.0, 2.5) << it["offset"].dump();
  // A candidate lost in the seed noise was probed at larger values before it was given up: the
  // largest probe is named, or the larger probe that could not be photographed (at the grid's
  // bottom, camera_height's doubled probe, 20 mm, gave photos of the flattest piles in which
  // vision found no pile).
  int lost = 0;
  for (const nlohmann::json& u : loop["unavailable_candidates"]) {
    const std::string why = u["why"].get<std::string>();
    if (why.find("seed noise") == std::string::npos) continue;
    ++lost;
    EXPECT_TRUE(why.find("largest probe tried") != std::string::npos ||
                why.find("failed at probe") != std::string::npos)
        << u.dump();
  }
  EXPECT_GE(lost, 1) << loop["unavailable_candidates"].dump(1);

  // A declared hypothesis (--refit) is refitted whatever the trace decides (LoopJoint's
  // pick_refit test), end to end on the tiny scene in LoopHeldOut: the two trials a declared
  // plate would cost here (144 pile runs and 152 photographs) are a sixth of the suite.
}

// No hidden effect: the loop must add nothing.
TEST(LoopSynth, NullDatasetNamesNothing) {
  const nlohmann::json loop = run_case("null", design({}));
  EXPECT_TRUE(loop["summary"]["chosen"].is_null()) << loop["iterations"].dump(1);
  EXPECT_TRUE(loop["final"]["effects"].empty());
}

}  // namespace
}  // namespace reposetwin::experiments

namespace reposetwin::experiments {
namespace {

// loop-synth's cache holds the hidden settings in its records, so it never lies inside the
// dataset's folder (where the loop reads): by default it is the folder beside it, and a --cache
// or --truth given inside it is refused naming the option (issue 52).
TEST(SynthCacheDir, TheCacheLiesBesideTheDatasetNeverInsideIt) {
  EXPECT_EQ(synth_cache_dir("runs/data", ""), "runs/data.synth-cache");
  EXPECT_EQ(synth_cache_dir("runs/data/", ""), "runs/data.synth-cache");
  EXPECT_EQ(synth_cache_dir("runs/data", "elsewhere/cache"), "elsewhere/cache");
  for (const std::string inside : {"runs/data/cache", "runs/data/.hidden_cache", "runs/data",
                                   "runs/./data/x/../cache"}) {
    try {
      synth_cache_dir("runs/data", inside);
      ADD_FAILURE() << inside << " accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("--cache " + inside), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(synth_cache_dir("runs/data", "", "runs/data/truth.json"), InputError);
  EXPECT_EQ(synth_cache_dir("runs/data", "", "runs/truth.json"), "runs/data.synth-cache");
}

}  // namespace
}  // namespace reposetwin::experiments
