// The loop's statistics on synthetic numbers with known answers: WLS against the closed form,
// leave-one-out against a direct refit, the acceptance rule on a planted effect and on noise.
#include "experiments/loop/loop_acceptance.hpp"

#include <gtest/gtest.h>

#include <random>

namespace reposetwin::experiments {
namespace {

TEST(LoopTrace, WeightedLeastSquaresMatchesTheClosedFormLine) {
  // y = 2 + 3 x with unit weights: exact recovery, and se of the slope = 1 / sqrt(Sxx).
  Eigen::MatrixXd x(4, 2);
  Eigen::VectorXd y(4), s = Eigen::VectorXd::Ones(4);
  const double xs[] = {0.0, 1.0, 2.0, 3.0};
  for (int i = 0; i < 4; ++i) {
    x(i, 0) = 1.0;
    x(i, 1) = xs[i];
    y[i] = 2.0 + 3.0 * xs[i];
  }
  const WlsFit f = weighted_least_squares(x, y, s);
  EXPECT_NEAR(f.beta[0], 2.0, 1e-12);
  EXPECT_NEAR(f.beta[1], 3.0, 1e-12);
  EXPECT_NEAR(f.se[1], 1.0 / std::sqrt(5.0), 1e-12);  // Sxx = sum (x - 1.5)^2 = 5
  EXPECT_NEAR(f.chi2, 0.0, 1e-20);
}

TEST(LoopTrace, WeightsFollowTheSigmas) {
  // Two measurements of one constant: the weighted mean 1/sigma^2 and its se.
  Eigen::MatrixXd x = Eigen::MatrixXd::Ones(2, 1);
  Eigen::VectorXd y(2), s(2);
  y << 1.0, 4.0;
  s << 1.0, 2.0;
  const WlsFit f = weighted_least_squares(x, y, s);
  EXPECT_NEAR(f.beta[0], (1.0 + 4.0 / 4.0) / (1.0 + 0.25), 1e-12);
  EXPECT_NEAR(f.se[0], 1.0 / std::sqrt(1.25), 1e-12);
}

TEST(LoopTrace, LeaveOneOutEqualsDirectRefits) {
  // For the mean model, the LOO prediction of y_i is the mean of the others.
  Eigen::MatrixXd x = Eigen::MatrixXd::Ones(4, 1);
  Eigen::VectorXd y(4), s = Eigen::VectorXd::Ones(4);
  y << 1.0, 2.0, 4.0, 7.0;
  double sum = 0.0;
  for (int i = 0; i < 4; ++i) {
    const double others = (y.sum() - y[i]) / 3.0;
    sum += (y[i] - others) * (y[i] - others);
  }
  EXPECT_NEAR(loo_rmse(x, y, s), std::sqrt(sum / 4.0), 1e-12);
}

TEST(LoopTrace, BadInputIsRejected) {
  Eigen::MatrixXd x = Eigen::MatrixXd::Ones(3, 2);  // two equal columns: singular
  Eigen::VectorXd y = Eigen::VectorXd::Ones(3), s = Eigen::VectorXd::Ones(3);
  EXPECT_THROW(weighted_least_squares(x, y, s), std::invalid_argument);
  s[1] = 0.0;
  EXPECT_THROW(weighted_least_squares(Eigen::MatrixXd::Ones(3, 1), y, s), std::invalid_argument);
  EXPECT_THROW(weighted_least_squares(Eigen::MatrixXd::Ones(2, 1), y, Eigen::VectorXd::Ones(3)),
               std::invalid_argument);
  TraceProblem p;
  p.residual = Eigen::VectorXd::Zero(2);
  p.sigma = Eigen::VectorXd::Ones(2);
  p.mu_sensitivity = Eigen::VectorXd::Ones(2);
  EXPECT_THROW(score_null(p), std::invalid_argument);
}

// Eight tests with a mu_r sensitivity and two candidate fingerprints; the residual carries
// `strength` x candidate A plus a mu_r offset plus Gaussian noise of sd 1.
TraceProblem planted(double strength, std::uint64_t seed, Eigen::VectorXd& fa,
                     Eigen::VectorXd& fb) {
  const int n = 8;
  TraceProblem p;
  p.residual.resize(n);
  p.sigma = Eigen::VectorXd::Ones(n);
  p.mu_sensitivity.resize(n);
  fa.resize(n);
  fb.resize(n);
  p.seed_noise_deg = 0.5;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  for (int i = 0; i < n; ++i) {
    p.mu_sensitivity[i] = 40.0 + 3.0 * i;          // deg per unit mu_r
    fa[i] = (i % 2 == 0) ? -4.0 : -1.0 + 0.2 * i;  // condition-dependent
    fb[i] = 0.5 * i - 2.0;
    p.residual[i] = strength * fa[i] + 0.02 * p.mu_sensitivity[i] + noise(rng);
  }
  return p;
}

TEST(LoopTrace, ThePlantedEffectIsNamedAndItsStrengthRecovered) {
  Eigen::VectorXd fa, fb;
  const TraceProblem p = planted(2.0, 7, fa, fb);
  const NullScore ns = score_null(p);
  std::vector<CandidateScore> scores = {score_candidate(p, "A", fa, ns),
                                        score_candidate(p, "B", fb, ns)};
  const int best = rank_candidates(scores);
  ASSERT_GE(best, 0);
  EXPECT_EQ(scores[static_cast<std::size_t>(best)].name, "A");
  EXPECT_EQ(scores[0].name, "A");  // ranked first by LOO
  // The estimate lies within 3 standard errors of the truth.
  EXPECT_NEAR(scores[0].coef, 2.0, 3.0 * scores[0].coef_se);
  EXPECT_GT(scores[0].t, 3.0);
  EXPECT_LT(scores[0].loo_rmse, ns.loo_rmse);
}

TEST(LoopTrace, PureNoiseAcceptsNothingInMostDraws) {
  // With no effect, |c|/se > 3 has probability 0.27% per candidate under the known sigma; over
  // 200 draws with two candidates, at most a handful may pass both rules.
  int accepted = 0;
  for (std::uint64_t seed = 1; seed <= 200; ++seed) {
    Eigen::VectorXd fa, fb;
    const TraceProblem p = planted(0.0, seed, fa, fb);
    const NullScore ns = score_null(p);
    std::vector<CandidateScore> scores = {score_candidate(p, "A", fa, ns),
                                          score_candidate(p, "B", fb, ns)};
    if (rank_candidates(scores) >= 0) ++accepted;
  }
  EXPECT_LE(accepted, 4);
}

TEST(LoopTrace, AConstantFingerprintIsAMuShiftNotAnEffect) {
  // A fingerprint proportional to the mu_r sensitivity cannot be told from mu_r: not identifiable.
  Eigen::VectorXd fa, fb;
  const TraceProblem p = planted(2.0, 3, fa, fb);
  const NullScore ns = score_null(p);
  const CandidateScore s = score_candidate(p, "shift", 0.1 * p.mu_sensitivity, ns);
  EXPECT_FALSE(s.accepted);
  EXPECT_NE(s.why.find("not identifiable"), std::string::npos);
}

TEST(LoopTrace, AnOffsetBeyondTheMuRangeIsNotAMuShift) {
  // The residual is -8 deg everywhere plus a small pattern q; the candidate's fingerprint is
  // -6 + 2 q. With mu_r free to move anywhere, b absorbs most of the constant (exactly:
  // c = 0.5, 40 b = -8 + 3, b = -0.125) and the fit is perfect; with mu_r already at the low end
  // of its range (b >= 0), b stays at 0 and c is the one-column fit of the whole residual.
  const int n = 8;
  TraceProblem p;
  p.residual.resize(n);
  p.sigma = Eigen::VectorXd::Ones(n);
  p.mu_sensitivity = Eigen::VectorXd::Constant(n, 40.0);
  p.seed_noise_deg = 0.5;
  Eigen::VectorXd f(n);
  for (int i = 0; i < n; ++i) {
    const double q = (i % 2 == 0) ? 0.3 : -0.3;
    f[i] = -6.0 + 2.0 * q;
    p.residual[i] = -8.0 + q;
  }
  const NullScore free_null = score_null(p);
  EXPECT_NEAR(free_null.mu_shift, -0.2, 1e-9);
  EXPECT_NEAR(free_null.rmse_fit, 0.3, 1e-9);
  const CandidateScore free_score = score_candidate(p, "plate", f, free_null);
  EXPECT_FALSE(free_score.mu_shift_at_bound);
  EXPECT_NEAR(free_score.mu_shift, -0.125, 1e-9);
  EXPECT_NEAR(free_score.coef, 0.5, 1e-9);

  p.mu_shift_lo = 0.0;
  p.mu_shift_hi = 0.25;
  const NullScore bounded_null = score_null(p);
  EXPECT_EQ(bounded_null.mu_shift, 0.0);
  EXPECT_NEAR(bounded_null.rmse_fit, std::sqrt(64.09), 1e-9);  // nothing absorbed
  EXPECT_NEAR(bounded_null.loo_rmse, bounded_null.rmse_fit, 1e-9);
  const CandidateScore s = score_candidate(p, "plate", f, bounded_null);
  EXPECT_TRUE(s.mu_shift_at_bound);
  EXPECT_EQ(s.mu_shift, 0.0);
  EXPECT_NEAR(s.coef, f.dot(p.residual) / f.dot(f), 1e-9);
  EXPECT_NEAR(s.coef_se, 1.0 / f.norm(), 1e-9);  // unit sigmas, the column alone
  EXPECT_TRUE(s.accepted);
  EXPECT_LT(s.loo_rmse, 0.5 * bounded_null.loo_rmse);

  p.mu_shift_lo = 0.01;  // the bounds must allow no shift
  EXPECT_THROW(score_null(p), std::invalid_argument);
}

// The 95% points of chi^2 in the tables: 3.841 (1), 11.070 (5), 18.307 (10), 43.773 (30).
TEST(LoopTrace, ChiSquare95PointMatchesTheTables) {
  EXPECT_NEAR(chi2_95(1), 3.841, 0.025 * 3.841);
  EXPECT_NEAR(chi2_95(5), 11.070, 0.01 * 11.070);
  EXPECT_NEAR(chi2_95(10), 18.307, 0.005 * 18.307);
  EXPECT_NEAR(chi2_95(30), 43.773, 0.002 * 43.773);
  EXPECT_THROW(chi2_95(0), std::invalid_argument);
}

}  // namespace
}  // namespace reposetwin::experiments
