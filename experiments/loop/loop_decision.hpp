// Deciding what a residual can be traced to: the observables taken jointly, candidates the data
// cannot tell apart, a residual that looks like a measurement error, and what a design of
// calibration and held-out tests can decide at all. Plain numbers in, records out.
//
// Design note.
//  * Channels. The angle is one observable of a pile; H and D are two more, and effects that
//    move the angle alike can move H and D differently (a smooth plate spreads the pile, a fast
//    lift flattens its top). Each channel c carries, per traced test i, the residual r_ci, its
//    known noise sigma_ci (from its own seed spread) and its sensitivity to mu_r s_ci; a
//    candidate's fingerprint has one column per channel. Rows are standardised by sigma, so the
//    channels share one weighted fit
//        r_ci / sigma_ci = b s_ci / sigma_ci + c f_ci / sigma_ci + N(0, 1),
//    one mu_r correction b (inside the grid) and one strength c for all channels. The loop
//    fits it on simulated surfaces rather than this linear form (loop_joint_surface.hpp: the
//    model and the fingerprint at every mu_r, not their slope and value at one grid point);
//    the JointScore below is that fit's record.
//    A further observable is one more channel; nothing else changes. The crest width (the flat
//    top's width, vision/crest.hpp) is one where the lab data give it (add_optional_channel): a
//    fast lift and a rough plate may lower the angle alike while one widens the crest and the
//    other does not.
//  * Telling candidates apart. With the noise known, chi^2 is -2 log likelihood up to a
//    constant, and every candidate has the same two coefficients, so chi^2_A - chi^2_B is the
//    log likelihood ratio of A against B. Among the candidates that meet the acceptance rule
//    (loop_acceptance.hpp, on the angle) or its joint form, the one with the lowest joint chi^2 is
//    named only when every other is worse by more than min_delta_chi2 (default 4: the named one
//    at least e^2 = 7.4 times as likely). Otherwise the loop reports them as indistinguishable
//    with their numbers and names none: which to believe is for a further observable or test to
//    decide.
//  * Accepted jointly. A candidate whose angle fingerprint alone barely beats mu_r can explain
//    H, D and the crest far better than any other (elongated grains steepen the flanks and
//    narrow the crest, where mu_r raises the apex). Shutting it out on the angle alone would
//    hand its residual to a worse candidate that passed there. So, where two or more channels
//    are traced, a candidate also contends when it meets the rule in its joint form:
//    |c|/se > min_t in the joint fit, and a leave-one-test-out chi^2 below the mu_r correction
//    alone's by more than min_delta_chi2 (the same evidence threshold as the naming). With the
//    angle alone the angle rule stands by itself.
//  * A measurement suspected. A residual nearly the same on every test, that mu_r cannot take
//    up inside its range, is the mark of a measurement (or a declared condition) wrong
//    everywhere, not of a physical effect whose pattern follows the conditions. The offset
//    hypothesis is a pseudo-candidate: a column of ones on the angle (zeros on H and D, which a
//    wrong angle reading leaves alone). It is beyond mu_r's reach when it explains the residual
//    better than the mu_r correction alone by more than min_delta_chi2 (mu_r's correction
//    stops at the grid's bound, or H and D say mu_r did not change); it is flagged when, in
//    addition, its strength is significant (|c|/se > min_t) and no accepted physical candidate
//    beats it by more than min_delta_chi2; then nothing is named.
//  * The design. mu_r is fitted on the calibration tests (one is enough: it is then matched
//    exactly); every test, held-out ones included, is traced (a prediction's residual is
//    out-of-sample evidence); leave-one-test-out over all traced tests keeps the rule honest
//    about the fitted coefficients. describe_design states what a design can and cannot decide.
#pragma once

#include <Eigen/Core>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "experiments/loop/loop_acceptance.hpp"

