// Calibrate on one test, predict the others: the [[predict]] file format, the driver through the
// resumable pool, --predict-only reuse, and the paper comparison the report builds from it.
//
// The "simulations" are synthetic case functions with a closed-form angle (as in
// campaign_test.cpp), so every expected number below is computed independently of the driver:
// angle = 20 + 50 mu_r + offset [deg], where the offset is read from the run's scene
// (sample.mass_kg, so another scene is another test) and +-0.1 deg alternates with the seed.
#include <gtest/gtest.h>

#include <limits>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <thread>

#include "../../support/quiet_runner.hpp"
#include "../../vision/synthetic.hpp"
#include "experiments/calibration/calibrate_campaign.hpp"
#include "experiments/calibration/campaign_target.hpp"
#include "experiments/campaign/campaign.hpp"
#include "experiments/campaign/case_runner.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/report/report.hpp"
#include "experiments/io/input_error.hpp"
#include "sim/contact.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;

// Two tests: the same scene format, the angle offset carried by sample.mass_kg.
constexpr const char* kSceneA = R"(
[sample]
mass_kg = 0.0
[contacts.rock-rock]
rolling_friction = 0.15
rolling_model = "epsd"
[contacts.rock-plate]
rolling_friction = 0.15
)";
constexpr const char* kSceneB = R"(
[sample]
mass_kg = 2.0
[contacts.rock-rock]
rolling_friction = 0.15
rolling_model = "epsd"
[contacts.rock-plate]
rolling_friction = 0.15
)";

double closed_form(double mu, double offset, std::uint64_t seed) {
  return 20.0 + 50.0 * mu + offset + (seed % 2 ? 0.1 : -0.1);
}

struct Scratch {
  explicit Scratch(const std::string& name)
      : path(fs::temp_directory_path() /
             ("reposetwin_predict_test_" + std::to_string(::getpid()) + "_" + name)) {
    fs::remove_all(path);
    fs::create_directories(path);
    write_file_atomic((path / "a.toml").string(), kSceneA);
    write_file_atomic((path / "b.toml").string(), kSceneB);
  }
  ~Scratch() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  fs::path path;
};

// The synthetic runs' vision flank angle lies this far above their image atan(2H/D) [deg].
constexpr double kFlankAboveImage = 4.0;

// A case result shaped like pile_case_fn's (so the real case_angle_deg and the report read it),
// with a render overlay when `overlay` is set. Each start is logged (one line per run id).
CaseFn synthetic_case(const fs::path& log, bool overlay = false) {
  return [log, overlay](const CaseSpec& s, const std::string& dir) {
    std::ofstream(log, std::ios::app) << s.id() << "\n";
    const SceneDoc scene = build_case_scene(s);
    const double mu = scene.number("contacts.rock-rock.rolling_friction").value();
    const double plate = scene.number("contacts.rock-plate.rolling_friction").value();
    EXPECT_DOUBLE_EQ(plate, mu);  // both calibration keys take the value
    const double a = closed_form(mu, scene.number("sample.mass_kg").value(), s.seed);
    if (overlay) {
      fs::create_directories(fs::path(dir) / "run" / "images");
      cv::imwrite((fs::path(dir) / "run" / "images" / "side_az000.measured.png").string(),
                  cv::Mat(8, 8, CV_8UC3, cv::Scalar(0, 0, 255)));
    }
    return json{{"stop", {{"reason", "settled"}}},
                {"pile", {{"status", "ok"}, {"theta_hd_deg", a}, {"slice_angle_mean_deg", a}}},
                {"provenance", {{"time_step_s", 1e-6}, {"code_version", "test"}}},
                {"image", {{"theta_deg", a}, {"flank_deg", a + kFlankAboveImage}}},
                {"run_dir", "run"}};
  };
}

std::map<std::string, int> read_log(const fs::path& log) {
  std::map<std::string, int> n;
  std::ifstream in(log);
  for (std::string line; std::getline(in, line);) ++n[line];
  return n;
}

RunnerSettings quiet() { return test_support::quiet_runner(); }

const AngleFn kAngle = [](const json& r) { return case_angle_deg(r, AngleMeasure::kImage); };

