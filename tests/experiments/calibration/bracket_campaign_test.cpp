// The bracketing calibration from a campaign file: its keys, strictness, and a calibration through
// the resumable pool where some pours jam. The "pile runs" are synthetic case functions with a
// closed-form angle, 20 + 50 mu_r +- 0.1 deg by seed parity, so mu_r = 0.3 matches 35 deg.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "../../support/quiet_runner.hpp"
#include "experiments/calibration/calibrate_campaign.hpp"
#include "experiments/calibration/campaign_target.hpp"
#include "experiments/campaign/case_runner.hpp"
#include "experiments/io/provenance.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;

constexpr const char* kScene = R"(
[sample]
mass_kg = 0.0
[contacts.rock-rock]
rolling_friction = 0.15
[contacts.rock-plate]
rolling_friction = 0.15
)";

struct Scratch {
  explicit Scratch(const std::string& name)
      : path(fs::temp_directory_path() /
             ("reposetwin_bracket_test_" + std::to_string(::getpid()) + "_" + name)) {
    fs::remove_all(path);
    fs::create_directories(path);
    write_file_atomic((path / "a.toml").string(), kScene);
  }
  ~Scratch() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  fs::path path;
};

std::string campaign(const std::string& extra) {
  return "name = \"bracket\"\nscene = \"a.toml\"\nseeds = [1, 2]\n[calibration]\n"
         "key = [\"contacts.rock-rock.rolling_friction\", "
         "\"contacts.rock-plate.rolling_friction\"]\n"
         "target_deg = 35.0\nmu_r_range = [0.02, 0.8]\nmethod = \"bracket\"\n"
         "bootstrap_replicates = 400\n" +
         extra;
}