namespace reposetwin::experiments {

/// One observable over the traced tests.
struct TraceChannel {
  std::string name;                // "angle", "H", "D", "crest"
  std::string units;               // "deg", "mm"
  Eigen::VectorXd residual;        // (n) measured - predicted [units]
  Eigen::VectorXd sigma;           // (n) 1-sigma noise of the residual [units]
  Eigen::VectorXd mu_sensitivity;  // (n) d value / d mu_r [units per unit mu_r]
};

/// The channels traced together, with the mu_r correction's range.
struct JointProblem {
  std::vector<TraceChannel> channels;
  double mu_shift_lo = -std::numeric_limits<double>::infinity();  // [-]
  double mu_shift_hi = std::numeric_limits<double>::infinity();   // [-]
};

/// An observable the lab may not have measured (the crest width, an optional CSV column): its
/// channel over the traced tests and, per test, whether the lab measured it.
struct OptionalChannel {
  TraceChannel channel;
  std::vector<bool> measured;  // (n) the lab measured it on this test
};

/// Appends `obs` to `p` when the lab measured it on every traced test and its residuals, noise
/// and sensitivities are finite (a twin photograph cached by a version that did not record it
/// has none): the channel then joins the joint fit. When no test has it (the column is absent)
/// `p` and `left_out` stay exactly as they were, so the trace is the one without it; otherwise
/// the reason it is not used is appended to `left_out`. Returns whether it was added.
bool add_optional_channel(JointProblem& p, const OptionalChannel& obs,
                          std::vector<std::string>& left_out);

/// One hypothesis fitted to every channel at once.
struct JointScore {
  std::string name;
  bool identifiable = true;         // false: the columns are degenerate
  double coef = 0.0, coef_se = 0.0;  // c and its standard error [-]
  double t = 0.0;                    // |c| / se [-]
  double mu_shift = 0.0;             // b [-]
  bool mu_shift_at_bound = false;
  double chi2 = 0.0;                 // sum of squared standardised residuals [-]
  double loo_chi2 = 0.0;             // the same, each test predicted from the others [-]
  int rows = 0;                      // tests x channels
  std::vector<double> chi2_by_channel;
  std::string out_of_range;  // set by the caller (outside_range): why c lies outside the
                             // effect's range; empty inside it
};

/// What the tracing concludes.
enum class TraceVerdict {
  kNothing,             // no candidate meets the rule
  kNamed,               // one candidate, told from the others
  kIndistinguishable,   // two or more explain the residual alike; none named
  kMeasurementSuspected,  // a uniform offset beyond mu_r's reach; nothing named
};
std::string trace_verdict_name(TraceVerdict v);

struct TraceDecision {
  TraceVerdict verdict = TraceVerdict::kNothing;
  std::string named;                 // kNamed: the candidate
  std::vector<std::string> tied;     // kIndistinguishable: the candidates (best first)
  std::vector<std::string> contenders;  // every candidate that met the rule, by joint chi^2
  std::string statement;             // in words, with the numbers
};

/// Why a fitted strength c +- se (in units of the probe: the value is off + c (probe - off))
/// puts an effect outside its range [lo, hi]: the words with the numbers when even the 2-sigma
/// band stays outside (a camera below the plate, a negative cohesion), else empty. Such a fit
/// says the fingerprint's shape matches the residual, not that the effect can make it.
std::string outside_range(double coef, double coef_se, double off, double probe, double lo,
                          double hi, const std::string& units);

/// Whether `j` meets the acceptance rule in its joint form against the mu_r correction alone
/// (design note): two or more channels, |c|/se > min_t, and a leave-one-test-out chi^2 lower
/// by more than min_delta_chi2.
bool accepted_jointly(const JointScore& j, const JointScore& mu_only, const AcceptanceRule& rule);

/// Decides among `angle` (the candidates' angle scores; the accepted ones compete, and so do the
/// scores of `joint` accepted jointly, each unless the strength it would be refitted with, the
/// angle's or the joint one, lies outside its range) by their joint scores `joint` (matched by name), the
/// offset hypothesis `offset` and the mu_r correction alone `mu_only` (design note). Throws
/// std::invalid_argument when an accepted candidate has no joint score.
TraceDecision decide_trace(const std::vector<CandidateScore>& angle,
                           const std::vector<JointScore>& joint, const JointScore& offset,
                           const JointScore& mu_only, const AcceptanceRule& rule);

/// The candidate an iteration refits. Without a declared hypothesis it is the one `d` names.
/// A user may bring one (reposetwin loop --refit NAME): a lab that believes its rock's shape
/// matters wants that effect refitted and its error after reported even when the trace names
/// another or nothing. The declared candidate is then refitted once, in the first iteration
/// where it is not yet in the model (`used`), whatever the trace decided, and `declared` says so
/// with the trace's own verdict, which stays on record; later iterations follow the trace.
struct RefitPick {
  int index = -1;                       // into `ranked`; -1: nothing to refit
  std::optional<std::string> declared;  // why the pick (or its absence) is the user's
};

/// The pick among `ranked` (the iteration's angle scores) for decision `d` and the declared
/// hypothesis `declared` (empty: none). A declared candidate with no score (its fingerprint was
/// lost in the seed noise or could not be simulated) leaves the trace's pick, with a statement.
RefitPick pick_refit(const std::vector<CandidateScore>& ranked, const TraceDecision& d,
                     const std::string& declared, const std::set<std::string>& used);

/// What a design of calibration and held-out tests can decide.
struct DesignRecord {
  int n_calibrate = 0, n_validate = 0;
  bool can_trace = false;   // enough tests for a leave-one-out check of an effect
  bool refit_on_all = false;  // the refit of (mu_r, effect) uses every test
  std::vector<std::string> can, cannot;  // statements
};

/// The statement for `n_calibrate` (>= 1) and `n_validate` tests. Throws std::invalid_argument
/// when n_calibrate < 1.
DesignRecord describe_design(int n_calibrate, int n_validate);

nlohmann::json to_json(const JointScore& s);
nlohmann::json to_json(const TraceDecision& d);
nlohmann::json to_json(const DesignRecord& d);
JointScore joint_score_from_json(const nlohmann::json& j);
TraceDecision trace_decision_from_json(const nlohmann::json& j);
DesignRecord design_record_from_json(const nlohmann::json& j);

}  // namespace reposetwin::experiments