// Calibrates on test A (sample 3, measured 35 deg: mu_r 0.3 exactly) and predicts test B
// (sample 4, offset +2 deg) with interval runs, B again without them, and A itself (a check).
std::string calibration_campaign(int sample = 3, double target = 35.0) {
  std::ostringstream os;
  os << "name = \"calib_s" << sample << "\"\nscene = \"a.toml\"\nseeds = [1, 2]\n"
     << "[calibration]\nkey = [\"contacts.rock-rock.rolling_friction\", "
        "\"contacts.rock-plate.rolling_friction\"]\n"
     << "target_deg = " << target << "\ntarget_sd_deg = 0.3\nmu_r_range = [0.02, 0.8]\n"
     << "seeds_per_point = 2\ntolerance_deg = 0.3\nmax_simulations = 24\n"
     << "bootstrap_replicates = 400\ntable1_sample = " << sample << "\n"
     << "[[predict]]\nname = \"sample4\"\nscene = \"b.toml\"\nmeasured_deg = 37.17\n"
        "seeds = [1, 2, 3]\ntable1_sample = 4\n"
     << "[[predict]]\nname = \"sample4_no_ends\"\nscene = \"b.toml\"\nmeasured_deg = 37.17\n"
        "interval_ends = false\ntable1_sample = 4\n"
     << "[[predict]]\nname = \"self\"\nscene = \"a.toml\"\nmeasured_deg = " << target << "\n";
  return os.str();
}

TEST(Predict, ParsesPredictEntries) {
  const Scratch d("parse");
  write_file_atomic((d.path / "c.toml").string(), calibration_campaign());
  const Campaign c = load_campaign((d.path / "c.toml").string());
  ASSERT_TRUE(c.calibration.has_value());
  EXPECT_EQ(c.calibration->key, "contacts.rock-rock.rolling_friction");
  ASSERT_EQ(c.calibration->keys.size(), 2u);
  EXPECT_EQ(c.calibration->keys[1], "contacts.rock-plate.rolling_friction");
  EXPECT_EQ(c.calibration->table1_sample, 3);
  EXPECT_DOUBLE_EQ(c.calibration->settings.mu_r_hi, 0.8);
  ASSERT_EQ(c.predictions.size(), 3u);
  const PredictionCase& p = c.predictions[0];
  EXPECT_EQ(p.name, "sample4");
  EXPECT_EQ(p.scene_path, fs::absolute(d.path / "b.toml").lexically_normal().string());
  EXPECT_DOUBLE_EQ(p.measured.angle_deg, 37.17);
  EXPECT_EQ(p.seeds, (std::vector<std::uint64_t>{1, 2, 3}));
  EXPECT_TRUE(p.interval_ends);
  EXPECT_EQ(p.table1_sample, 4);
  EXPECT_FALSE(c.predictions[1].interval_ends);
  EXPECT_EQ(c.predictions[1].seeds, c.seeds);  // default: the campaign's seeds
  // A prediction run sets every calibration key on the other test's scene.
  const CaseSpec s = prediction_run(c, p, 0.25, 3);
  EXPECT_EQ(s.case_name, "predict_sample4_rolling_friction_0.25");
  const SceneDoc scene = build_case_scene(s);
  EXPECT_DOUBLE_EQ(scene.number("contacts.rock-plate.rolling_friction").value(), 0.25);
  EXPECT_DOUBLE_EQ(scene.number("sample.mass_kg").value(), 2.0);
}

TEST(Predict, BadEntriesNameFileKeyAndValue) {
  const Scratch d("bad");
  const std::string head =
      "name = \"x\"\nscene = \"a.toml\"\nseeds = [1]\n[calibration]\ntarget_deg = 30\n"
      "mu_r_range = [0.02, 0.8]\n";
  const std::string ok = "[[predict]]\nname = \"p\"\nscene = \"b.toml\"\nmeasured_deg = 37\n";
  struct Bad {
    std::string text, key, value;
  };
  const std::vector<Bad> cases = {
      {head + "[[predict]]\nname = \"p\"\nscene = \"nope.toml\"\nmeasured_deg = 37\n",
       "predict[0].scene", "nope.toml"},
      {head + "[[predict]]\nname = \"p\"\nmeasured_deg = 37\n", "predict[0].scene", "missing"},
      {head + "[[predict]]\nname = \"p\"\nscene = \"b.toml\"\nmeasured_deg = 95\n",
       "predict[0].measured_deg", "95"},
      {head + "[[predict]]\nname = \"p\"\nscene = \"b.toml\"\nmeasured_deg = 0\n",
       "predict[0].measured_deg", "0"},
      {head + "[[predict]]\nname = \"p\"\nscene = \"b.toml\"\n", "predict[0].measured_deg",
       "missing"},
      {head + "[[predict]]\nname = \"p\"\nscene = \"b.toml\"\nmeasured_deg = 37\n"
              "measured_sd_deg = -1\n",
       "predict[0].measured_sd_deg", "-1"},
      {head + ok + "colour = 1\n", "predict[0].colour", "unknown key"},
      {head + ok + ok, "predict[1].name", "not unique"},
      {head + "[[predict]]\nname = \"a b\"\nscene = \"b.toml\"\nmeasured_deg = 37\n",
       "predict[0].name", "a b"},
      {head + ok + "seeds = [1, 1]\n", "predict[0].seeds", "repeated"},
      {head + ok + "interval_ends = \"yes\"\n", "predict[0].interval_ends", "yes"},
      {head + ok + "table1_sample = 7\n", "predict[0].table1_sample", "7"},
      {head + ok + "overrides = { \"sample.colour.x\" = 1 }\n", "prediction p", "sample.colour"},
      {"name = \"x\"\nscene = \"a.toml\"\nseeds = [1]\n[[case]]\nname = \"c\"\n" + ok, "predict",
       "needs a [calibration]"},
      {head + "key = [\"contacts.rock-rock.rolling_friction\", 3]\n", "calibration.key", "3"},
  };
  for (const auto& b : cases) {
    write_file_atomic((d.path / "c.toml").string(), b.text);
    std::string e;
    try {
      load_campaign((d.path / "c.toml").string());
    } catch (const std::exception& x) {
      e = x.what();
    }
    EXPECT_NE(e.find("c.toml"), std::string::npos) << b.text << "\n-> " << e;
    EXPECT_NE(e.find(b.key), std::string::npos) << b.text << "\n-> " << e;
    EXPECT_NE(e.find(b.value), std::string::npos) << b.text << "\n-> " << e;
  }
}

