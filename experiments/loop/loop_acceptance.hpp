// Tracing a residual to a candidate effect: weighted least squares, leave-one-test-out error and
// the acceptance rule of the loop (reposetwin loop), on plain numbers.
//
// Design note. After mu_r is calibrated, the residual r_i = measured - predicted angle of test i
// still carries any discrepancy that varies with the test conditions (Kennedy and O'Hagan 2001:
// a constant discrepancy is absorbed by mu_r). A candidate effect j has a fingerprint f_ij: the
// simulated change of test i's angle when the effect is switched on at its probe value, with the
// baseline's seeds (common random numbers cancel most of the packing noise). The residual is
// regressed on the fingerprint with mu_r free,
//     r_i = b s_i + c f_ij + noise_i,      noise_i ~ N(0, sigma_i^2),
// where s_i is the angle's sensitivity to mu_r at test i; b is a mu_r correction, c the effect's
// strength in units of its probe (c = 1: the probe value itself). There is no intercept: a
// constant offset is a mu_r change, not an effect. sigma_i is known from the seeds (the spread
// of one run, i.e. one lab test, plus the standard error of the predicted mean), so the standard
// errors of b and c come from the weights, not from the residual scatter (with five or six tests
// a scatter-based error is itself too noisy to gate on).
//
// The mu_r correction b is bounded: mu_r + b must stay inside the calibrated range (the loop's
// mu_r grid). Within the range a constant offset is a mu_r change; beyond it (a residual of
// -8 deg everywhere when mu_r already sits at the grid's low end) it is not, and an unbounded b
// would absorb an effect's constant part into an impossible mu_r. The bounded fit is exact: the
// least-squares problem is convex with one box-constrained coefficient, so when the unconstrained
// b violates a bound the optimum has b on that bound and the other coefficients are refitted
// with it fixed (their standard errors then come from that fit).
//
// Acceptance rule (both must hold):
//   1. significance: |c| > min_t standard errors (default 3, a 0.3% false alarm per candidate
//      under Gaussian seed noise, so six candidates on a null dataset alarm about 2% of the time);
//   2. prediction: the leave-one-test-out RMSE with the effect is below the no-effect
//      leave-one-test-out RMSE (mu_r correction only) by more than the seed noise, taken as the
//      RMS over tests of the standard error of the predicted angle (the noise that a difference
//      of two model predictions cannot beat).
// Candidates are ranked by their leave-one-out RMSE (lowest first); the best accepted one is
// added. Leave-one-out, not the in-sample fit, decides, because an extra column always lowers
// the in-sample error.
#pragma once

#include <Eigen/Core>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace reposetwin::experiments {

/// A weighted least-squares fit y = X beta with known noise sigma per row.
struct WlsFit {
  Eigen::VectorXd beta;  // (k) coefficients
  Eigen::VectorXd se;    // (k) standard errors from the known sigmas
  double chi2 = 0.0;     // sum of squared standardised residuals [-]
  double rmse = 0.0;     // unweighted RMS of the residuals y - X beta [units of y]
};

/// Fits y = X beta by weighted least squares with weights 1 / sigma^2. Throws
/// std::invalid_argument if the sizes differ, a sigma is not positive and finite, there are fewer
/// rows than columns, or X^T W X is singular (a column is zero or two columns are proportional).
WlsFit weighted_least_squares(const Eigen::MatrixXd& x, const Eigen::VectorXd& y,
                              const Eigen::VectorXd& sigma);

/// The leave-one-out RMSE of the model y = X beta: each row is predicted by the fit on the others.
/// Throws std::invalid_argument as weighted_least_squares does, or when there are not more rows
/// than columns + 1.
double loo_rmse(const Eigen::MatrixXd& x, const Eigen::VectorXd& y, const Eigen::VectorXd& sigma);

/// The 95% point of chi^2 with `dof` degrees of freedom (> 0), by Wilson and Hilferty's cube-root
/// approximation (2.5% low at 1 degree of freedom, within 1% from 5).
double chi2_95(double dof);

