// The stages of the loop and the simulated model they share; internal to loop.cpp (Loop::run,
// which calls the stages in order, and the stages up to the tracing), loop_model.cpp (the
// model, its mu_r fit and residuals) and loop_refit.cpp (the refit by simulation). The method
// is loop.hpp's design note.
//
// Design note. A Surface is the twin at one setting of the effects: every test's simulated
// response on the mu_r grid. The current model is a weighted mixture of surfaces (the baseline,
// then one more per effect refitted), held by pointer into the surfaces the Loop owns, so a
// model is cheap to copy while trials are compared. Each stage is a member of Loop that takes
// and returns the records of loop_records.hpp (or a surface); none builds JSON.
#pragma once

#include <algorithm>
#include <cstddef>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "experiments/calibration/calibration.hpp"
#include "experiments/loop/loop.hpp"
#include "experiments/loop/loop_decision.hpp"
#include "experiments/loop/loop_records.hpp"

namespace reposetwin::experiments::loop_detail {

/// One test's simulated response on the mu_r grid (one model setting).
struct Curve {
  std::vector<double> mu;                        // grid [-]
  MonotoneFit fit;                               // angle against mu_r
  // Per channel: the seed means per grid point [deg or mm]; a crest no photograph recorded is
  // NaN.
  PerChannel<std::vector<double>> mean;
  PerChannel<std::vector<std::vector<double>>> seeds;  // per channel, grid point and seed
  std::vector<int> clogged;  // per grid point: pours that formed no pile
  // Empty when every pour series formed a pile; else where a held-out test's pours all jammed
  // (a prediction of no pile: the curve has no fit and the model predicts nothing for it).
  std::string no_pile;

  double clamp(double m) const { return std::clamp(m, mu.front(), mu.back()); }
  /// The fitted angle at mu_r m (clamped to the grid) [deg].
  double at(double m) const { return evaluate(fit, clamp(m)); }
  /// y interpolated linearly on the grid at m (clamped).
  double lin(const std::vector<double>& y, double m) const;
};

/// The twin for every test at one setting of the effects: curves on the mu_r grid.
struct Surface {
  std::vector<EffectSetting> effects;
  std::vector<Curve> curve;                               // per test
  std::vector<std::vector<std::vector<SimOutcome>>> raw;  // [test][grid][seed]
};

/// The current model: a mixture of simulated surfaces (loop.hpp's design note). A test one of
/// its weighted surfaces formed no pile for has no prediction: every value is NaN for it.
struct Model {
  std::vector<std::pair<double, const Surface*>> terms;  // weight, surface
  /// Why the model predicts no pile for `test` (the first weighted surface's reason); empty
  /// when it predicts one.
  std::string no_pile(std::size_t test) const;
  /// The predicted value of `channel` at mu_r `mu`: the angle from each curve's monotone fit,
  /// the others interpolated on the grid [deg or mm].
  double value(std::size_t test, double mu, Channel channel) const;
  double angle(std::size_t test, double mu) const { return value(test, mu, Channel::kAngle); }

 private:
  template <class Of>
  double mix(std::size_t test, Of of) const;
};

/// What the iterations change: the model, its fit and the effects in it.
struct LoopState {
  Model model;
  MuFit fit;
  std::vector<EffectSetting> effects;
  std::set<std::string> used;        // names of the effects in the model
  std::vector<ChosenEffect> chosen;  // in the order they were added
};

/// One refit trial: the effect simulated at p on the whole grid and (mu_r, t) fitted jointly.
struct Trial {
  double p = 0.0;         // simulated value
  double fraction = 0.0;  // its response at the node, in units of the probe's fingerprint
  const Surface* surf = nullptr;
  MuFit joint;
  double rmse = 0.0;  // calibration RMSE of the refitted model [deg]
  Model model;        // the model with this trial mixed in
  std::vector<std::string> no_pile;  // held-out tests that formed no pile at p
};

/// The refit of one accepted candidate: its trials and the failures on the way.
struct Refit {
  std::vector<Trial> trials;
  std::string notes;
};

/// The loop over one dataset; run() names the stages in order.
class Loop {
 public:
  Loop(const LabData& data, const std::string& out, const LoopSettings& s);
  nlohmann::json run();

 private:
  void say(const std::string& m) const;
  // The cache's runs, a pour that formed no pile repeated with a new seed (s_.max_pours).
  std::vector<SimOutcome> pour(const std::vector<SimRequest>& req);