TEST(Predict, CalibratesOnOneTestAndPredictsTheOthers) {
  const Scratch d("run");
  write_file_atomic((d.path / "c.toml").string(), calibration_campaign());
  const Campaign c = load_campaign((d.path / "c.toml").string());
  const fs::path out = d.path / "out", log = d.path / "log";
  const CalibrationRecord cal =
      run_calibration(c, out.string(), synthetic_case(log), kAngle, quiet());
  ASSERT_TRUE(cal.mu_r) << to_json(cal).dump(2);
  const double mu = *cal.mu_r;
  EXPECT_NEAR(mu, 0.3, 1e-9);  // the seed effects cancel in every point's mean
  EXPECT_EQ(cal.rolling_model.keyword, "epsd");
  EXPECT_EQ(cal.rolling_model.radius, std::string(sim::find_rolling_model("epsd")->radius));
  EXPECT_EQ(cal.table1_sample, 3);
  const double lo = cal.mu_r_lo;
  const double hi = cal.mu_r_hi;
  EXPECT_LT(lo, mu);  // target sd 0.3 deg: a real interval
  EXPECT_GT(hi, mu);
  // The file the sequential driver wrote is the record it returned, read by the one reader.
  EXPECT_TRUE(read_calibration_record((out / "calibration.json").string()) == cal);

  const json pj = run_predictions(c, cal, out.string(), synthetic_case(log), kAngle, quiet());
  ASSERT_TRUE(fs::exists(out / "predictions.json"));
  ASSERT_EQ(pj["predictions"].size(), 3u);
  const json& b = pj["predictions"][0];
  // Test B at the calibrated mu_r: 20 + 50 mu_r + 2, seeds 1, 2, 3 give +0.1, -0.1, +0.1.
  const double mean_b = 20.0 + 50.0 * mu + 2.0 + 0.1 / 3.0;
  EXPECT_NEAR(b["mean_deg"].get<double>(), mean_b, 1e-9);
  EXPECT_NEAR(b["seed_sd_deg"].get<double>(), std::sqrt(0.04 / 3.0), 1e-9);
  EXPECT_EQ(b["n"], 3);
  EXPECT_NEAR(b["error_deg"].get<double>(), mean_b - 37.17, 1e-9);
  EXPECT_NEAR(b["abs_error_deg"].get<double>(), std::abs(mean_b - 37.17), 1e-9);
  EXPECT_FALSE(b["check"].get<bool>());
  // Interval ends run: the angle there, in closed form.
  EXPECT_EQ(b["interval_effect"]["method"], "runs");
  EXPECT_NEAR(b["interval_effect"]["angle_range_deg"][0].get<double>(),
              20.0 + 50.0 * lo + 2.0 + 0.1 / 3.0, 1e-9);
  EXPECT_NEAR(b["interval_effect"]["angle_range_deg"][1].get<double>(),
              20.0 + 50.0 * hi + 2.0 + 0.1 / 3.0, 1e-9);
  // Without the end runs: shifted by the calibration fit's change over the interval (the fit is
  // the line 20 + 50 mu_r between its points, so the shift is 50 (hi - mu_r) exactly).
  const json& b2 = pj["predictions"][1];
  EXPECT_EQ(b2["interval_effect"]["method"], "calibration_slope");
  EXPECT_EQ(b2["n"], 2);  // the campaign's seeds [1, 2]
  const double mean_b2 = 20.0 + 50.0 * mu + 2.0;
  EXPECT_NEAR(b2["mean_deg"].get<double>(), mean_b2, 1e-9);
  EXPECT_NEAR(b2["interval_effect"]["angle_range_deg"][0].get<double>(), mean_b2 + 50.0 * (lo - mu),
              1e-6);
  EXPECT_NEAR(b2["interval_effect"]["angle_range_deg"][1].get<double>(), mean_b2 + 50.0 * (hi - mu),
              1e-6);
  // The calibration test itself at its calibrated mu_r: a check, on target.
  const json& self = pj["predictions"][2];
  EXPECT_TRUE(self["check"].get<bool>());
  EXPECT_NEAR(self["mean_deg"].get<double>(), 35.0, 1e-6);
  // Every prediction run went through the pool once, in its own folder.
  const auto runs = read_log(log);
  int predict_runs = 0;
  for (const auto& [id, n] : runs) {
    EXPECT_EQ(n, 1) << id;
    if (id.rfind("predict_", 0) == 0) ++predict_runs;
  }
  EXPECT_EQ(predict_runs, 3 * 3 + 2 + 3 * 2);  // B: 3 mu_r x 3 seeds; B no ends: 2; self: 3 x 2
  EXPECT_TRUE(
      fs::exists(out / prediction_run(c, c.predictions[0], mu, 3).relative_dir() / "result.json"));
}

