// The records of one loop run: what each stage of run_loop returns, and their JSON.
//
// Design note. The stages of the loop (loop.cpp) hand each other these plain structs; JSON is
// made only at the file edge, by one to_json per record, and loop.json is the to_json of a
// LoopRecord. The JSON field names are those of loop.json (docs/loop.md), which tests and the
// report (report/loop_report.cpp) read. An iteration's `chosen` field is null when nothing was
// chosen, the refit failure when every refit simulation failed, or the chosen effect.
#pragma once

#include <Eigen/Core>
#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "experiments/loop/loop_data.hpp"
#include "experiments/loop/loop_decision.hpp"
#include "experiments/loop/loop_region.hpp"
#include "experiments/loop/loop_acceptance.hpp"

namespace reposetwin::experiments {

/// A joint fit of mu_r (and of the refit's mixing weight t) to the calibration tests.
struct MuFit {
  double mu = 0.0;       // calibrated mu_r [-]
  double mu_se = 0.0;    // its standard error [-]
  double t = 0.0;        // weight of the extra simulated surface (0 without one) [-]
  double t_se = 0.0;     // its standard error [-]
  bool at_edge = false;  // mu sits on an end of the mu_r grid
  // With an extra surface: the joint region of (mu_r, t) over the scan (loop_region.hpp).
  std::optional<JointRegion> region;
  // With an extra surface: the Fisher information of the fitted data at the optimum (mu_r, t)
  // and each fitted test's share of it (its channels), in the order of the tests fitted.
  Eigen::Matrix2d info = Eigen::Matrix2d::Zero();
  std::vector<std::pair<std::size_t, Eigen::Matrix2d>> test_info;
  // With an extra surface: the scan the region was read from, and t's cap, so that the region
  // can be read over several refit trials at one likelihood (value_region). Not in loop.json.
  std::vector<ProfileRow> profile;
  double t_max = 0.0;
};

/// One test's residual under a model at a mu_r.
struct ResidualRow {
  std::string id;
  Role role = Role::kCalibrate;
  double measured_deg = 0.0;            // lab angle as compared [deg]
  double predicted_deg = 0.0;           // twin angle [deg]
  double residual_deg = 0.0;            // measured - predicted [deg]
  double sigma_deg = 0.0;               // 1-sigma noise of the residual [deg]
  double predicted_se_deg = 0.0;        // seed standard error of the prediction [deg]
  double predicted_h_mm = 0.0;          // [mm]
  double predicted_d_mm = 0.0;          // [mm]
  std::optional<double> residual_h_mm;  // when the lab measured H [mm]
  std::optional<double> residual_d_mm;  // when the lab measured D [mm]
  std::optional<double> predicted_crest_mm;  // crest width, when the lab measured it [mm]
  std::optional<double> residual_crest_mm;   // [mm]
  // Why the twin predicts no pile for this held-out test (its pours jammed); empty when it
  // predicts one. Then the predictions and residual are NaN (null in loop.json).
  std::string no_pile;
};

/// RMS residuals by role.
struct RoleRmse {
  double calibrate_deg = 0.0;          // [deg]
  std::optional<double> validate_deg;  // none without validation tests [deg]
  std::size_t n_calibrate = 0;
  std::size_t n_validate = 0;
  std::size_t n_no_pile = 0;  // rows left out: the twin predicts no pile (ResidualRow::no_pile)
};

/// RMS residual of each role over `rows` that have a prediction.
RoleRmse rmse_by_role(const std::vector<ResidualRow>& rows);

/// One test's baseline response on the mu_r grid, with the seeds of the pours that made its
/// piles and the pours that jammed (repeated; a lab pours its tests without jamming).
struct BaselineCurve {
  std::string id;
  std::vector<double> mu;                              // grid [-]
  std::vector<double> angle_deg;                       // seed means per grid point [deg]
  std::vector<std::vector<double>> angle_seeds_deg;    // [grid][seed] [deg]
  std::vector<std::vector<std::uint64_t>> pour_seeds;  // [grid][seed]
  std::vector<int> clogged_pours;                      // per grid point
};

/// The calibrated base model (mu_r only) and its residuals.
struct BaselineRecord {
  MuFit fit;
  double seed_sd_deg = 0.0;  // pooled seed spread of one pile's angle [deg]
  double seed_se_deg = 0.0;  // seed standard error of a predicted angle [deg]
  std::vector<ResidualRow> residuals;
  RoleRmse rmse;
  std::vector<BaselineCurve> curves;
};

/// The observables the loop traces: the angle [deg], H, D and the crest width [mm]. A quantity
/// held per channel is a PerChannel, indexed by the enum, so a new channel is one enumerator
/// (and its name, unit and value in the functions below and LoopContext::twin_value).
enum class Channel { kAngle, kH, kD, kCrest };
inline constexpr std::size_t kChannelCount = 4;
inline constexpr std::array<Channel, kChannelCount> kAllChannels = {Channel::kAngle, Channel::kH,
                                                                    Channel::kD, Channel::kCrest};

/// One T per channel.
template <class T>
struct PerChannel {
  std::array<T, kChannelCount> values{};
  T& operator[](Channel c) { return values[static_cast<std::size_t>(c)]; }
  const T& operator[](Channel c) const { return values[static_cast<std::size_t>(c)]; }
};

/// The channel's name in loop.json and the joint trace (IterationRecord::channels): "angle",
/// "H", "D" or "crest".
const char* channel_name(Channel c);
/// The unit of its values: "deg" for the angle, "mm" for the others.
const char* channel_unit(Channel c);
/// The channel named as channel_name gives it; throws std::logic_error for another name.
Channel channel_from_name(const std::string& name);

/// A candidate's simulated change of every test's angle, H, D and crest at its probe value.
/// A fingerprint at one grid point of its surface.
struct FingerprintNode {
  double mu_r = 0.0;                       // [-]
  PerChannel<std::vector<double>> change;  // per channel, per test [deg or mm]; empty if missing
  std::string missing;                     // why it has none (its pours failed); empty: it has
};

struct FingerprintRecord {
  std::string name;
  double probe = 0.0;  // effect value simulated
  double mu_r = 0.0;   // grid point the probe was chosen at (nearest the calibration) [-]
  // Per channel, per test: the mean change [deg or mm]. The crest's is empty when no test has a
  // measured crest.
  PerChannel<std::vector<double>> change;
  std::vector<double> angle_se_deg;  // per test: the angle change's standard error [deg]
  std::vector<double> probes_tried;  // every probe simulated, the one used last
  // The probe at every grid point (mu_r's above included), so that the candidate is fitted
  // jointly with mu_r across the grid (loop_joint_surface.hpp). Empty in a loop.json written
  // before the loop simulated it.
  std::vector<FingerprintNode> surface;
};

/// The mu_r grid as the loop settled it: extended beyond a bound mu_r landed on, or left.
struct GridRecord {
  std::vector<double> initial, final_grid;  // [-]
  std::vector<double> added;                // points added, in order [-]
  std::string policy;                       // "extend", "refuse" or "trace"
  bool at_bound = false;                    // mu_r still on an end of the final grid
  std::string statement;                    // what was done, in words
  // mu_r's declared range (LoopSettings::mu_prior), when declared, and whether mu_r alone
  // needed a value beyond it (then traced as evidence for an effect, mu_r held inside it).
  std::optional<std::pair<double, double>> prior;
  std::string prior_reason;
  bool beyond_prior = false;
};

/// A candidate left out of the tracing, with the reason.
struct UnavailableCandidate {
  std::string name;
  std::string why;
};

/// One simulated refit value and the joint fit it gave.
struct RefitTrialRecord {
  double simulated_at = 0.0;        // effect value simulated on the grid
  double response_fraction = 0.0;   // response where the strength was fitted / fingerprint
  double t = 0.0;                   // joint fit's weight [-]
  double mu_r = 0.0;                // joint fit's mu_r [-]
  double rmse_calibrate_deg = 0.0;  // calibration RMSE of the refitted model [deg]
  std::vector<std::string> no_pile;  // held-out tests whose pours all jammed at this value
};

/// What the simulated refit of an accepted candidate gave: the trial kept and all trials.
struct RefitSummary {
  std::string name;
  double linear_estimate = 0.0;  // the tracing's value, clamped to the range
  double simulated_at = 0.0;     // the trial kept (lowest calibration RMSE)
  double t = 0.0;                // its joint fit's weight [-]
  double mu_r = 0.0;             // its joint fit's mu_r [-]
  std::vector<RefitTrialRecord> trials;
  std::string refit_notes;  // failed simulations and the steps back
};

/// An effect the simulated refit took into the model.
struct ChosenEffect {
  RefitSummary refit;
  std::string kind, key, units;
  double off = 0.0, probe = 0.0;
  double value = 0.0, value_se = 0.0;  // off + t (simulated_at - off), in `units`
  bool t_at_limit = false;
  double mu_r_se = 0.0;
  bool declared = false;  // refitted as the user's hypothesis (--refit), not named by the trace
  // The joint 95% region of (mu_r, the effect's value) from the refit's profile likelihood,
  // its correlation, and whether the data separate the two (loop_region.hpp).
  std::optional<JointRegion> region;
  double value_lo = 0.0, value_hi = 0.0;  // the region's extent in the effect's value [units]
  // What would separate them: a repeat of each fitted test, ranked by the shrink of the effect's
  // 95% interval it is expected to give (Fisher information at the optimum; loop_region.hpp).
  std::vector<NextTestGain> next_tests;
};

/// An accepted candidate whose simulated refit did not confirm it.
struct NotConfirmed {
  RefitSummary refit;
  double rmse_calibrate_deg = 0.0;  // of the refitted model [deg]
  std::string reason;
};

/// An accepted candidate none of whose refit simulations could be measured.
struct RefitFailed {
  std::string name;
  std::string refit_failed;  // the failures
  double linear_estimate = 0.0;
};

/// One iteration: the tracing of the residual and what became of the best candidate.
struct IterationRecord {
  int iteration = 0;
  double mu_r = 0.0;  // mu_r the residual was taken at [-]
  NullScore null;
  std::vector<CandidateScore> candidates;  // ranked
  std::vector<std::string> channels;       // observables traced jointly
  std::vector<std::string> channels_left_out;  // and why the others were not
  std::vector<std::string> tests_left_out;     // tests not traced: no pile predicted, and why
  std::vector<JointScore> joint;           // per candidate (matched by name)
  std::optional<JointScore> offset;        // the uniform-offset hypothesis
  std::optional<JointScore> mu_only;       // the mu_r correction alone, jointly
  TraceDecision decision;
  std::optional<std::string> stopped;      // an accepted candidate the effect limit stopped
  std::optional<std::string> declared;     // the refit is the user's hypothesis (pick_refit)
  std::optional<ChosenEffect> chosen;
  std::optional<NotConfirmed> not_confirmed;
  std::optional<RefitFailed> refit_failed;
  // The named candidate's refit, set aside because its simulations still misfit the calibration
  // tests beyond their noise while the next contender's refit fits them better (iterate).
  std::optional<NotConfirmed> set_aside;
};

/// The model at the end of the loop.
struct FinalRecord {
  MuFit fit;
  std::vector<ChosenEffect> effects;
  std::vector<ResidualRow> residuals;
  RoleRmse rmse;
};

/// What the loop ran on and with.
struct LoopProvenance {
  std::string code_version, data, angle_measure, angle_method, lab_angle_source;
  std::vector<std::uint64_t> seeds;
  std::vector<double> mu_grid;
  std::string mu_key, image, cache, finished;
  int max_pours = 0;
  std::optional<int> refit_follow_ups;  // absent from a loop.json written before they were made
  std::optional<nlohmann::json> run;  // the first baseline pile run's provenance
  std::vector<std::string> scenes;    // sorted, unique
};

/// The simulations this run started.
struct SimulationCounts {
  int pile_runs_started = 0;
  int photos_started = 0;
  double wall_s = 0.0;
};

/// One photograph shown on the loop's page: the picture and vision's overlay on it, copied into
/// the loop's output folder, with the scale that lets the page show two at one scale.
struct PhotoView {
  std::string photo;       // path relative to the loop's folder (photos/<id>/...)
  std::string overlay;     // the same with vision's measurement drawn on it
  std::string source;      // where it was copied from (the lab's file, the cache's)
  double mm_per_px = 0.0;  // scale at the pile axis [mm/px]
  int width_px = 0;        // [px]
  int height_px = 0;       // [px]
  double angle_deg = 0.0;  // vision atan(2H/D) on this photo [deg]
};

/// A test's lab photo beside one twin photo of the same test (the first measured view of the
/// first seed's pile at the grid point nearest the final mu_r, on the simulated surface that
/// weighs most in the final model, photographed through the lab's cameras when it gave them).
/// A test the lab gave no photo of (a typed angle) has the twin's photo alone.
struct PhotoPair {
  std::string id;                 // the test
  std::optional<PhotoView> lab;   // absent: the lab gave no photo of this test
  std::optional<PhotoView> twin;  // absent: no twin view could be measured (`note` says why)
  double mu_r = 0.0;              // grid point of the twin pile [-]
  std::uint64_t seed = 0;         // its pour's seed
  std::vector<std::pair<std::string, double>> effects;  // effects simulated in it, by name
  std::string note;
};

/// The loop's verdict on its dataset: the trace's (TraceVerdict) when nothing was refitted, or
/// what became of the refit.
enum class Verdict {
  kNothing,               // the trace: no candidate meets the rule
  kNamed,                 // an effect named by the trace, confirmed by its simulated refit
  kIndistinguishable,     // the trace: two or more explain the residual alike; none refitted
  kMeasurementSuspected,  // the trace: a uniform offset beyond mu_r's reach; nothing named
  kDeclared,              // the user's hypothesis (--refit), confirmed by its simulated refit
  kNotConfirmed,          // a refit the simulations did not bear out
  kRefitFailed,           // a refit none of whose simulations could be measured
  kNotTraced,             // nothing traced: the design or the grid did not allow it
};
/// The verdict's word in loop.json ("named", "not_confirmed", ...).
const char* verdict_name(Verdict v);
/// The verdict `text` names; throws std::invalid_argument naming it for any other text.
Verdict parse_verdict(const std::string& text);
/// The loop's verdict when the trace's is the last word.
Verdict verdict_of(TraceVerdict v);

/// The loop's outcome in brief (loop.json's `summary`), decided by summarise.
struct LoopSummary {
  std::optional<std::string> chosen;     // the last effect chosen
  std::optional<Verdict> verdict;        // none: the loop did not iterate
  std::optional<std::string> statement;  // every iteration's decision and its refit, in words
  double rmse_all_before_deg = 0.0;      // every test with a prediction [deg]
  double rmse_all_after_deg = 0.0;       // [deg]
  std::vector<std::string> effects;      // chosen, in order
  double rmse_calibrate_before_deg = 0.0;             // [deg]
  double rmse_calibrate_after_deg = 0.0;              // [deg]
  std::optional<double> rmse_validate_before_deg;     // [deg]
  std::optional<double> rmse_validate_after_deg;      // [deg]
  double reduction = 0.0;                             // 1 - after / before (calibration) [-]
  std::vector<std::string> no_pile_predicted;         // held-out tests the final model jams
};

/// The whole of loop.json.
struct LoopRecord {
  std::vector<LabTest> tests;
  DesignRecord design;
  GridRecord grid;
  std::optional<std::string> not_traced;  // why nothing was traced (design or grid)
  std::vector<UnavailableCandidate> unavailable;
  AcceptanceRule rule;
  BaselineRecord baseline;
  std::vector<FingerprintRecord> fingerprints;
  std::vector<IterationRecord> iterations;
  FinalRecord final_model;
  SimulationCounts simulations;
  LoopProvenance provenance;
  std::vector<PhotoPair> photo_pairs;  // one per test
  LoopSummary summary;                 // summarise(*this), once the rest is filled in
};

/// The loop's summary of a record whose other fields are filled in: the verdict, the statement
/// and the RMSEs before and after. to_json writes it as decided here.
LoopSummary summarise(const LoopRecord& loop);

nlohmann::json to_json(const ResidualRow& r);
nlohmann::json to_json(const RoleRmse& r);
nlohmann::json to_json(const BaselineCurve& c);
nlohmann::json to_json(const BaselineRecord& b);
nlohmann::json to_json(const FingerprintRecord& f);
nlohmann::json to_json(const GridRecord& g);
nlohmann::json to_json(const UnavailableCandidate& u);
nlohmann::json to_json(const RefitTrialRecord& t);
nlohmann::json to_json(const ChosenEffect& c);
nlohmann::json to_json(const NotConfirmed& n);
nlohmann::json to_json(const RefitFailed& f);
nlohmann::json to_json(const IterationRecord& it);
nlohmann::json to_json(const FinalRecord& f);
nlohmann::json to_json(const LoopProvenance& p);
nlohmann::json to_json(const SimulationCounts& s);
nlohmann::json to_json(const PhotoView& v);
nlohmann::json to_json(const PhotoPair& p);
nlohmann::json to_json(const LoopSummary& s);
/// loop.json: the records, the candidate registry, the rule and a summary.
nlohmann::json to_json(const LoopRecord& loop);

/// The records of a list as a JSON array, each written by its to_json.
nlohmann::json to_json_array(const auto& records) {
  nlohmann::json a = nlohmann::json::array();
  for (const auto& r : records) a.push_back(to_json(r));
  return a;
}

/// The acceptance rule in words, as loop.json's rule.text gives it (the code's words, written
/// with every loop.json and not read back).
const char* acceptance_rule_text();

// Each record back from its JSON (loop.json read by a report or a later run). A number written
// as null (NaN) reads back as NaN; a missing or mistyped field throws JsonFieldError
// (io/json_read.hpp) with its JSON pointer within `j`.
// BaselineRecord and FinalRecord carry the fit's fields loop.json holds (mu_r, mu_r_se and, for
// the baseline, mu_r_at_grid_edge); the weight t of a refit is in the chosen effects.
ResidualRow residual_row_from_json(const nlohmann::json& j);
RoleRmse role_rmse_from_json(const nlohmann::json& j);
BaselineCurve baseline_curve_from_json(const nlohmann::json& j);
BaselineRecord baseline_record_from_json(const nlohmann::json& j);
FingerprintRecord fingerprint_record_from_json(const nlohmann::json& j);
GridRecord grid_record_from_json(const nlohmann::json& j);
UnavailableCandidate unavailable_candidate_from_json(const nlohmann::json& j);
RefitTrialRecord refit_trial_record_from_json(const nlohmann::json& j);
ChosenEffect chosen_effect_from_json(const nlohmann::json& j);
NotConfirmed not_confirmed_from_json(const nlohmann::json& j);
RefitFailed refit_failed_from_json(const nlohmann::json& j);
IterationRecord iteration_record_from_json(const nlohmann::json& j);
FinalRecord final_record_from_json(const nlohmann::json& j);
LoopProvenance loop_provenance_from_json(const nlohmann::json& j);
SimulationCounts simulation_counts_from_json(const nlohmann::json& j);
PhotoView photo_view_from_json(const nlohmann::json& j);
PhotoPair photo_pair_from_json(const nlohmann::json& j);
LoopSummary loop_summary_from_json(const nlohmann::json& j);

/// The whole of loop.json, read through the readers above; `path` names the file in messages.
/// Every field a record holds must be there with its type, but for the fields a loop.json
/// written before them lacks, whose absence has one meaning (each reader says which); the
/// candidate registry and the rule's text are the code's and not read back. Throws InputError
/// naming `path`, the JSON pointer of the field and what is wrong with it.
LoopRecord loop_record_from_json(const nlohmann::json& j, const std::string& path);

}  // namespace reposetwin::experiments
