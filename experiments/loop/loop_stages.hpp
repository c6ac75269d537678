// The loop's stages as free functions, the context they read and the store they simulate into;
// internal to the loop's .cpp files. run_loop (loop.cpp) calls them in order; the method is
// loop.hpp's design note.
//
// Design note. What a stage reads is a LoopContext: the data, the settings, the tests by role,
// the design, the mu_r grid and the seed noise. It is a value, fixed once the grid is settled
// (settle_grid returns the context on the settled grid, as a stage returns its record), and every
// stage takes it by const reference, so no stage can change what another one reads. The one
// mutable thing is the PileStore: the pile service's cache and the surfaces simulated so far. It
// is passed by reference, and only to the stages that simulate (baseline, settle_grid,
// fingerprint_candidates, refit_by_simulation, photo_pairs), so a signature says whether a stage
// pours piles.
//
// A Surface is the twin at one setting of the effects: every test's simulated response on the
// mu_r grid. The current model is a weighted mixture of surfaces (the baseline, then one more per
// effect refitted), held by pointer into the surfaces the store owns, so a model is cheap to
// copy while trials are compared. Each stage returns the records of loop_records.hpp (or a
// surface); none builds JSON.
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
  std::vector<double> mu;  // grid [-]
  MonotoneFit fit;         // angle against mu_r
  // Per channel: the seed means per grid point [deg or mm]; a crest no photograph recorded is
  // NaN.
  PerChannel<std::vector<double>> mean;
  PerChannel<std::vector<std::vector<double>>> seeds;  // per channel, grid point and seed
  std::vector<int> clogged;                            // per grid point: pours that formed no pile
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

/// The tests by role (indices into the data's tests).
struct Roles {
  std::vector<std::size_t> calibrate, validate;  // by the data's role
  std::vector<std::size_t> traced;               // the tests traced: all of them
  std::vector<std::size_t> fitted;               // the tests a refit fits (design.refit_on_all)
  /// Whether some fit of mu_r uses test i (it must form piles).
  bool fits(std::size_t i) const;
};

/// The seed noise every residual and prediction carries (loop.hpp's design note).
struct SeedNoise {
  // Per channel: the pooled seed spread of one pile's value [deg or mm] (the crest's 0 when no
  // test has a measured crest), and per test its residual's 1-sigma noise.
  PerChannel<double> sd;
  PerChannel<std::vector<double>> sigma;
  double se = 0.0;              // seed standard error of a predicted angle [deg]
  bool crest_measured = false;  // some test has a measured crest width
};

/// What every stage reads (see the design note). `data` and `settings` outlive the loop.
struct LoopContext {
  const LabData* data = nullptr;
  const LoopSettings* settings = nullptr;
  std::string out;  // the output folder
  Roles roles;
  DesignRecord design;
  std::vector<double> grid;  // the mu_r grid, extended when mu_r sits on a bound
  SeedNoise noise;           // from the baseline on this grid

  const std::vector<LabTest>& tests() const { return data->tests; }
  const LoopSettings& s() const { return *settings; }
  /// Whether the settings trace `e`: named in them, or, when they name none, not opt-in.
  bool selected(const CandidateEffect& e) const;
  /// A progress line on stderr (settings.progress).
  void say(const std::string& message) const;
  /// The lab's value of `channel` for test i [deg or mm].
  double observed(std::size_t i, Channel channel) const;
  /// The 1-sigma noise of test i's residual on `channel` [deg or mm].
  double sigma(std::size_t i, Channel channel) const { return noise.sigma[channel][i]; }
  /// The effect's value in the base model.
  double effect_off(const CandidateEffect& e) const;
  /// One pile's value of `channel`: the angle compared (twin_angle), H, D or the crest width.
  double twin_value(const SimOutcome& o, Channel channel) const;
  /// The grid point nearest mu_r `mu`.
  std::size_t nearest_grid_point(double mu) const;
};