  // Stages (loop.cpp).
  void check_settings();
  void check_declared_refit() const;
  bool selected(const CandidateEffect& e) const;
  const Surface& simulate_baseline();
  void set_seed_noise(const Surface& base);
  BaselineRecord calibrate_baseline(const Surface& base) const;
  GridRecord settle_grid(const Surface*& base, BaselineRecord& baseline);
  std::size_t nearest_grid_point(double mu) const;
  std::vector<const CandidateEffect*> available_candidates(
      std::vector<UnavailableCandidate>& unavailable);
  std::vector<FingerprintRecord> fingerprint_candidates(
      const Surface& base, std::size_t node, std::vector<UnavailableCandidate>& unavailable);
  bool iterate(int it, LoopState& state, const std::vector<FingerprintRecord>& fps,
               std::size_t node, std::vector<IterationRecord>& iterations);
  IterationRecord trace(int it, const LoopState& state,
                        const std::vector<FingerprintRecord>& fps) const;
  FinalRecord final_record(const LoopState& state) const;
  // Per test, the lab's photo (when given) beside a twin photo (loop_photos.cpp).
  std::vector<PhotoPair> photo_pairs(const LoopState& state);
  std::vector<std::optional<SimOutcome>> photograph_for_page(
      const std::vector<SimRequest>& requests, std::vector<std::string>& notes);
  LoopProvenance provenance(const Surface& base) const;
  nlohmann::json write(const LoopRecord& rec) const;  // OUT/loop.json and OUT/index.html

  // Building blocks (loop.cpp).
  Surface simulate_surface(const std::vector<EffectSetting>& effects);
  std::vector<SimOutcome> pour_surface(const std::vector<EffectSetting>& effects);
  std::string no_pile_reason(std::size_t i, const std::vector<std::vector<SimOutcome>>& raw) const;
  bool fitted(std::size_t i) const;  // a test some fit of mu_r uses (it must form piles)
  // The tests the model predicts a pile for, of the traced ones; the others into left_out.
  std::vector<std::size_t> traced(const Model& model, std::vector<std::string>& left_out) const;
  std::vector<std::vector<std::size_t>> pour_groups() const;
  void require_pile(std::size_t i, std::size_t j, std::size_t r, const SimOutcome& o) const;
  std::optional<FingerprintRecord> probe_candidate(const CandidateEffect& e, const Surface& base,
                                                   std::size_t node,
                                                   std::vector<UnavailableCandidate>& unavailable);
  FingerprintRecord fingerprint(const CandidateEffect& e, double probe, const Surface& base,
                                std::size_t node, const std::vector<SimOutcome>& on) const;
  std::string untraceable(const FingerprintRecord& f) const;
  JointProblem joint_problem(const LoopState& state, const std::vector<std::size_t>& tests,
                             std::vector<std::string>& left_out) const;
  double mu_slope(const LoopState& state, std::size_t i, Channel channel) const;
  double pooled_seed_sd(const Surface& base, Channel channel) const;
  double twin_value(const SimOutcome& o, Channel channel) const;  // one pile's [deg or mm]

  // The model's fit and residuals (loop_model.cpp). fit_mu fits the tests `tests` on the
  // observables `channels` (each residual over its own noise).
  MuFit fit_mu(const Model& model, const Surface* extra, double t_max,
               const std::vector<std::size_t>& tests,
               const std::vector<Channel>& channels = {Channel::kAngle}) const;
  double observed(std::size_t test, Channel channel) const;  // the lab's value
  double effect_off(const CandidateEffect& e) const;  // its value in the base model
  double noise(std::size_t test, Channel channel) const;  // its residual's 1-sigma noise
  std::vector<ResidualRow> residuals(const Model& model, double mu) const;

  // Refit by simulation (loop_refit.cpp).
  Refit refit_by_simulation(const CandidateEffect& e, double off, double p1, double coef,
                            const FingerprintRecord& fp, double mu_node, const LoopState& state,
                            const std::vector<Channel>& channels);
  bool run_trial(const CandidateEffect& e, double off, double p, const FingerprintRecord& fp,
                 double mu_node, const LoopState& state, const std::vector<Channel>& channels,
                 Refit& refit);
  std::string unconfirmed_reason(const Trial& best, const LoopState& state) const;
  double calibration_rmse(const Model& model, double mu) const;

  const LabData& data_;
  std::string out_;
  const LoopSettings s_;
  SimCache cache_;
  std::vector<double> grid_;            // the mu_r grid, extended when mu_r sits on a bound
  std::vector<std::size_t> cal_, val_;  // test indices by role
  std::vector<std::size_t> trace_;      // the tests traced: all of them
  std::vector<std::size_t> fit_;        // the tests a refit fits (design_.refit_on_all)
  DesignRecord design_;
  // Per channel: the pooled seed spread of one pile's value [deg or mm] (the crest's 0 when no
  // test has a measured crest), and per test its residual's 1-sigma noise.
  PerChannel<double> noise_sd_;
  PerChannel<std::vector<double>> sigma_;
  double seed_se_ = 0.0;                // seed standard error of a predicted angle [deg]
  bool crest_measured_ = false;         // some test has a measured crest width
  std::vector<std::unique_ptr<Surface>> surfaces_;
};

}  // namespace reposetwin::experiments::loop_detail