TEST(Predict, PredictOnlyReusesTheCalibrationAndNeverOverwrites) {
  const Scratch d("reuse");
  write_file_atomic((d.path / "c.toml").string(), calibration_campaign());
  const Campaign c = load_campaign((d.path / "c.toml").string());
  const fs::path out = d.path / "out", log = d.path / "log";
  // No calibration yet: predict-only is a clear error naming the file.
  try {
    read_calibration(c, out.string());
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("calibration.json"), std::string::npos) << e.what();
  }
  run_calibration(c, out.string(), synthetic_case(log), kAngle, quiet());
  const CalibrationRecord cal = read_calibration(c, out.string());
  const std::string cal_text = read_file((out / "calibration.json").string());
  const auto cal_time = fs::last_write_time(out / "calibration.json");
  const auto calibration_runs = read_log(log);

  // Kill a prediction mid-way: it leaves only started.json in one run folder.
  const CaseSpec victim = prediction_run(c, c.predictions[0], *cal.mu_r, 2);
  fs::create_directories(out / victim.relative_dir());
  write_file_atomic((out / victim.relative_dir() / "started.json").string(), "{}");
  const json first = run_predictions(c, cal, out.string(), synthetic_case(log), kAngle, quiet());
  std::map<fs::path, fs::file_time_type> stamps;
  for (const auto& e : fs::recursive_directory_iterator(out / "cases"))
    if (e.path().filename() == "result.json") stamps[e.path()] = fs::last_write_time(e.path());

  // Predict-only again: nothing runs, no result or calibration file is rewritten.
  const auto before = read_log(log);
  const json again = run_predictions(c, read_calibration(c, out.string()), out.string(),
                                     synthetic_case(log), kAngle, quiet());
  EXPECT_EQ(read_log(log), before);
  for (const auto& [p, t] : stamps) EXPECT_EQ(fs::last_write_time(p), t) << p;
  EXPECT_EQ(read_file((out / "calibration.json").string()), cal_text);
  EXPECT_EQ(fs::last_write_time(out / "calibration.json"), cal_time);
  EXPECT_EQ(again["predictions"], first["predictions"]);
  // Predicting ran no calibration run again.
  for (const auto& [id, n] : before) {
    if (id.rfind("calib_", 0) == 0) {
      EXPECT_EQ(n, calibration_runs.at(id)) << id;
    }
  }

  // Nor does a prediction that matches another angle than the calibration did.
  try {
    read_calibration(c, out.string(), "vision flank angle");
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("angle_method"), std::string::npos) << e.what();
  }
  // An edited campaign (another target) does not reuse this calibration.
  write_file_atomic((d.path / "c.toml").string(), calibration_campaign(3, 36.0));
  const Campaign edited = load_campaign((d.path / "c.toml").string());
  try {
    read_calibration(edited, out.string());
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("target.angle_deg"), std::string::npos) << e.what();
  }
  // A calibration that cannot reach its target has nothing to predict with.
  write_file_atomic((d.path / "c.toml").string(), calibration_campaign(3, 89.0));
  const Campaign unreachable = load_campaign((d.path / "c.toml").string());
  const fs::path out2 = d.path / "out2";
  const CalibrationRecord none =
      run_calibration(unreachable, out2.string(), synthetic_case(log), kAngle, quiet());
  EXPECT_FALSE(none.mu_r);
  EXPECT_THROW(
      run_predictions(unreachable, none, out2.string(), synthetic_case(log), kAngle, quiet()),
      std::runtime_error);
}

