// A candidate fitted jointly with mu_r on surfaces, on closed-form responses with known answers:
// data made at (mu_0, c_0) are fitted back exactly where the linear trace at the grid's end
// cannot fit them, the standard error agrees with the spread of fits over noise draws, a mu_r
// beyond the samples stops on the end, and leave-one-out predicts each test from the others.
#include "experiments/loop/loop_joint_surface.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace reposetwin::experiments {
namespace {

constexpr int kTests = 8;
constexpr int kSamples = 61;  // mu_r 0.1 to 0.4 in steps of 0.005

std::vector<double> samples() {
  std::vector<double> mu;
  for (int k = 0; k < kSamples; ++k) mu.push_back(0.1 + 0.005 * k);
  return mu;
}

// The model: the angle rises with mu_r and flattens (a pile's response to rolling friction), H
// rises, both with a per-test slope. Rods: their change shrinks as mu_r grows (at mu_r 0.4 the
// grains already stand steep) and changes its pattern over the tests (at high mu_r it splits
// the tests in two, as a plate would), and they lower H where mu_r raises it.
double model_angle(int i, double mu) { return 30.0 + (20.0 + 2.0 * i) * std::sqrt(mu); }
double model_h(int i, double mu) { return 20.0 + (10.0 + 0.5 * i) * mu; }
double rods_angle(int i, double mu) {
  return (1.0 + 0.4 * i) * (0.45 - mu) * 10.0 - 8.0 * mu * (i % 2);
}
double rods_h(int i, double mu) { return -(0.5 + 0.1 * (i % 3)) * (1.0 + 4.0 * mu); }

struct Made {
  SurfaceProblem p;
  SurfaceFingerprint rods;
};

// Data made at (mu0, c0) with rods, plus noise of sd `noise` times sigma when an engine is given.
Made make(double mu0, double c0, double mu_fit, std::mt19937* rng = nullptr) {
  Made m;
  m.p.mu = samples();
  m.p.mu_fit = mu_fit;
  SurfaceChannel angle{"angle", Eigen::VectorXd(kTests), Eigen::VectorXd::Constant(kTests, 0.5),
                       Eigen::MatrixXd(kSamples, kTests)};
  SurfaceChannel h{"H", Eigen::VectorXd(kTests), Eigen::VectorXd::Constant(kTests, 0.3),
                   Eigen::MatrixXd(kSamples, kTests)};
  m.rods = {Eigen::MatrixXd(kSamples, kTests), Eigen::MatrixXd(kSamples, kTests)};
  std::normal_distribution<double> z(0.0, 1.0);
  for (int i = 0; i < kTests; ++i) {
    angle.observed[i] = model_angle(i, mu0) + c0 * rods_angle(i, mu0);
    h.observed[i] = model_h(i, mu0) + c0 * rods_h(i, mu0);
    if (rng) {
      angle.observed[i] += angle.sigma[i] * z(*rng);
      h.observed[i] += h.sigma[i] * z(*rng);
    }
    for (int k = 0; k < kSamples; ++k) {
      const double mu = m.p.mu[static_cast<std::size_t>(k)];
      angle.predicted(k, i) = model_angle(i, mu);
      h.predicted(k, i) = model_h(i, mu);
      m.rods[0](k, i) = rods_angle(i, mu);
      m.rods[1](k, i) = rods_h(i, mu);
    }
  }
  m.p.channels = {angle, h};
  return m;
}

TEST(LoopJointSurface, FitsBackTheValuesTheDataWereMadeAt) {
  const Made m = make(0.25, 0.8, 0.4);
  const JointScore s = score_joint_on_surfaces(m.p, "rods", m.rods);
  EXPECT_TRUE(s.identifiable);
  EXPECT_NEAR(s.mu_shift, 0.25 - 0.4, 1e-9);
  EXPECT_NEAR(s.coef, 0.8, 1e-9);
  EXPECT_NEAR(s.chi2, 0.0, 1e-12);
  EXPECT_NEAR(s.loo_chi2, 0.0, 1e-12);
  EXPECT_FALSE(s.mu_shift_at_bound);
  EXPECT_EQ(s.rows, 2 * kTests);
  ASSERT_EQ(s.chi2_by_channel.size(), 2u);
}

// The reason for surfaces: linearised at mu_r 0.4 (where mu_r alone climbs), the same rods
// leave a residual far beyond its 16 rows' chi^2 (the noise's expectation).
TEST(LoopJointSurface, BeatsTheLinearTraceAtTheGridsEnd) {
  const Made m = make(0.25, 0.8, 0.4);
  const Eigen::Index end = kSamples - 1;
  // The linear trace: every channel's residual at 0.4 over its sigma, stacked, fitted as
  // b s + c f with the slope and the fingerprint taken there, b inside the grid.
  Eigen::VectorXd y(2 * kTests), slope(2 * kTests), f(2 * kTests);
  for (std::size_t c = 0; c < 2; ++c) {
    const SurfaceChannel& ch = m.p.channels[c];
    for (int i = 0; i < kTests; ++i) {
      const Eigen::Index r = static_cast<Eigen::Index>(c) * kTests + i;
      y[r] = (ch.observed[i] - ch.predicted(end, i)) / ch.sigma[i];
      slope[r] = (ch.predicted(end, i) - ch.predicted(end - 1, i)) / 0.005 / ch.sigma[i];
      f[r] = m.rods[c](end, i) / ch.sigma[i];
    }
  }
  const BoundedFit linear =
      bounded_fit(slope, &f, y, Eigen::VectorXd::Ones(2 * kTests), 0.1 - 0.4, 0.0);
  const JointScore surface = score_joint_on_surfaces(m.p, "rods", m.rods);
  EXPECT_GT(linear.chi2, 4.0 * surface.rows);
  EXPECT_LT(surface.chi2, 1e-9);
}

TEST(LoopJointSurface, MuAloneAndTheOffsetAreFittedOnTheSameSurfaces) {
  // Made at mu 0.3 without rods: mu alone fits it exactly, on a sample.
  const Made m = make(0.3, 0.0, 0.2);
  const JointScore mu_only = score_joint_on_surfaces(m.p, "mu_r only", {});
  EXPECT_NEAR(mu_only.mu_shift, 0.1, 1e-9);
  EXPECT_NEAR(mu_only.chi2, 0.0, 1e-12);
  EXPECT_EQ(mu_only.coef, 0.0);
  // A uniform 3-deg offset on the angle at mu 0.3: the offset fits it, c = 3.
  Made off = m;
  off.p.channels[0].observed.array() += 3.0;
  const JointScore o = score_offset_on_surfaces(off.p);
  EXPECT_NEAR(o.coef, 3.0, 1e-9);
  EXPECT_NEAR(o.chi2, 0.0, 1e-12);
  EXPECT_GT(score_joint_on_surfaces(off.p, "mu_r only", {}).chi2, 10.0);
}

// The Gauss-Newton standard error of c against the spread of fits over 400 noise draws.
TEST(LoopJointSurface, StandardErrorMatchesTheSpreadOverNoiseDraws) {
  std::mt19937 rng(12345);
  std::vector<double> c;
  double se = 0.0;
  for (int d = 0; d < 400; ++d) {
    const Made m = make(0.25, 0.8, 0.4, &rng);
    const JointScore s = score_joint_on_surfaces(m.p, "rods", m.rods);
    ASSERT_TRUE(s.identifiable);
    c.push_back(s.coef);
    se += s.coef_se / 400.0;
  }
  double mean = 0.0, var = 0.0;
  for (double x : c) mean += x / c.size();
  for (double x : c) var += (x - mean) * (x - mean) / (c.size() - 1);
  EXPECT_NEAR(mean, 0.8, 3.0 * std::sqrt(var / c.size()) + 0.01);
  EXPECT_NEAR(std::sqrt(var) / se, 1.0, 0.15);
}

TEST(LoopJointSurface, MuBeyondTheSamplesStopsOnTheEnd) {
  // Made at mu 0.5 without rods: beyond the samples (0.1-0.4).
  const Made m = make(0.5, 0.0, 0.4);
  const JointScore s = score_joint_on_surfaces(m.p, "rods", m.rods);
  EXPECT_TRUE(s.mu_shift_at_bound);
  EXPECT_NEAR(s.mu_shift, 0.0, 1e-12);
  // On the end c's error is of c alone: 1 / |F / sigma| there.
  double ff = 0.0;
  for (std::size_t c = 0; c < 2; ++c)
    for (int i = 0; i < kTests; ++i)
      ff += std::pow(m.rods[c](kSamples - 1, i) / m.p.channels[c].sigma[i], 2);
  EXPECT_NEAR(s.coef_se, 1.0 / std::sqrt(ff), 1e-12);
}

TEST(LoopJointSurface, LeaveOneOutPredictsEachTestFromTheOthers) {
  // One test's angle off by 5 deg: leave-one-out charges it in full, the in-sample fit less.
  Made m = make(0.25, 0.8, 0.4);
  m.p.channels[0].observed[3] += 5.0;
  const JointScore s = score_joint_on_surfaces(m.p, "rods", m.rods);
  EXPECT_GT(s.loo_chi2, s.chi2);
  EXPECT_GT(s.loo_chi2, std::pow(5.0 / 0.5, 2) * 0.8);
}

TEST(LoopJointSurface, ZeroFingerprintIsNotIdentifiable) {
  const Made m = make(0.25, 0.0, 0.25);
  const SurfaceFingerprint zero(2, Eigen::MatrixXd::Zero(kSamples, kTests));
  const JointScore s = score_joint_on_surfaces(m.p, "nothing", zero);
  EXPECT_FALSE(s.identifiable);
  EXPECT_EQ(s.coef, 0.0);
  EXPECT_NEAR(s.chi2, 0.0, 1e-12);
}

TEST(LoopJointSurface, RejectsMismatchedSizes) {
  Made m = make(0.25, 0.8, 0.4);
  SurfaceFingerprint short_f = {m.rods[0]};
  EXPECT_THROW(score_joint_on_surfaces(m.p, "rods", short_f), std::invalid_argument);
  m.p.mu[5] = m.p.mu[4];
  EXPECT_THROW(score_joint_on_surfaces(m.p, "rods", m.rods), std::invalid_argument);
}

TEST(LoopJointSurface, InterpolatesBetweenKnownNodesAndHoldsBeyond) {
  const std::vector<double> nodes = {0.1, 0.25, 0.4};
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_DOUBLE_EQ(interpolate_on_nodes(nodes, {1.0, 4.0, 10.0}, 0.175), 2.5);
  EXPECT_DOUBLE_EQ(interpolate_on_nodes(nodes, {1.0, 4.0, 10.0}, 0.05), 1.0);
  EXPECT_DOUBLE_EQ(interpolate_on_nodes(nodes, {1.0, 4.0, 10.0}, 0.5), 10.0);
  // An unknown middle node is bridged by its neighbours.
  EXPECT_NEAR(interpolate_on_nodes(nodes, {1.0, nan, 10.0}, 0.25), 5.5, 1e-12);
  EXPECT_TRUE(std::isnan(interpolate_on_nodes(nodes, {nan, nan, nan}, 0.2)));
  EXPECT_THROW(interpolate_on_nodes(nodes, {1.0}, 0.2), std::invalid_argument);
}

}  // namespace
}  // namespace reposetwin::experiments