/// The one mutable thing the stages share: the pile service's cache and the surfaces simulated
/// so far, which models point into.
struct PileStore {
  SimCache cache;
  std::vector<std::unique_ptr<Surface>> surfaces;
  /// Keeps `surface` for the rest of the loop and returns it.
  const Surface& keep(Surface surface);
};

/// The calibrated baseline on a grid: the context on that grid with its seed noise, the surface
/// and the calibration's record.
struct Baseline {
  LoopContext ctx;
  const Surface* surface = nullptr;
  BaselineRecord record;
};

/// What the iterations change: the model, its fit and the effects in it.
struct LoopState {
  Model model;
  MuFit fit;
  std::vector<EffectSetting> effects;
  std::set<std::string> used;        // names of the effects in the model
  std::vector<ChosenEffect> chosen;  // in the order they were added
};

/// The fingerprints of the candidates, and those that have none with the reason.
struct Fingerprints {
  std::vector<FingerprintRecord> records;
  std::vector<UnavailableCandidate> unavailable;
};

/// What a decision hands to the refit: the candidate, its traced strength, the value the
/// tracing gives and the channels it is refitted on.
struct RefitPlan {
  const CandidateEffect* effect = nullptr;
  const FingerprintRecord* fingerprint = nullptr;
  double off = 0.0;      // its value in the base model
  double coef = 0.0;     // traced strength, in units of the fingerprint's probe
  double p1 = 0.0;       // the linear estimate, clamped to the range
  // Where the strength was fitted: the fingerprints' grid point for the angle's linear fit, the
  // joint fit's mu_r on the surfaces; and the fingerprint there, per channel and test [-; deg or
  // mm].
  double mu_at = 0.0;
  PerChannel<std::vector<double>> column;
  std::vector<Channel> channels;
  bool declared = false;  // the user's hypothesis picked it (--refit)
};

/// One refit trial: the effect simulated at p on the whole grid and (mu_r, t) fitted jointly.
struct Trial {
  double p = 0.0;         // simulated value
  double fraction = 0.0;  // its response at plan.mu_at, in units of the fingerprint there
  const Surface* surf = nullptr;
  MuFit joint;
  double rmse = 0.0;                 // calibration RMSE of the refitted model [deg]
  Model model;                       // the model with this trial mixed in
  std::vector<std::string> no_pile;  // held-out tests that formed no pile at p
};

/// The refit of one accepted candidate: its trials and the failures on the way.
struct Refit {
  std::vector<Trial> trials;
  std::vector<double> failed;  // values that could not be simulated (no pile, no photo)
  std::string notes;
};

// Building blocks (loop_surface.cpp): piles poured through the store, surfaces and seed noise.
std::vector<SimOutcome> pour(const LoopContext& ctx, PileStore& store,
                             const std::vector<SimRequest>& requests);
Surface simulate_surface(const LoopContext& ctx, PileStore& store,
                         const std::vector<EffectSetting>& effects);
SeedNoise seed_noise(const LoopContext& ctx, const Surface& base);

// The model's fit and residuals (loop_model.cpp). fit_mu fits the tests `tests` on the
// observables `channels` (each residual over its own noise).
MuFit fit_mu(const LoopContext& ctx, const Model& model, const Surface* extra, double t_max,
             const std::vector<std::size_t>& tests,
             const std::vector<Channel>& channels = {Channel::kAngle});
std::vector<ResidualRow> residuals(const LoopContext& ctx, const Model& model, double mu);
double calibration_rmse(const LoopContext& ctx, const Model& model, double mu);

// The stages, in the order run_loop calls them.
/// The settings checked and the context on the settings' grid, before any noise is known
/// (loop_setup.cpp).
LoopContext check_settings(const LabData& data, const std::string& out,
                           const LoopSettings& settings);