TEST(Predict, AClogIsCountedNeverAveraged) {
  const Scratch d("clog");
  write_file_atomic((d.path / "c.toml").string(), calibration_campaign());
  const Campaign c = load_campaign((d.path / "c.toml").string());
  const fs::path out = d.path / "out", log = d.path / "log";
  const CalibrationRecord cal =
      run_calibration(c, out.string(), synthetic_case(log), kAngle, quiet());
  const double hi = cal.mu_r_hi;
  // Test B's seed 2 arches the outlet at the high end of the interval: no pile there.
  const CaseSpec clogged = prediction_run(c, c.predictions[0], hi, 2);
  const CaseFn base = synthetic_case(log);
  const CaseFn fn = [&](const CaseSpec& s, const std::string& dir) {
    json r = base(s, dir);
    if (s.id() == clogged.id()) r["pile"]["status"] = "no pile";
    return r;
  };
  const AngleFn angle = [](const json& r) {
    const json& res = r.contains("result") ? r.at("result") : r;
    return res["pile"]["status"] == "no pile" ? std::numeric_limits<double>::quiet_NaN()
                                              : case_angle_deg(r, AngleMeasure::kImage);
  };
  const json pj = run_predictions(c, cal, out.string(), fn, angle, quiet());
  const json& high = pj["predictions"][0]["interval_effect"]["at_high"];
  EXPECT_EQ(high["no_pile"], 1);
  EXPECT_EQ(high["n"], 2);
  EXPECT_TRUE(high["angles_deg"][1].is_null());
  // The mean is over the two piles that formed (seeds 1 and 3: both +0.1 deg).
  EXPECT_NEAR(high["mean_deg"].get<double>(), 20.0 + 50.0 * hi + 2.0 + 0.1, 1e-9);
  EXPECT_EQ(pj["predictions"][0]["no_pile"], 0);
  EXPECT_TRUE(fs::exists(out / "predictions.json"));
}

// Predictions run in separate --only selections from one calibration all stay in
// predictions.json; running one again replaces only its own entry.
TEST(Predict, SeparateSelectionsAddUpInOneFile) {
  const Scratch d("selections");
  write_file_atomic((d.path / "c.toml").string(), calibration_campaign());
  const Campaign full = load_campaign((d.path / "c.toml").string());
  const fs::path out = d.path / "out", log = d.path / "log";
  run_calibration(full, out.string(), synthetic_case(log), kAngle, quiet());
  const CalibrationRecord cal = read_calibration(full, out.string());
  auto names = [&]() {
    std::vector<std::string> n;
    const json pj = json::parse(read_file((out / "predictions.json").string()));
    for (const auto& p : pj["predictions"]) n.push_back(p["name"]);
    std::sort(n.begin(), n.end());
    return n;
  };
  Campaign a = full;
  keep_only_predictions(a, {"self"});
  run_predictions(a, cal, out.string(), synthetic_case(log), kAngle, quiet());
  EXPECT_EQ(names(), std::vector<std::string>({"self"}));
  Campaign b = full;
  keep_only_predictions(b, {"sample4"});
  const json pj = run_predictions(b, cal, out.string(), synthetic_case(log), kAngle, quiet());
  EXPECT_EQ(names(), std::vector<std::string>({"sample4", "self"}));
  EXPECT_EQ(pj["predictions"].size(), 2u);
  run_predictions(a, cal, out.string(), synthetic_case(log), kAngle, quiet());
  EXPECT_EQ(names(), std::vector<std::string>({"sample4", "self"}));
}

TEST(Predict, OnlyTheNamedPredictionsAreKept) {
  const Scratch d("only");
  write_file_atomic((d.path / "c.toml").string(), calibration_campaign());
  Campaign c = load_campaign((d.path / "c.toml").string());
  keep_only_predictions(c, {"self", "sample4"});
  ASSERT_EQ(c.predictions.size(), 2u);
  EXPECT_EQ(c.predictions[0].name, "self");
  EXPECT_EQ(c.predictions[1].name, "sample4");
  try {
    keep_only_predictions(c, {"sample5"});
    FAIL() << "an unknown prediction name was accepted";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("c.toml"), std::string::npos) << what;
    EXPECT_NE(what.find("sample5"), std::string::npos) << what;
    EXPECT_NE(what.find("self, sample4"), std::string::npos) << what;
  }
}

