// The joint confidence region of (mu_r, effect) after a refit: a profile likelihood over the
// simulated response surfaces, and what an added lab test would do to it.
//
// Design note. The refit's model is linear in the effect's weight t between two simulated
// surfaces and nonlinear in mu_r (loop.hpp): prediction_k(mu, t) = base_k(mu) + t d_k(mu) for
// every observation k (a test's angle, H, D or crest), each with its known noise sigma_k. At one
// mu_r the chi^2 is therefore a quadratic in t,
//     chi2(mu, t) = syy(mu) - 2 t sdy(mu) + t^2 sdd(mu),
// with syy = sum w y^2, sdy = sum w d y, sdd = sum w d^2 (y = observed - base, w = 1/sigma^2),
// so a scan over mu_r of these three sums is the whole likelihood surface, exactly (no
// linearisation in t, none in mu_r beyond the scan's step). The region at level L is the set
// chi2 <= chi2_min + q, q the chi^2 quantile with two degrees of freedom (5.99 at 95%, Wilks);
// its extent in mu_r and in t is read off the scan, per mu_r in closed form.
//  * Noise larger than declared: when chi2_min exceeds its degrees of freedom (n - 2) the model
//    or the noise is worse than stated, and q is scaled by chi2_min / (n - 2) (the usual
//    quasi-likelihood widening), never narrowed below the stated noise.
//  * Not separated: mu_r and the effect both move the piles, and where their changes are nearly
//    proportional the data fix a combination of them, not each. The region says so when the
//    correlation (from the curvature at the optimum) exceeds 0.9 in magnitude or the region
//    reaches a bound of mu_r's declared range or of t's; the interval is then reported to that
//    bound, widened, never cut to the optimum's neighbourhood.
//  * What would separate them: an added test j with sensitivities (dmu_j, dt_j) / sigma_j adds
//    its outer product to the Fisher information J^T J; the expected area of the region scales as
//    det(info)^(-1/2), and each interval as sqrt of the diagonal of info^-1. suggest_next_test
//    ranks candidate tests by the shrink of the effect's interval.
#pragma once

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace reposetwin::experiments {

/// One mu_r of the scan: the three weighted sums that make chi^2(mu, t) (design note).
struct ProfileRow {
  double mu = 0.0;   // [-]
  double syy = 0.0;  // sum w y^2 [-]
  double sdy = 0.0;  // sum w d y [-]
  double sdd = 0.0;  // sum w d^2 [-]
};

/// The joint region of (mu_r, t) at `level`.
struct JointRegion {
  double level = 0.95;
  double mu = 0.0, t = 0.0;  // the joint optimum
  double chi2_min = 0.0;
  int observations = 0;      // n
  double widening = 1.0;     // q scaled by this (>= 1; chi2_min / (n - 2) when above 1) [-]
  double chi2_limit = 0.0;   // the region: chi2(mu, t) <= this [-]
  double mu_lo = 0.0, mu_hi = 0.0;  // the region's extent in mu_r [-]
  double t_lo = 0.0, t_hi = 0.0;    // and in t [-]
  double correlation = 0.0;         // of (mu_r, t) at the optimum, from the curvature [-]
  bool mu_at_bound = false;         // the region reaches a bound of mu_r's range
  bool t_at_bound = false;          // or of t's
  bool separated = true;            // |correlation| <= 0.9 and no bound reached
  std::string statement;            // the above in words
};

/// The profile-likelihood region over the scan `rows` (increasing mu, at least 3), t limited to
/// [t_lo, t_hi], from `observations` values. Throws std::invalid_argument for fewer than 3 rows,
/// fewer than 3 observations or an empty t range.
JointRegion joint_region(const std::vector<ProfileRow>& rows, double t_lo, double t_hi,
                         int observations, double level = 0.95);

/// The region's extent over `rows` at the chi^2 limit `chi2_limit`, t inside [t_lo, t_hi]; none
/// when no row dips below the limit. joint_region reads its own extent so; a refit's other
/// simulated chords are read at the best one's limit (value_region).
struct RegionExtent {
  double mu_lo = 0.0, mu_hi = 0.0;  // [-]
  double t_lo = 0.0, t_hi = 0.0;    // [-]
  bool mu_at_bound = false;         // a row at an end of the scan is inside
  bool t_at_bound = false;          // t reaches t_lo or t_hi
};
std::optional<RegionExtent> region_extent(const std::vector<ProfileRow>& rows, double t_lo,
                                          double t_hi, double chi2_limit);

/// One simulated chord of a refit: the effect at value p mixed in with weight t in [0, t_max],
/// its scan over mu_r and its own region.
struct ChordScan {
  double p = 0.0;
  double t_max = 0.0;
  std::vector<ProfileRow> rows;
  JointRegion region;
};

/// The joint region of (mu_r, the effect's value) over every simulated chord at one likelihood:
/// the limit is that of the chord with the lowest chi2_min (its minimum plus the quantile,
/// widened as joint_region widens it); each chord's t range inside that limit is mapped to values
/// off + t (p - off), and the ranges are joined. A refit whose trials land at different (mu_r,
/// value) pairs with chi^2 alike has a region that holds them all, not only the best trial's chord.
struct ValueRegion {
  double value_lo = 0.0, value_hi = 0.0;  // [effect's units]
  double mu_lo = 0.0, mu_hi = 0.0;        // [-]
  double chi2_limit = 0.0;                // [-]
  int chords = 0;                         // chords with a part inside the limit
  bool mu_at_bound = false;
  bool t_at_bound = false;  // some chord's part reaches its t bound
};
/// Throws std::invalid_argument when `chords` is empty.
ValueRegion value_region(const std::vector<ChordScan>& chords, double off);

/// One added lab test that could be poured next: its name and the Fisher information it adds,
/// the sum over its observations of j j^T, j = (d prediction / d mu_r, d prediction / d t) over
/// the observation's noise, at the optimum.
struct NextTest {
  std::string name;
  Eigen::Matrix2d added = Eigen::Matrix2d::Zero();
  /// The information of one observation with sensitivities (dmu, dt) over its noise.
  static NextTest one(const std::string& name, double dmu, double dt) {
    const Eigen::Vector2d j(dmu, dt);
    return {name, j * j.transpose()};
  }
};

/// The expected shrink of the joint region by adding one test.
struct NextTestGain {
  std::string name;
  double t_interval_ratio = 1.0;   // the effect's 95% interval after over before [-]
  double mu_interval_ratio = 1.0;  // mu_r's [-]
  double area_ratio = 1.0;         // the region's area after over before [-]
};

/// Ranks `candidates` by the effect's interval after adding each to the Fisher information
/// `info` (2 x 2, mu_r then t; J^T J of the data as fitted), best first.
std::vector<NextTestGain> rank_next_tests(const Eigen::Matrix2d& info,
                                          const std::vector<NextTest>& candidates);

nlohmann::json to_json(const JointRegion& r);
JointRegion joint_region_from_json(const nlohmann::json& j);
nlohmann::json to_json(const NextTestGain& g);
NextTestGain next_test_gain_from_json(const nlohmann::json& j);

}  // namespace reposetwin::experiments