/// The acceptance rule's thresholds (see the design note).
struct AcceptanceRule {
  double min_t = 3.0;              // |c| / se(c) must exceed this [-]
  double loo_margin_factor = 1.0;  // LOO gain must exceed this x the seed noise [-]
  double min_delta_chi2 = 4.0;     // a candidate is told from another when its joint chi^2 is
                                   // lower by more than this (loop_decision.hpp) [-]
};

/// The fit y = b s + c f (f optional) with known sigma and b bounded to [lo, hi] (the design
/// note): unconstrained first; if b leaves the range, b is fixed on the violated bound and c
/// refitted alone. Throws std::invalid_argument as weighted_least_squares does.
struct BoundedFit {
  double b = 0.0, c = 0.0, c_se = 0.0, rmse = 0.0;
  double chi2 = 0.0;  // sum of squared standardised residuals [-]
  bool at_bound = false;
};
BoundedFit bounded_fit(const Eigen::VectorXd& s, const Eigen::VectorXd* f, const Eigen::VectorXd& y,
                       const Eigen::VectorXd& sigma, double lo, double hi);

/// The residuals of one loop iteration, on the tests traced (every test, held-out ones included).
struct TraceProblem {
  Eigen::VectorXd residual;        // (n) measured - predicted angle [deg]
  Eigen::VectorXd sigma;           // (n) 1-sigma noise of each residual [deg]
  Eigen::VectorXd mu_sensitivity;  // (n) d angle / d mu_r at the baseline [deg per unit mu_r]
  double seed_noise_deg = 0.0;     // RMS standard error of the predicted angles [deg]
  double mu_shift_lo = -std::numeric_limits<double>::infinity();  // smallest allowed b [-]
  double mu_shift_hi = std::numeric_limits<double>::infinity();   // largest allowed b [-]
};

/// One candidate's fit to the residual.
struct CandidateScore {
  std::string name;
  double coef = 0.0;               // c: the effect's strength in units of its probe [-]
  double coef_se = 0.0;            // its standard error [-]
  double t = 0.0;                  // |c| / se(c) [-]
  double mu_shift = 0.0;           // b: the mu_r correction fitted with it [-]
  bool mu_shift_at_bound = false;  // b sits on a bound of the calibrated range
  double rmse_fit = 0.0;           // in-sample RMSE with the effect [deg]
  double loo_rmse = 0.0;           // leave-one-out RMSE with the effect [deg]
  double loo_gain = 0.0;           // no-effect LOO RMSE - loo_rmse [deg]
  double explained = 0.0;    // 1 - rmse_fit^2 / rmse_before^2: share of the residual's variance
  bool significant = false;  // rule 1
  bool predictive = false;   // rule 2
  bool accepted = false;     // both
  std::string why;           // the rule in words with the numbers
  std::string out_of_range;  // set by the caller: why c lies outside the effect's range
};

/// The no-effect model's scores (mu_r correction only): in-sample and leave-one-out RMSE.
struct NullScore {
  double mu_shift = 0.0;     // b of the best mu_r correction (bounded) [-]
  double rmse_before = 0.0;  // RMS of the residual as given [deg]
  double rmse_fit = 0.0;     // after the best mu_r correction [deg]
  double loo_rmse = 0.0;     // leave-one-out [deg]
};

/// Scores the no-effect model. Throws std::invalid_argument for mismatched sizes or fewer than
/// three tests.
NullScore score_null(const TraceProblem& problem);

/// Scores one candidate with fingerprint `fingerprint` (n) against the null model.
CandidateScore score_candidate(const TraceProblem& problem, const std::string& name,
                               const Eigen::VectorXd& fingerprint, const NullScore& null_score,
                               const AcceptanceRule& rule = {});

/// Sorts candidates by leave-one-out RMSE (best first) and returns the index of the best accepted
/// one in the sorted vector, or -1 if none is accepted.
int rank_candidates(std::vector<CandidateScore>& scores);

/// The root mean square of `v` (0 for an empty vector), summed in order [units of v].
double rmse(const std::vector<double>& v);

nlohmann::json to_json(const CandidateScore& s);
nlohmann::json to_json(const NullScore& s);
/// The scores back from their JSON (loop.json's candidates and null fields).
CandidateScore candidate_score_from_json(const nlohmann::json& j);
NullScore null_score_from_json(const nlohmann::json& j);

}  // namespace reposetwin::experiments