TEST(Predict, ASecondCalibrationNeverReplacesAnotherFinishedOneUnasked) {
  const Scratch d("replace");
  write_file_atomic((d.path / "c.toml").string(), calibration_campaign());
  const fs::path out = d.path / "out", log = d.path / "log";
  const Campaign c = load_campaign((d.path / "c.toml").string());
  run_calibration(c, out.string(), synthetic_case(log), kAngle, quiet());
  // The same question again: allowed (every run is reused, the numbers are the same; only the
  // file's creation time is new, so the text to keep is read after it).
  EXPECT_NO_THROW(run_calibration(c, out.string(), synthetic_case(log), kAngle, quiet()));
  const std::string text = read_file((out / "calibration.json").string());
  // Another target, or the same target with another angle, in the same folder: refused, and the
  // finished file is left as it was.
  write_file_atomic((d.path / "c.toml").string(), calibration_campaign(3, 36.0));
  const Campaign edited = load_campaign((d.path / "c.toml").string());
  try {
    run_calibration(edited, out.string(), synthetic_case(log), kAngle, quiet());
    FAIL() << "a finished calibration was replaced unasked";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("calibration.json"), std::string::npos) << what;
    EXPECT_NE(what.find("target.angle_deg"), std::string::npos) << what;
    EXPECT_NE(what.find("--force"), std::string::npos) << what;
  }
  CalibrateOptions flank;
  flank.angle_method = "flank";
  EXPECT_THROW(run_calibration(c, out.string(), synthetic_case(log), kAngle, quiet(), flank),
               std::runtime_error);
  EXPECT_EQ(read_file((out / "calibration.json").string()), text);
  // Asked (--force): replaced.
  RunnerSettings forced = quiet();
  forced.force = true;
  const CalibrationRecord again =
      run_calibration(edited, out.string(), synthetic_case(log), kAngle, forced);
  EXPECT_DOUBLE_EQ(again.target.angle_deg, 36.0);
}

// The paper's CSV read independently of the report's reader: sample -> field -> value.
std::map<int, std::map<std::string, std::string>> independent_csv(const fs::path& p) {
  std::ifstream in(p);
  std::vector<std::string> header;
  std::map<int, std::map<std::string, std::string>> out;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> f;
    std::stringstream ss(line);
    for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
    if (header.empty()) {
      header = f;
      continue;
    }
    std::map<std::string, std::string> row;
    for (std::size_t i = 0; i < f.size(); ++i) row[header[i]] = f[i];
    out[std::stoi(row["sample"])] = row;
  }
  return out;
}