/// Every test simulated on the grid without effects, its seed noise and mu_r calibrated
/// (loop_baseline.cpp).
Baseline baseline(const LoopContext& ctx, PileStore& store);
/// The grid extended while mu_r sits on its bound, as the settings allow (loop_baseline.cpp):
/// `base` is replaced by the baseline on the settled grid, whose context every later stage reads.
GridRecord settle_grid(Baseline& base, PileStore& store);
/// The next mu_r the grid grows by while mu_r sits on its `low` or high end, `added` points
/// added so far, or none with the reason it stops there ("" when the settings stop it)
/// (loop_baseline.cpp): the last step's spacing beyond that end while --at-bound extend allows
/// (grid_extensions), never below 0 (or the declared range's low end) nor above mu_max (or its
/// high end); then, with a declared range whose end the grid has not reached, that end itself,
/// whatever --at-bound says, so that mu_r alone needing more than the range is seen as such.
struct GridGrowth {
  std::optional<double> next;  // [-]
  std::string stop;            // why not, when next is empty
};
GridGrowth next_grid_point(const std::vector<double>& grid, bool low, int added,
                           const LoopSettings& s);
/// Why nothing is traced (the design or mu_r on the grid's bound), or nothing (loop_baseline.cpp).
std::optional<std::string> not_traced(const LoopContext& ctx, const GridRecord& grid);
/// The available candidates' fingerprints at grid point `node`, and their probes' at every grid
/// point (loop_fingerprints.cpp).
Fingerprints fingerprint_candidates(const LoopContext& ctx, PileStore& store, const Surface& base,
                                    std::size_t node);
/// The fingerprint's change of `c` for `test` at mu_r `mu`, interpolated on its surface (the
/// record's own grid point when it has none) [deg or mm]; NaN where no grid point has it.
double fingerprint_at(const FingerprintRecord& f, Channel c, std::size_t test, double mu);
/// One iteration: trace, decide, refit, confirm; appends its record to `iterations` and
/// returns whether the loop goes on (loop_iteration.cpp).
bool iterate(const LoopContext& ctx, PileStore& store, int it, LoopState& state,
             const std::vector<FingerprintRecord>& fps, std::size_t node,
             std::vector<IterationRecord>& iterations);
/// The residual of the current model regressed on every unused fingerprint (loop_iteration.cpp).
IterationRecord trace(const LoopContext& ctx, int it, const LoopState& state,
                      const std::vector<FingerprintRecord>& fps);
/// The accepted candidate simulated on the whole grid at its linear estimate, refined by secant
/// steps when its response misses the traced strength, then simulated where the joint fit lands
/// until it lands on a simulated value (loop_refit.cpp).
Refit refit_by_simulation(const LoopContext& ctx, PileStore& store, const RefitPlan& plan,
                          const LoopState& state);
/// The trial with the lowest calibration RMSE (the first of equals); refit.trials not empty
/// (loop_refit.cpp).
const Trial& best_trial(const Refit& refit);
/// The value the refit simulates next: where the best trial's joint fit lands, off + t (p - off)
/// clamped to [lo, hi]; none when that t is within `tolerance` of 1 (the value is the trial's
/// own), when the value is off, one simulated already or one that failed, or when there is no
/// trial.
std::optional<double> follow_up_value(const Refit& refit, double off, double lo, double hi,
                                      double tolerance);
/// Why the simulations do not confirm the best trial, or empty when they do (loop_refit.cpp).
std::string unconfirmed_reason(const LoopContext& ctx, const Trial& best, const LoopState& state);
/// The final model's fit, effects and residuals (loop_iteration.cpp).
FinalRecord final_record(const LoopContext& ctx, const LoopState& state);
/// Per test, the lab's photo (when given) beside a twin photo (loop_photos.cpp).
std::vector<PhotoPair> photo_pairs(const LoopContext& ctx, PileStore& store,
                                   const LoopState& state);
/// How the loop was made (loop_setup.cpp).
LoopProvenance provenance(const LoopContext& ctx, const PileStore& store, const Surface& base);

}  // namespace reposetwin::experiments::loop_detail