std::string load_error(const fs::path& dir, const std::string& text) {
  write_file_atomic((dir / "c.toml").string(), text);
  try {
    load_campaign((dir / "c.toml").string());
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(BracketCampaign, ReadsItsKeys) {
  const Scratch d("keys");
  write_file_atomic((d.path / "c.toml").string(),
                    campaign("mu_r_start = 0.2\nslope_guess_deg = 40.0\nmu_r_tolerance = 0.01\n"
                             "max_jam_rate = 0.4\nseeds_per_point = 3\n"));
  const Campaign c = load_campaign((d.path / "c.toml").string());
  ASSERT_TRUE(c.calibration);
  EXPECT_EQ(c.calibration->method, CalibrationMethod::kBracket);
  const BracketSettings& b = c.calibration->bracket;
  EXPECT_DOUBLE_EQ(*b.mu_r_start, 0.2);
  EXPECT_DOUBLE_EQ(b.slope_guess_deg, 40.0);
  EXPECT_DOUBLE_EQ(b.mu_r_tolerance, 0.01);
  EXPECT_DOUBLE_EQ(b.max_jam_rate, 0.4);
  EXPECT_EQ(b.seeds, (std::vector<std::uint64_t>{1, 2, 3}));
  EXPECT_EQ(b.max_runs, 9);  // three points by default
  EXPECT_DOUBLE_EQ(b.mu_r_lo, 0.02);
  EXPECT_DOUBLE_EQ(b.mu_r_hi, 0.8);
}

TEST(BracketCampaign, BadKeysAreNamed) {
  const Scratch d("bad");
  std::string secant = campaign("");
  secant.replace(secant.find("method = \"bracket\""), 18, "method = \"secant\"");
  const std::string m1 = load_error(d.path, secant);
  EXPECT_NE(m1.find("calibration.method"), std::string::npos) << m1;
  EXPECT_NE(m1.find("secant"), std::string::npos) << m1;
  const std::string m2 = load_error(d.path, campaign("mu_r_start = 0.9\n"));
  EXPECT_NE(m2.find("calibration.mu_r_start"), std::string::npos) << m2;
  EXPECT_NE(m2.find("0.9"), std::string::npos) << m2;
  const std::string m3 = load_error(d.path, campaign("confirm = true\n"));
  EXPECT_NE(m3.find("calibration.confirm"), std::string::npos) << m3;
  const std::string m4 = load_error(d.path, campaign("seeds_per_point = 1\n"));
  EXPECT_NE(m4.find("calibration.seeds_per_point"), std::string::npos) << m4;
  const std::string m5 = load_error(d.path, campaign("mu_r_tolerence = 0.01\n"));
  EXPECT_NE(m5.find("mu_r_tolerence"), std::string::npos) << m5;
  // The sequential driver refuses the bracketing keys rather than ignore them.
  std::string seq = campaign("mu_r_start = 0.2\n");
  seq.replace(seq.find("method = \"bracket\"\n"), 19, "");
  const std::string m6 = load_error(d.path, seq);
  EXPECT_NE(m6.find("calibration.mu_r_start"), std::string::npos) << m6;
}

// Pours above mu_r 0.45 jam for odd seeds: counted per mu_r, never averaged.
CaseFn jamming_case(const fs::path& log) {
  return [log](const CaseSpec& s, const std::string&) {
    std::ofstream(log, std::ios::app) << s.id() << "\n";
    const double mu = build_case_scene(s).number("contacts.rock-rock.rolling_friction").value();
    const double a = 20.0 + 50.0 * mu + (s.seed % 2 ? 0.1 : -0.1);
    json pile = {{"status", "ok"}, {"theta_hd_deg", a}, {"slice_angle_mean_deg", a}};
    json stop = {{"reason", "settled"}};
    if (mu > 0.45 && s.seed % 2 == 1) {
      pile = {{"status", "no pile"}, {"clogged", true}, {"lodged", 40}};
      stop = {{"reason", "clogged"}, {"detail", "no pile: 40 lodged"}};
    }
    return json{{"stop", stop},
                {"pile", pile},
                {"provenance", {{"time_step_s", 1e-6}, {"code_version", "test"}}},
                {"run_dir", "run"}};
  };
}

RunnerSettings quiet() { return test_support::quiet_runner(); }

TEST(BracketCampaign, CalibratesThroughThePoolAndCountsJams) {
  const Scratch d("run");
  // Start high, where half the pours jam: the driver must step down from the piles it has.
  write_file_atomic((d.path / "c.toml").string(),
                    campaign("mu_r_start = 0.5\nslope_guess_deg = 40.0\nmax_simulations = 8\n"));
  const Campaign c = load_campaign((d.path / "c.toml").string());
  const fs::path out = d.path / "out", log = d.path / "log";
  const CalibrationRecord cal = run_calibration(
      c, out.string(), jamming_case(log), calibration_angle(AngleMeasure::kParticles), quiet());
  EXPECT_EQ(cal.method, CalibrationMethod::kBracket);
  ASSERT_TRUE(cal.mu_r) << cal.message;
  EXPECT_NEAR(*cal.mu_r, 0.3, 0.02);
  EXPECT_LE(cal.working.at("pile_runs").get<int>(), 8);
  bool saw_jams = false;
  for (const PourCount& q : cal.pour_counts)
    if (q.mu_r > 0.45) {
      saw_jams = true;
      EXPECT_EQ(q.jams, 1);
      EXPECT_DOUBLE_EQ(q.jam_rate, 0.5);
    }
  EXPECT_TRUE(saw_jams);
  for (const Observation& o : cal.observations) EXPECT_GT(o.angle_deg, 20.0);
  // The file says the same: read back through the one reader, it is the record returned.
  EXPECT_EQ(read_calibration_record((out / "calibration.json").string()), cal);
  // Resumed: every pour is reused, none is run again.
  std::map<std::string, int> runs;
  {
    std::ifstream in(log);
    for (std::string line; std::getline(in, line);) ++runs[line];
  }
  const CalibrationRecord again = run_calibration(
      c, out.string(), jamming_case(log), calibration_angle(AngleMeasure::kParticles), quiet());
  std::map<std::string, int> after;
  {
    std::ifstream in(log);
    for (std::string line; std::getline(in, line);) ++after[line];
  }
  EXPECT_EQ(runs, after);
  EXPECT_EQ(again.mu_r, cal.mu_r);
}

// Every pour stopped by procedure.max_time_s: the calibration names the time limit and advises
// on it, not on the grain shape or jams.
TEST(BracketCampaign, AdviceIsOnTheRealStop) {
  const Scratch d("time_limit");
  write_file_atomic((d.path / "c.toml").string(),
                    campaign("ends_first = true\nmax_simulations = 8\n"));
  const Campaign c = load_campaign((d.path / "c.toml").string());
  const CaseFn timed_out = [](const CaseSpec&, const std::string&) {
    return json{{"stop", {{"reason", "time limit"}, {"detail", "t = 4 s"}}},
                {"pile", {{"status", "ok"}, {"theta_hd_deg", 30.0}, {"slice_angle_mean_deg", 30.0}}},
                {"provenance", {{"time_step_s", 1e-6}, {"code_version", "test"}}},
                {"run_dir", "run"}};
  };
  const CalibrationRecord cal =
      run_calibration(c, (d.path / "out").string(), timed_out,
                      calibration_angle(AngleMeasure::kParticles), quiet());
  ASSERT_FALSE(cal.mu_r) << to_json(cal).dump(2);
  EXPECT_FALSE(cal.material);
  const std::string advice = cannot_reach_advice(c, cal, AngleMeasure::kParticles);
  EXPECT_NE(advice.find("time_limit (4 pour(s)): raise procedure.max_time_s"), std::string::npos)
      << advice;
  EXPECT_EQ(advice.find("jammed"), std::string::npos) << advice;
  EXPECT_EQ(advice.find("grain shape"), std::string::npos) << advice;
}

}  // namespace
}  // namespace reposetwin::experiments