TEST(Report, PaperComparisonHasEverySampleAndReadsTheCsv) {
  const Scratch d("compare");
  const fs::path parent = d.path / "calibrations", log = d.path / "log";
  // Two calibrations: sample 3 (predicting 4) and sample 1 (measured 33.47 deg: no predictions).
  for (int sample : {3, 1}) {
    const std::string text = sample == 3
                                 ? calibration_campaign(3, 35.0)
                                 : "name = \"calib_s1\"\nscene = \"a.toml\"\nseeds = [1, 2]\n"
                                   "[calibration]\ntarget_deg = 33.47\n"
                                   "mu_r_range = [0.02, 0.8]\nseeds_per_point = 2\n"
                                   "max_simulations = 16\nbootstrap_replicates = 200\n"
                                   "key = [\"contacts.rock-rock.rolling_friction\", "
                                   "\"contacts.rock-plate.rolling_friction\"]\n"
                                   "table1_sample = 1\n";
    const fs::path file = d.path / ("s" + std::to_string(sample) + ".toml");
    write_file_atomic(file.string(), text);
    const Campaign c = load_campaign(file.string());
    const fs::path out = parent / ("s" + std::to_string(sample));
    const CalibrationRecord cal =
        run_calibration(c, out.string(), synthetic_case(log), kAngle, quiet());
    if (!c.predictions.empty())
      run_predictions(c, cal, out.string(), synthetic_case(log), kAngle, quiet());
  }
  // A paper folder of our own with unusual values: the table must show these, not built-ins.
  const fs::path paper = d.path / "paper";
  fs::create_directories(paper);
  write_file_atomic((paper / "table1_lab_tests.csv").string(),
                    "# test copy\nsource,sample,d_max_mm,mass_g,funnel_W_mm,theta_measured_deg,"
                    "angle_method\nTable 1,1,2.5,210,40,33.11,x\nTable 1,2,3.5,310,40,34.22,x\n"
                    "Table 1,3,5.5,710,40,36.33,x\nTable 1,4,8.5,910,40,37.44,x\n");
  write_file_atomic((paper / "table3_calibration.csv").string(),
                    "# EDEM convention: lever arm R (test copy)\nsource,sample,d_max_mm,mass_g,"
                    "mu_r,how,theta_measured_deg,theta_numerical_deg\n"
                    "Table 3,1,2.5,210,0.111,calibration,33.11,33.55\n"
                    "Table 3,2,3.5,310,0.122,calibration,34.22,34.66\n"
                    "Table 3,3,5.5,710,0.133,calibration,36.33,36.77\n"
                    "Table 3,4,8.5,910,0.144,prediction,37.44,38.88\n");
  ReportSettings rs;
  rs.paper_dir = paper.string();
  const json summary = build_report(parent.string(), rs);  // a parent of calibration folders
  ASSERT_TRUE(summary.contains("paper_comparison")) << summary.dump(2);
  const json& rows = summary["paper_comparison"]["rows"];
  std::map<std::string, json> by;  // "<kind> <sample>"
  for (const json& r : rows)
    by[r["kind"].get<std::string>() + " " + std::to_string(r["sample"].get<int>())] = r;
  ASSERT_TRUE(by.count("calibration 1"));
  ASSERT_TRUE(by.count("calibration 3"));
  ASSERT_TRUE(by.count("prediction 4"));  // sample4 and sample4_no_ends
  ASSERT_TRUE(by.count("not run here 2"));
  EXPECT_EQ(rows.size(), 5u);
  const auto t1 = independent_csv(paper / "table1_lab_tests.csv");
  const auto t3 = independent_csv(paper / "table3_calibration.csv");
  for (const auto& [k, r] : by) {
    const int s = r["sample"].get<int>();
    EXPECT_DOUBLE_EQ(r["paper_mu_r"].get<double>(), std::stod(t3.at(s).at("mu_r"))) << k;
    EXPECT_DOUBLE_EQ(r["paper_angle_deg"].get<double>(),
                     std::stod(t3.at(s).at("theta_numerical_deg")))
        << k;
    EXPECT_DOUBLE_EQ(r["measured_deg"].get<double>(), std::stod(t1.at(s).at("theta_measured_deg")))
        << k;
    EXPECT_DOUBLE_EQ(r["paper_d_max_mm"].get<double>(), std::stod(t1.at(s).at("d_max_mm"))) << k;
  }
  // Sample 3: the check runs at the calibrated mu_r give the angle (35 +- the seed effect).
  const json& s3 = by["calibration 3"];
  EXPECT_NEAR(s3["angle_mean_deg"].get<double>(), 35.0, 1e-6);
  EXPECT_NEAR(s3["abs_error_deg"].get<double>(), std::abs(35.0 - 36.33), 1e-6);
  EXPECT_NE(s3["angle_how"].get<std::string>().find("runs"), std::string::npos);
  // Sample 1 has no check run: the fit's value there (the target, 33.47).
  EXPECT_NEAR(by["calibration 1"]["angle_mean_deg"].get<double>(), 33.47, 1e-6);
  EXPECT_NE(by["calibration 1"]["angle_how"].get<std::string>().find("fit"), std::string::npos);

  const std::string html = read_file((parent / "report" / "index.html").string());
  EXPECT_NE(html.find("0.144"), std::string::npos);  // the test CSV's sample-4 mu_r
  EXPECT_NE(html.find("38.88"), std::string::npos);
  EXPECT_NE(html.find("<b>prediction</b>"), std::string::npos);
  // The caption states our convention as sim::kRollingModels words it, and the CSV's note.
  std::string radius(sim::find_rolling_model("epsd")->radius);
  EXPECT_NE(html.find(radius.substr(0, radius.find(' ', 10))), std::string::npos) << radius;
  EXPECT_NE(html.find("twice"), std::string::npos);
  EXPECT_NE(html.find("EDEM convention: lever arm R (test copy)"), std::string::npos);
  EXPECT_TRUE(fs::exists(parent / "report" / "comparison.png"));
  EXPECT_TRUE(fs::exists(parent / "s3" / "report" / "index.html"));  // each folder's own report
  // Several folders named on the command line give the same rows.
  const json two = build_report({(parent / "s1").string(), (parent / "s3").string()},
                                (d.path / "both").string(), rs);
  EXPECT_EQ(two["paper_comparison"]["rows"], summary["paper_comparison"]["rows"]);
  // The shipped CSVs are found from the campaign... here from the source tree, given.
  rs.paper_dir = std::string(REPOSETWIN_SOURCE_DIR) + "/data/paper";
  const json shipped = paper_comparison({(parent / "s3").string()}, rs.paper_dir);
  const auto real3 = independent_csv(fs::path(rs.paper_dir) / "table3_calibration.csv");
  for (const json& r : shipped["rows"])
    EXPECT_DOUBLE_EQ(r["paper_mu_r"].get<double>(),
                     std::stod(real3.at(r["sample"].get<int>()).at("mu_r")));
  EXPECT_THROW(paper_comparison({d.path.string()}, rs.paper_dir), InputError);
}

