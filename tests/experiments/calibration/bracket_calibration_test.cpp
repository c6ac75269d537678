#include "experiments/calibration/bracket_calibration.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>

namespace reposetwin::experiments {
namespace {

// A saturating curve like our flank angles on sample 1: angle(mu_r) = 11.92 + 30 (1 - exp(-mu_r /
// 0.3)) [deg], slope about 28 deg per unit mu_r at the lab's 33.47 deg. Its inverse in closed form.
double curve(double mu) { return 11.92 + 30.0 * (1.0 - std::exp(-mu / 0.3)); }
double curve_root(double angle) { return -0.3 * std::log(1.0 - (angle - 11.92) / 30.0); }

// A standard normal that depends only on its arguments (a simulation's seed noise).
double gauss(std::uint64_t a, std::uint64_t b, std::uint64_t c) {
  std::seed_seq ss{a, b, c};
  std::mt19937_64 g(ss);
  const double u1 = (static_cast<double>(g() >> 11) + 0.5) * 0x1.0p-53;
  const double u2 = (static_cast<double>(g() >> 11) + 0.5) * 0x1.0p-53;
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

// The faked pile runs: the curve plus a per-seed offset (common to every mu_r: what common random
// numbers exploit) and run-to-run noise; pours above `jam_above` jam for odd seeds (or all seeds
// when `jam_all`), as an outlet arches at high rolling resistance.
struct FakePours {
  std::uint64_t stream = 1;
  double seed_sd = 0.3, run_sd = 0.15;
  double jam_above = 10.0;
  bool jam_all = false;
  int calls = 0;
  std::vector<Pour> operator()(const std::vector<std::pair<double, std::uint64_t>>& batch) {
    std::vector<Pour> out;
    for (const auto& [mu, seed] : batch) {
      ++calls;
      Pour p;
      if (mu > jam_above && (jam_all || seed % 2 == 1)) {
        p.outcome = PourOutcome::kJam;
        p.angle_deg = 0.0;  // what a clogged run's angle reads: must never enter the fit
        p.detail = "no pile: outlet arched";
      } else {
        const auto mu_key = static_cast<std::uint64_t>(std::llround(mu * 1e9));
        p.angle_deg =
            curve(mu) + seed_sd * gauss(stream, seed, 0) + run_sd * gauss(stream, seed, mu_key + 1);
      }
      out.push_back(p);
    }
    return out;
  }
};

BracketSettings sample1_settings() {
  BracketSettings s;
  s.mu_r_lo = 0.2;
  s.mu_r_hi = 0.6;
  s.mu_r_start = 0.35;
  s.slope_guess_deg = 26.0;
  s.seeds = {1, 2};
  s.mu_r_tolerance = 0.02;
  s.max_runs = 6;
  s.bootstrap.replicates = 500;
  return s;
}

// The goal: a Table 1 sample-1 calibration in at most 6 pile runs, with the known root
// found within the tolerance, over many noise streams.
TEST(BracketCalibration, FindsTheKnownRootWithinToleranceInSixRuns) {
  const Target target{33.47, 0.0};
  const double truth = curve_root(target.angle_deg);
  ASSERT_NEAR(truth, 0.38, 0.01);
  int calibrated = 0, within = 0;
  const int trials = 40;
  for (int t = 0; t < trials; ++t) {
    FakePours fake;
    fake.stream = 100 + t;
    const BracketCalibration c = calibrate_bracket(std::ref(fake), target, sample1_settings());
    EXPECT_LE(fake.calls, 6) << "trial " << t;
    EXPECT_EQ(c.result.simulations, fake.calls);
    ASSERT_TRUE(c.result.mu_r.has_value()) << c.result.message;
    EXPECT_TRUE(c.bracketed);
    if (c.result.status == CalibrationStatus::kCalibrated) ++calibrated;
    if (std::abs(*c.result.mu_r - truth) <= 0.02) ++within;
    // The stated uncertainty is what the stop rule compared.
    if (c.result.status == CalibrationStatus::kCalibrated) {
      EXPECT_LE(c.mu_r_uncertainty, 0.02);
    }
  }
  EXPECT_GE(calibrated, trials * 9 / 10);
  EXPECT_GE(within, trials * 9 / 10);
}

// Without noise the driver must land on the root to within the tolerance, deterministically.
TEST(BracketCalibration, NoiselessCurveGivesTheRoot) {
  FakePours fake;
  fake.seed_sd = 0.0;
  fake.run_sd = 0.0;
  const BracketCalibration c = calibrate_bracket(std::ref(fake), {33.47, 0.0}, sample1_settings());
  ASSERT_TRUE(c.result.mu_r.has_value());
  EXPECT_EQ(c.result.status, CalibrationStatus::kCalibrated) << c.result.message;
  EXPECT_NEAR(*c.result.mu_r, curve_root(33.47), 0.01);
  EXPECT_LE(fake.calls, 6);
  EXPECT_EQ(c.mu_r_seed_se, 0.0);  // identical seeds: no spread
}

// Common random numbers: every point is run with the same seeds.
TEST(BracketCalibration, EveryPointRunsTheSameSeeds) {
  FakePours fake;
  const BracketCalibration c = calibrate_bracket(std::ref(fake), {33.47, 0.0}, sample1_settings());
  for (const PourPoint& q : c.points) EXPECT_EQ(q.pours, 2) << q.mu_r;
  for (std::size_t i = 0; i < c.pours.size(); ++i) EXPECT_EQ(c.pours[i].seed, i % 2 == 0 ? 1u : 2u);
}

// A target above everything the range reaches is reported as such, with no mu_r, and the search
// ends at the range's end instead of spending the whole budget there.
TEST(BracketCalibration, TargetOutOfReachIsSaid) {
  BracketSettings s = sample1_settings();
  s.max_runs = 20;
  FakePours high;
  const BracketCalibration c = calibrate_bracket(std::ref(high), {45.0, 0.0}, s);
  EXPECT_EQ(c.result.status, CalibrationStatus::kCannotReachHigh) << c.result.message;
  EXPECT_FALSE(c.result.mu_r.has_value());
  EXPECT_NE(c.result.message.find("cannot reach"), std::string::npos) << c.result.message;
  EXPECT_EQ(c.points.back().mu_r, 0.6);
  EXPECT_LT(high.calls, 20);
  FakePours low;
  const BracketCalibration d = calibrate_bracket(std::ref(low), {15.0, 0.0}, s);
  EXPECT_EQ(d.result.status, CalibrationStatus::kCannotReachLow) << d.result.message;
  EXPECT_EQ(d.points.front().mu_r, 0.2);
}

// Jammed pours are a jam rate, never an angle: with half the pours jamming above mu_r 0.36 the
// calibration still finds the root from the piles alone, and the jam rate per point is reported.
TEST(BracketCalibration, JamsCountAsJamRateNotAngles) {
  FakePours fake;
  fake.seed_sd = 0.0;
  fake.run_sd = 0.0;
  fake.jam_above = 0.36;
  BracketSettings s = sample1_settings();
  s.seeds = {1, 2, 3, 4};
  s.max_runs = 12;
  const BracketCalibration c = calibrate_bracket(std::ref(fake), {33.47, 0.0}, s);
  ASSERT_TRUE(c.result.mu_r.has_value()) << c.result.message;
  EXPECT_NEAR(*c.result.mu_r, curve_root(33.47), 0.02);
  bool saw_jam_point = false;
  for (const PourPoint& q : c.points) {
    if (q.mu_r > 0.36) {
      saw_jam_point = true;
      EXPECT_EQ(q.jams, 2);
      EXPECT_DOUBLE_EQ(q.jam_rate(), 0.5);
    } else {
      EXPECT_EQ(q.jams, 0);
    }
  }
  EXPECT_TRUE(saw_jam_point);
  for (const Observation& o : c.result.observations) EXPECT_GT(o.angle_deg, 20.0);
  int jams = 0;
  for (const Pour& p : c.pours) jams += p.outcome == PourOutcome::kJam;
  EXPECT_EQ(static_cast<int>(c.result.observations.size()),
            static_cast<int>(c.pours.size()) - jams);
  const nlohmann::json j = to_json(calibration_record(c, s));
  EXPECT_EQ(j["method"], "bracket");
  EXPECT_EQ(j["pile_runs"], c.pours.size());
  EXPECT_TRUE(j["jam_rate_per_mu_r"].is_array());
  EXPECT_NE(c.result.message.find("jammed"), std::string::npos);
}

// When every pour above some mu_r jams and the angle below it stays under the target, the target
// is out of reach because of the jams, and the message says so.
TEST(BracketCalibration, JamsBelowTheTargetMakeItUnreachable) {
  FakePours fake;
  fake.seed_sd = 0.0;
  fake.run_sd = 0.0;
  fake.jam_above = 0.3;
  fake.jam_all = true;
  BracketSettings s = sample1_settings();
  s.mu_r_start = 0.25;
  s.max_runs = 30;
  const BracketCalibration c = calibrate_bracket(std::ref(fake), {33.47, 0.0}, s);
  EXPECT_EQ(c.result.status, CalibrationStatus::kCannotReachHigh) << c.result.message;
  EXPECT_NE(c.result.message.find("jam"), std::string::npos) << c.result.message;
  for (const Observation& o : c.result.observations) EXPECT_LE(o.mu_r, 0.3);
}

// Pours that a time limit stopped are not jams: the calibration stops at once (a lower mu_r does
// not cure a time limit), and its message names the real stop, never "every pour jammed".
TEST(BracketCalibration, ATimeLimitIsNamedNotTakenForAJam) {
  BracketSettings s = sample1_settings();
  s.mu_r_start.reset();
  s.ends_first = true;
  s.max_runs = 12;
  int calls = 0;
  const auto timed_out = [&calls](const std::vector<std::pair<double, std::uint64_t>>& batch) {
    std::vector<Pour> out;
    for (const auto& [mu, seed] : batch) {
      ++calls;
      Pour p;
      p.mu_r = mu;
      p.seed = seed;
      p.outcome = PourOutcome::kTimeLimit;
      p.detail = "stopped at procedure.max_time_s";
      out.push_back(p);
    }
    return out;
  };
  const BracketCalibration c = calibrate_bracket(timed_out, {33.47, 0.0}, s);
  EXPECT_FALSE(c.result.mu_r.has_value());
  EXPECT_EQ(calls, 4);  // the two ends, then stopped
  EXPECT_EQ(c.result.message.find("jammed"), std::string::npos) << c.result.message;
  EXPECT_NE(c.result.message.find("4 stopped by the time limit procedure.max_time_s"),
            std::string::npos)
      << c.result.message;
  const nlohmann::json j = to_json(calibration_record(c, s));
  int limits = 0;
  for (const auto& q : j["jam_rate_per_mu_r"]) limits += q["time_limits"].get<int>();
  EXPECT_EQ(limits, 4);
  EXPECT_EQ(j["pours"][0]["outcome"], "time_limit");
}

// A lab's calibration from its sheets runs the two range ends first: a target above what the
// range reaches is known after those two points (4 pours with 2 seeds), and the reachable
// interval is the curve's values at the ends.
TEST(BracketCalibration, EndsFirstKnowsAnUnreachableTargetAfterTwoPoints) {
  FakePours fake;
  fake.seed_sd = 0.0;
  fake.run_sd = 0.0;
  BracketSettings s = sample1_settings();
  s.mu_r_start.reset();
  s.ends_first = true;
  s.max_runs = 12;
  const BracketCalibration c = calibrate_bracket(std::ref(fake), {45.0, 0.0}, s);
  EXPECT_EQ(c.result.status, CalibrationStatus::kCannotReachHigh) << c.result.message;
  ASSERT_EQ(c.pours.size(), 4u);
  EXPECT_EQ(fake.calls, 4);
  EXPECT_EQ(c.pours[0].mu_r, s.mu_r_lo);
  EXPECT_EQ(c.pours[1].mu_r, s.mu_r_lo);
  EXPECT_EQ(c.pours[2].mu_r, s.mu_r_hi);
  EXPECT_EQ(c.pours[3].mu_r, s.mu_r_hi);
  EXPECT_NEAR(c.result.reachable_low_deg, curve(s.mu_r_lo), 1e-9);
  EXPECT_NEAR(c.result.reachable_high_deg, curve(s.mu_r_hi), 1e-9);
  const nlohmann::json j = to_json(calibration_record(c, s));
  EXPECT_TRUE(j["ends_first"].get<bool>());
}

// Ends first, a reachable target: the third point is the fitted crossing between the ends, and
// the calibration ends near the known root.
TEST(BracketCalibration, EndsFirstThenTheCrossing) {
  FakePours fake;
  BracketSettings s = sample1_settings();
  s.mu_r_start.reset();
  s.ends_first = true;
  s.max_runs = 12;
  const double target = 33.47;
  const BracketCalibration c = calibrate_bracket(std::ref(fake), {target, 0.0}, s);
  ASSERT_GE(c.pours.size(), 6u);
  EXPECT_EQ(c.pours[0].mu_r, s.mu_r_lo);
  EXPECT_EQ(c.pours[2].mu_r, s.mu_r_hi);
  EXPECT_GT(c.pours[4].mu_r, s.mu_r_lo);
  EXPECT_LT(c.pours[4].mu_r, s.mu_r_hi);
  ASSERT_TRUE(c.result.mu_r.has_value()) << c.result.message;
  EXPECT_NEAR(*c.result.mu_r, curve_root(target), 0.03);
}

TEST(BracketCalibration, SettingsAreChecked) {
  FakePours fake;
  BracketSettings s = sample1_settings();
  s.seeds = {1};
  EXPECT_THROW(calibrate_bracket(std::ref(fake), {33.47, 0.0}, s), std::invalid_argument);
  s = sample1_settings();
  s.mu_r_start = 0.9;
  EXPECT_THROW(calibrate_bracket(std::ref(fake), {33.47, 0.0}, s), std::invalid_argument);
  s = sample1_settings();
  s.max_runs = 3;
  EXPECT_THROW(calibrate_bracket(std::ref(fake), {33.47, 0.0}, s), std::invalid_argument);
  s = sample1_settings();
  s.max_jam_rate = 1.0;
  EXPECT_THROW(calibrate_bracket(std::ref(fake), {33.47, 0.0}, s), std::invalid_argument);
  EXPECT_EQ(fake.calls, 0);
}

}  // namespace
}  // namespace reposetwin::experiments
