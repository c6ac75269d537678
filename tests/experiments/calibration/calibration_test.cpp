#include "experiments/calibration/calibration.hpp"
#include "experiments/calibration/calibration_file.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>
#include <random>
#include <set>
#include <stdexcept>

namespace reposetwin::experiments {
namespace {

// A known monotone curve: angle(mu_r) = 20 + 25 (1 - exp(-mu_r / 0.12)) [deg].
double true_angle(double mu) { return 20.0 + 25.0 * (1.0 - std::exp(-mu / 0.12)); }
// Its inverse, in closed form.
double true_mu(double angle) { return -0.12 * std::log(1.0 - (angle - 20.0) / 25.0); }

// Seeded Gaussian noise that depends only on (noise seed, mu_r, run seed), as a simulation would.
double noise(std::uint64_t stream, double mu, std::uint64_t seed, double sd) {
  std::seed_seq ss{stream, seed, static_cast<std::uint64_t>(std::llround(mu * 1e9))};
  std::mt19937_64 g(ss);
  const double u1 = (static_cast<double>(g() >> 11) + 0.5) * 0x1.0p-53;
  const double u2 = (static_cast<double>(g() >> 11) + 0.5) * 0x1.0p-53;
  return sd * std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

TEST(Calibration, PoolAdjacentViolatorsClosedForm) {
  // Means 30, 34, 32, 36 at equal weight: the violating pair pools to 33.
  std::vector<Observation> obs = {{0.0, 1, 30}, {0.1, 1, 34}, {0.2, 1, 32}, {0.3, 1, 36}};
  auto fit = fit_monotone(obs);
  ASSERT_EQ(fit.points.size(), 4u);
  EXPECT_DOUBLE_EQ(fit.points[1].fitted_deg, 33.0);
  EXPECT_DOUBLE_EQ(fit.points[2].fitted_deg, 33.0);
  // Weighted by seeds: three seeds at 0.2 (mean 32) against one at 0.1 (34): (34 + 3 x 32) / 4.
  obs = {{0.0, 1, 30}, {0.1, 1, 34}, {0.2, 1, 31}, {0.2, 2, 32}, {0.2, 3, 33}, {0.3, 1, 36}};
  fit = fit_monotone(obs);
  EXPECT_EQ(fit.points[2].n, 3);
  EXPECT_DOUBLE_EQ(fit.points[2].mean_deg, 32.0);
  EXPECT_DOUBLE_EQ(fit.points[1].fitted_deg, 32.5);
  EXPECT_DOUBLE_EQ(fit.points[2].fitted_deg, 32.5);
  // Pooled within-point sd: only the 0.2 point has spread, sd 1 with 2 degrees of freedom.
  EXPECT_EQ(fit.noise_dof, 2);
  EXPECT_DOUBLE_EQ(fit.noise_sd_deg, 1.0);
  for (std::size_t i = 1; i < fit.points.size(); ++i)
    EXPECT_LE(fit.points[i - 1].fitted_deg, fit.points[i].fitted_deg);
}

TEST(Calibration, InverseOfPiecewiseLinearFit) {
  const std::vector<Observation> obs = {{0.0, 1, 20}, {0.2, 1, 40}, {0.4, 1, 40}, {0.5, 1, 45}};
  const auto fit = fit_monotone(obs);
  EXPECT_NEAR(*invert(fit, 30.0), 0.1, 1e-12);
  EXPECT_NEAR(*invert(fit, 40.0), 0.3, 1e-12);  // middle of the flat level set [0.2, 0.4]
  EXPECT_NEAR(*invert(fit, 42.5), 0.45, 1e-12);
  EXPECT_FALSE(invert(fit, 19.0).has_value());
  EXPECT_FALSE(invert(fit, 46.0).has_value());
  EXPECT_NEAR(evaluate(fit, 0.05), 25.0, 1e-12);
  EXPECT_THROW(evaluate(fit, 0.6), std::invalid_argument);  // no extrapolation
}

TEST(Calibration, NoiselessLinearCurveIsRecoveredExactly) {
  int calls = 0;
  auto sim = [&](double mu, std::uint64_t) {
    ++calls;
    return 20.0 + 100.0 * mu;
  };
  CalibrationSettings s;
  s.mu_r_lo = 0.0;
  s.mu_r_hi = 0.3;
  s.seeds_per_point = 2;
  const auto r = calibrate(sim, {35.0, 0.0}, s);
  ASSERT_TRUE(r.mu_r.has_value());
  EXPECT_EQ(r.status, CalibrationStatus::kCalibrated);
  EXPECT_NEAR(*r.mu_r, 0.15, 1e-12);
  EXPECT_NEAR(r.mu_r_low, 0.15, 1e-12);
  EXPECT_NEAR(r.mu_r_high, 0.15, 1e-12);
  EXPECT_EQ(r.simulations, calls);
}

TEST(Calibration, RecoversKnownMuRFromNoisyCurve) {
  // Target: the curve's angle at mu_r = 0.15 (37.84 deg); run-to-run noise 0.4 deg.
  const double mu_true = 0.15;
  const double target = true_angle(mu_true);
  ASSERT_NEAR(true_mu(target), mu_true, 1e-12);
  CalibrationSettings s;
  s.mu_r_lo = 0.0;
  s.mu_r_hi = 0.5;
  s.seeds_per_point = 3;
  s.tolerance_deg = 0.3;
  s.max_simulations = 60;
  s.bootstrap.replicates = 1000;
  int covered = 0;
  const int trials = 20;
  for (int t = 0; t < trials; ++t) {
    int calls = 0;
    std::set<std::pair<double, std::uint64_t>> runs;
    auto sim = [&](double mu, std::uint64_t seed) {
      ++calls;
      EXPECT_TRUE(runs.insert({mu, seed}).second) << "a (mu_r, seed) pair ran twice";
      return true_angle(mu) + noise(t, mu, seed, 0.4);
    };
    const auto r = calibrate(sim, {target, 0.0}, s);
    ASSERT_TRUE(r.mu_r.has_value()) << r.message;
    EXPECT_TRUE(r.status == CalibrationStatus::kCalibrated ||
                r.status == CalibrationStatus::kBudgetSpent);
    EXPECT_EQ(r.simulations, calls);
    EXPECT_EQ(static_cast<int>(r.observations.size() + r.excluded.size()), calls);
    EXPECT_GE(r.excluded.size(), 3u);  // the bracket's search runs were replaced
    EXPECT_LE(calls, s.max_simulations);
    // Close to the truth, and the interval is not absurdly wide: the local slope is about
    // 60 deg per unit mu_r, so 0.4 deg of noise is about 0.007 in mu_r per run.
    EXPECT_NEAR(*r.mu_r, mu_true, 0.03);
    EXPECT_LT(r.mu_r_high - r.mu_r_low, 0.06);
    EXPECT_LE(r.mu_r_low, *r.mu_r);
    EXPECT_GE(r.mu_r_high, *r.mu_r);
    if (r.mu_r_low <= mu_true && mu_true <= r.mu_r_high) ++covered;
  }
  // A 95% interval covers the truth in most trials (binomial: P(<= 15 of 20) < 0.3% at 95%).
  EXPECT_GE(covered, 16) << covered << " of " << trials;
}

TEST(Calibration, ConfirmationReplacesTheBracketsSearchRuns) {
  int calls = 0;
  auto sim = [&](double mu, std::uint64_t seed) {
    ++calls;
    return true_angle(mu) + noise(5, mu, seed, 0.4);
  };
  CalibrationSettings s;
  s.mu_r_lo = 0.0;
  s.mu_r_hi = 0.5;
  const auto r = calibrate(sim, {true_angle(0.15), 0.0}, s);
  ASSERT_TRUE(r.mu_r.has_value());
  ASSERT_FALSE(r.excluded.empty());
  std::set<double> bracket;
  for (const auto& o : r.excluded) bracket.insert(o.mu_r);
  EXPECT_LE(bracket.size(), 2u);
  EXPECT_LE(*bracket.begin(), *r.mu_r);  // the excluded points bracket the answer
  EXPECT_GE(*bracket.rbegin(), *r.mu_r);
  for (double mu : bracket) {
    std::uint64_t max_excluded = 0;
    for (const auto& o : r.excluded)
      if (o.mu_r == mu) max_excluded = std::max(max_excluded, o.seed);
    int fresh = 0;
    for (const auto& o : r.observations) {
      if (o.mu_r != mu) continue;
      EXPECT_GT(o.seed, max_excluded);  // only fresh seeds remain at a bracket point
      ++fresh;
    }
    EXPECT_GE(fresh, s.seeds_per_point);
  }
  EXPECT_EQ(static_cast<int>(r.observations.size() + r.excluded.size()), calls);
  // Without the confirmation nothing is excluded.
  s.confirm_bracket = false;
  const auto u = calibrate(sim, {true_angle(0.15), 0.0}, s);
  EXPECT_TRUE(u.excluded.empty());
}

TEST(Calibration, TargetUncertaintyWidensTheInterval) {
  auto sim = [&](double mu, std::uint64_t seed) {
    return true_angle(mu) + noise(99, mu, seed, 0.3);
  };
  CalibrationSettings s;
  s.mu_r_lo = 0.0;
  s.mu_r_hi = 0.5;
  s.max_simulations = 30;
  const auto a = calibrate(sim, {35.0, 0.0}, s);
  const auto b = calibrate(sim, {35.0, 1.0}, s);
  ASSERT_TRUE(a.mu_r && b.mu_r);
  EXPECT_GT(b.mu_r_high - b.mu_r_low, a.mu_r_high - a.mu_r_low);
}

TEST(Calibration, CannotReachIsReportedNotClamped) {
  int calls = 0;
  auto sim = [&](double mu, std::uint64_t seed) {
    ++calls;
    return true_angle(mu) + noise(7, mu, seed, 0.3);
  };
  CalibrationSettings s;
  s.mu_r_lo = 0.0;
  s.mu_r_hi = 0.5;
  s.seeds_per_point = 3;
  const auto high = calibrate(sim, {60.0, 0.5}, s);  // the curve never exceeds 45 deg
  EXPECT_EQ(high.status, CalibrationStatus::kCannotReachHigh);
  EXPECT_FALSE(high.mu_r.has_value());
  EXPECT_NEAR(high.reachable_high_deg, true_angle(0.5), 1.0);
  EXPECT_NEAR(high.reachable_low_deg, 20.0, 1.0);
  EXPECT_EQ(calls, 6);  // the two range ends, three seeds each, nothing more
  EXPECT_EQ(high.simulations, 6);
  EXPECT_NE(high.message.find("cannot reach"), std::string::npos);
  EXPECT_EQ(to_json(calibration_record(high))["mu_r"], nullptr);
  const auto low = calibrate(sim, {10.0, 0.0}, s);
  EXPECT_EQ(low.status, CalibrationStatus::kCannotReachLow);
  EXPECT_FALSE(low.mu_r.has_value());
}

TEST(Calibration, NonMonotoneNoisyPointIsPooled) {
  // A noisy point (0.2) above its right neighbour (0.3): PAV pools them, the fit stays monotone
  // and the target between gives one crossing.
  std::vector<Observation> obs;
  const std::map<double, std::vector<double>> data = {{0.0, {20.1, 19.9}},
                                                      {0.1, {30.2, 29.8}},
                                                      {0.2, {37.5, 37.7}},
                                                      {0.3, {36.9, 37.1}},
                                                      {0.4, {41.0, 41.0}}};
  for (const auto& [mu, angles] : data)
    for (std::size_t i = 0; i < angles.size(); ++i) obs.push_back({mu, i + 1, angles[i]});
  const auto r = calibrate_observations(obs, {34.0, 0.0});
  ASSERT_TRUE(r.mu_r.has_value());
  EXPECT_DOUBLE_EQ(r.fit.points[2].fitted_deg, 37.3);  // (37.6 + 37.0) / 2
  EXPECT_DOUBLE_EQ(r.fit.points[3].fitted_deg, 37.3);
  // Linear between 30 at 0.1 and 37.3 at 0.2.
  EXPECT_NEAR(*r.mu_r, 0.1 + 0.1 * 4.0 / 7.3, 1e-12);
}

TEST(Calibration, BudgetIsRespected) {
  int calls = 0;
  auto sim = [&](double mu, std::uint64_t seed) {
    ++calls;
    return true_angle(mu) + noise(3, mu, seed, 1.0);
  };
  CalibrationSettings s;
  s.mu_r_lo = 0.0;
  s.mu_r_hi = 0.5;
  s.seeds_per_point = 3;
  s.tolerance_deg = 0.05;  // unreachable with 1 deg noise in 13 runs
  s.max_simulations = 16;  // 6 reserved for the confirmation: ends (6) + one point (3) fit in 10
  const auto r = calibrate(sim, {35.0, 0.0}, s);
  EXPECT_EQ(r.status, CalibrationStatus::kBudgetSpent);
  EXPECT_EQ(calls, 15);
  EXPECT_EQ(r.simulations, 15);
  EXPECT_TRUE(r.mu_r.has_value());
}

TEST(Calibration, BadInputIsRejected) {
  auto sim = [](double mu, std::uint64_t) { return 20.0 + 50.0 * mu; };
  CalibrationSettings s;
  for (double t : {0.0, 90.0, -3.0, 95.0, std::nan("")})
    EXPECT_THROW(calibrate(sim, {t, 0.0}, s), std::invalid_argument) << t;
  EXPECT_THROW(calibrate(sim, {30.0, -1.0}, s), std::invalid_argument);
  EXPECT_THROW(calibrate_observations({}, {30.0, 0.0}), std::invalid_argument);
  EXPECT_THROW(fit_monotone({}), std::invalid_argument);
  EXPECT_THROW(fit_monotone({{0.1, 1, 95.0}}), std::invalid_argument);
  EXPECT_THROW(fit_monotone({{-0.1, 1, 30.0}}), std::invalid_argument);
  CalibrationSettings bad = s;
  bad.mu_r_lo = 0.3;
  bad.mu_r_hi = 0.2;
  EXPECT_THROW(calibrate(sim, {30.0, 0.0}, bad), std::invalid_argument);
  bad = s;
  bad.mu_r_lo = -0.1;
  EXPECT_THROW(calibrate(sim, {30.0, 0.0}, bad), std::invalid_argument);
  bad = s;
  bad.max_simulations = 11;  // below 2 x 3 seeds for the ends + 2 x 3 for the confirmation
  EXPECT_THROW(calibrate(sim, {30.0, 0.0}, bad), std::invalid_argument);
  try {
    calibrate(sim, {95.0, 0.0}, s);
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("95"), std::string::npos) << e.what();
  }
  auto broken = [](double, std::uint64_t) { return std::nan(""); };
  EXPECT_THROW(calibrate(broken, {30.0, 0.0}, s), std::runtime_error);
}

TEST(Calibration, PredictOnAnotherTest) {
  // Test A calibrates; test B (a steeper curve: +2 deg everywhere) is predicted at A's mu_r.
  auto sim_a = [&](double mu, std::uint64_t seed) {
    return true_angle(mu) + noise(11, mu, seed, 0.3);
  };
  CalibrationSettings s;
  s.mu_r_lo = 0.0;
  s.mu_r_hi = 0.5;
  s.max_simulations = 45;
  const auto a = calibrate(sim_a, {true_angle(0.15), 0.0}, s);
  ASSERT_TRUE(a.mu_r.has_value());
  std::vector<Observation> b_obs;
  for (double mu : {0.0, 0.05, 0.1, 0.15, 0.2, 0.3, 0.5})
    for (std::uint64_t seed = 1; seed <= 3; ++seed)
      b_obs.push_back({mu, seed, true_angle(mu) + 2.0 + noise(12, mu, seed, 0.3)});
  const auto fit_b = fit_monotone(b_obs);
  const auto p = predict(fit_b, a);
  EXPECT_NEAR(p.angle_deg, true_angle(0.15) + 2.0, 0.6);
  EXPECT_LE(p.low_deg, p.angle_deg);
  EXPECT_GE(p.high_deg, p.angle_deg);
  EXPECT_LT(p.high_deg - p.low_deg, 3.0);
  EXPECT_GT(p.seed_sd_deg, 0.1);
  const auto q = predict(fit_b, 0.1);
  EXPECT_NEAR(q.angle_deg, true_angle(0.1) + 2.0, 0.6);
  EXPECT_THROW(predict(fit_b, 0.6), std::invalid_argument);
}

}  // namespace
}  // namespace reposetwin::experiments