TEST(Report, LabPhotoBesideTheRenderForCalibrationAndCampaign) {
  const Scratch d("lab");
  // A synthetic lab photo whose angle is known: H 55 mm, D 190 mm.
  vision::synthetic::SideScene scene;
  scene.height_mm = 55.0;
  scene.diameter_mm = 190.0;
  const fs::path photo = d.path / "lab.png";
  cv::imwrite(photo.string(), vision::synthetic::draw_side(scene));
  const double theta = std::atan(2.0 * 55.0 / 190.0) * 180.0 / 3.14159265358979323846;
  ReportSettings rs;
  rs.lab_photo = photo.string();
  rs.paper_dir = std::string(REPOSETWIN_SOURCE_DIR) + "/data/paper";

  // Calibration folder: the render shown is the calibration scene's run nearest the calibrated
  // mu_r (here the check run at it).
  write_file_atomic((d.path / "c.toml").string(), calibration_campaign());
  const Campaign c = load_campaign((d.path / "c.toml").string());
  const fs::path out = d.path / "cal", log = d.path / "log";
  const CalibrationRecord cal =
      run_calibration(c, out.string(), synthetic_case(log, true), kAngle, quiet());
  run_predictions(c, cal, out.string(), synthetic_case(log, true), kAngle, quiet());
  const json s = build_report(out.string(), rs);
  EXPECT_NEAR(s["lab_photo"]["theta_deg"].get<double>(), theta, 0.3) << s["lab_photo"];
  const std::string self = prediction_run(c, c.predictions[2], *cal.mu_r, 1).case_name;
  EXPECT_NE(s["lab_photo_render"].get<std::string>().find(self), std::string::npos)
      << s["lab_photo_render"];
  EXPECT_TRUE(fs::exists(out / "report" / "lab_photo.measured.png"));
  EXPECT_TRUE(fs::exists(out / "report" / "render_beside_lab.png"));
  const std::string html = read_file((out / "report" / "index.html").string());
  EXPECT_NE(html.find("render_beside_lab.png"), std::string::npos);
  EXPECT_NE(html.find("lab_photo.measured.png"), std::string::npos);

  // Campaign folder: the first case with a render.
  write_file_atomic((d.path / "camp.toml").string(),
                    "name = \"camp\"\nscene = \"a.toml\"\nseeds = [1]\n[[case]]\nname = \"low\"\n"
                    "overrides = { \"contacts.rock-rock.rolling_friction\" = 0.1, "
                    "\"contacts.rock-plate.rolling_friction\" = 0.1 }\n");
  const Campaign camp = load_campaign((d.path / "camp.toml").string());
  run_campaign(camp, (d.path / "camp").string(), synthetic_case(log, true), quiet());
  const json t = build_report((d.path / "camp").string(), rs);
  EXPECT_NEAR(t["lab_photo"]["theta_deg"].get<double>(), theta, 0.3);
  EXPECT_NE(t["lab_photo_render"].get<std::string>().find("low"), std::string::npos);
  EXPECT_TRUE(fs::exists(d.path / "camp" / "report" / "render_beside_lab.png"));
  // Every case shows its vision flank angle beside its image atan(2H/D).
  ASSERT_EQ(t["cases"].size(), 1u);
  EXPECT_DOUBLE_EQ(t["cases"][0]["image_flank_mean_deg"].get<double>(),
                   t["cases"][0]["image_theta_mean_deg"].get<double>() + kFlankAboveImage);
  EXPECT_NE(read_file((d.path / "camp" / "report" / "index.html").string())
                .find("image flank angle"),
            std::string::npos);
  // A photo that is not an image is a clear error naming it.
  write_file_atomic((d.path / "bad.png").string(), "not a png");
  rs.lab_photo = (d.path / "bad.png").string();
  try {
    build_report((d.path / "camp").string(), rs);
    FAIL() << "expected an error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.png"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace reposetwin::experiments
