// Closing the loop: calibrate mu_r on measured lab tests, find the residual, trace it to a
// candidate effect the base model lacks, add it, refit, and report the error before and after.
//
// Design note (see also loop_acceptance.hpp for the statistics and the acceptance rule).
//  * Model. Following Kennedy and O'Hagan, measured angle = twin(conditions, mu_r, effects) +
//    discrepancy + noise. The twin's angle is the vision angle of its own photographs of the pile,
//    so measured and simulated angles come through the same measurement, and through the same
//    camera where the lab declares its own (its photos' sidecars: loop_sim.hpp).
//  * Baseline. Every test is simulated on a grid of mu_r values with several seeds (the same seeds
//    for every test and grid point: common random numbers). Per test, a monotone fit of the angle
//    against mu_r (calibration.hpp's fit_monotone) interpolates between the grid points; mu_r is
//    the joint weighted least-squares value over the calibration tests (a fine scan of the fitted
//    curves, so no linearisation), with its standard error from the curves' slopes. H and D are
//    interpolated linearly. Predictions carry the seed standard error sd / sqrt(seeds); the noise
//    of a residual is sqrt(sd^2 / repeats + sd^2 / seeds), sd the pooled seed spread of one pile.
//  * Roles and the grid. mu_r is fitted on the calibration tests (one is enough); every test,
//    the held-out ones included, is traced (loop_decision.hpp's describe_design says what a design
//    can decide; too few tests is a statement in loop.json, not an error). A mu_r on an end of
//    its grid cannot take up what it should, so the grid is extended there (settings.at_bound)
//    before anything is traced, or the loop says why it traces nothing.
//  * Fingerprints. At the grid point nearest the calibrated mu_r, each available candidate is
//    switched on at its probe value with the baseline's seeds; the fingerprint is the mean change
//    of angle (and of H, D and, where the lab measured it, the crest width). Measurement
//    candidates re-photograph the same piles. The probe found there is then simulated at every
//    other grid point too: the fingerprint's surface, on which the trace fits the candidate
//    jointly with mu_r (loop_joint_surface.hpp), so an effect that mu_r partly mimics is not
//    judged where mu_r alone landed. Fingerprints are computed once, on the baseline model, and
//    reused in later iterations (first order). A fingerprint lost in the
//    seed noise (below the seed standard error of a predicted angle, or not standing out of its
//    own noise) is probed again at twice its distance from off, probe_scalings times at most;
//    one still lost is listed as unavailable with the largest probe tried: it could "explain"
//    any residual only with an absurd strength.
//  * Selection: loop_acceptance.hpp (WLS with the mu_r correction bounded to the grid, leave-one-
//    test-out ranking, accept when |c| > 3 se and the LOO RMSE gain beats the seed noise) and
//    loop_decision.hpp (angle, H, D and the crest width jointly: one candidate named only when it
//    beats the others by more than the noise allows, else none; a uniform offset beyond mu_r's
//    reach flagged as a suspected measurement error).
//  * Refit by simulation. The chosen effect's linear estimate p1 = off + c (probe - off) (clamped
//    to its range) is simulated on the whole mu_r grid. The model becomes
//    twin(mu_r, p) = (1 - t) twin_before(mu_r) + t twin_p1(mu_r), t = (p - off) / (p1 - off),
//    i.e. linear in p between two simulated surfaces; (mu_r, t) are fitted jointly (t in closed
//    form for each mu_r of the scan, t limited to [0, 3] and to the effect's range). Residuals
//    are recomputed from this simulated model, and the loop repeats while a candidate is
//    accepted and fewer than max_effects are in. If the refit's simulations cannot be measured
//    (a pile too flat to photograph), the simulated value steps back halfway towards off, twice
//    at most.
//    A threshold effect (a plate that slides only below some friction) breaks the linear
//    estimate: when the simulated response where the strength was fitted misses the traced
//    strength by more than half, the value is refined by secant steps between the known responses
//    (off, probe, trials), twice at most, and the trial with the lowest calibration RMSE is kept.
//    The simulations must confirm the tracing: an effect whose joint refit lands at t = 0, or
//    whose simulated model does not lower the calibration RMSE by more than the seed standard
//    error of a prediction, is not chosen (recorded under not_confirmed with the reason).
//  * Caching and resuming: loop_sim.hpp. loop.json (atomic) is written last; an existing one is
//    never overwritten without `force`.
//  * Code. run_loop (loop.cpp) reads as the list of these stages, each a free function of
//    loop_stages.hpp: check_settings, baseline (simulate, pool the seed noise, calibrate mu_r
//    with its residuals), settle_grid, fingerprint_candidates, then iterate (trace, decide,
//    refit_by_simulation, confirm), final_record, photo_pairs, summarise, and write loop.json.
//    Each takes the immutable LoopContext and returns a typed record of loop_records.hpp; those
//    that pour piles also take the PileStore. loop.json is the records' to_json, made in one
//    place.
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "experiments/campaign/campaign.hpp"
#include "experiments/loop/loop_data.hpp"
#include "experiments/loop/loop_effects.hpp"
#include "experiments/loop/loop_sim.hpp"
#include "experiments/loop/loop_acceptance.hpp"

namespace reposetwin::experiments {

/// What the loop does when the calibrated mu_r lands on an end of its grid (docs/loop.md): there
/// mu_r cannot take up what it should, and the rest would be handed to the effects.
enum class GridBound {
  kExtend,  // add grid points beyond the bound (at most grid_extensions), then refuse
  kRefuse,  // trace nothing, saying so
  kTrace,   // trace with the mu_r correction held inside the grid, saying so
};
std::string grid_bound_name(GridBound g);
/// "extend", "refuse" or "trace"; throws InputError naming `option` and the value otherwise.
GridBound parse_grid_bound(const std::string& text, const std::string& option);

/// The range of mu_r the loop may use, declared by the user with its reason (a prior: for rock
/// in our convention, 0.02-0.4). mu_r is never calibrated, extended or refitted outside it; when
/// mu_r alone needs a value beyond it to fit the data, that is evidence for an effect, and the
/// effects are traced with mu_r held inside it rather than the loop stopping at the bound.
/// Undeclared: [0, mu_max], and a bound mu_r reaches is handled by GridBound.
struct MuPrior {
  double lo = 0.0;                                      // [-]
  double hi = std::numeric_limits<double>::infinity();  // [-]
  std::string reason;  // why this range (required when declared)
  bool declared() const { return !reason.empty(); }
};

/// Settings of the loop.
struct LoopSettings {
  std::string mu_key = "contacts.{sample}-{sample}.rolling_friction";  // calibrated scene key
  AngleMeasure angle = AngleMeasure::kImage;  // the angle compared (lab_angles, twin_angle)
  std::vector<double> mu_grid = {0.05, 0.15, 0.3, 0.5};  // mu_r grid, increasing [-]
  std::vector<std::uint64_t> seeds = {1001, 1002, 1003};  // baseline seeds (common numbers)
  ImageVariant image;                      // how the twin photographs its piles
  AcceptanceRule rule;                     // significance and LOO thresholds
  std::vector<std::string> candidates;     // registry names to try; empty = all not opt-in
  GridBound at_bound = GridBound::kExtend;  // mu_r on the grid's bound
  int grid_extensions = 2;                 // grid points added beyond a bound, one at a time
  double mu_max = 1.0;                     // the grid is never extended above this [-]
  MuPrior mu_prior;                        // mu_r's declared range (--mu-range)
  int probe_scalings = 2;                  // doublings of a probe lost in the seed noise
  int max_effects = 2;                     // stop after adding this many effects
  std::string refit;                       // a candidate refitted even when the trace names
                                           // another or none (--refit; loop_decision.hpp's
                                           // pick_refit); empty: the trace decides
  int max_pours = 3;                       // pours per pile when the funnel jams (new seeds)
  double t_max = 3.0;                      // largest t = (p - off) / (p1 - off) of a refit [-]
  int refit_follow_ups = 3;                // trials where a refit's fit lands (loop_refit.cpp)
  int workers = 2;                         // concurrent simulations
  bool progress = true;                    // progress lines on stderr
  bool force = false;                      // overwrite a finished loop.json
  bool html = true;                        // write index.html with gnuplot plots, by `page`
  /// Writes OUT/index.html and its plots from loop.json: report/loop_report.hpp's
  /// write_loop_html, given by the command (the loop sits below report/ and never calls it).
  /// Required when `html` is set.
  std::function<void(const nlohmann::json& loop, const std::string& out_dir)> page;
  std::string cache_dir;                   // simulation cache; default OUT/cache
};

/// The measured data as the loop compares them under `measure`. kImage: as read (the lab's
/// atan(2H/D), typed or measured on its photos). kImageFlank: a test with photos takes the flank
/// angle vision measured on them; a test with a typed angle (or H and D) keeps it, which assumes
/// the lab pile is a full cone (flank = atan(2H/D)), as a protractor reading on a photo does.
/// kParticles: the typed or photo-measured atan(2H/D). A test with photos records the value
/// used in its photo_measurement ("compared_angle"). Throws InputError for kSlice (no lab
/// counterpart) or a photo record without a flank angle.
LabData lab_angles(const LabData& data, AngleMeasure measure);

/// Where the lab's compared angles come from under `measure` (a sentence for loop.json).
std::string lab_angle_source(AngleMeasure measure);

/// The twin's angle of one simulation under `measure` (kImage: vision atan(2H/D); kImageFlank:
/// vision flank; kParticles: atan(2H/D) from particle positions). Throws std::runtime_error for
/// a photograph without a flank angle (cached by an older version) or for kSlice.
double twin_angle(const SimOutcome& o, AngleMeasure measure);

/// Runs the loop on measured data and writes OUT/loop.json (and OUT/index.html). Returns the
/// loop.json content. Throws InputError when OUT already holds a finished loop.json and `force`
/// is not set, when the data have no calibration test, or when the grid or seeds are invalid;
/// std::runtime_error when simulations fail. A design the data cannot decide (too few tests,
/// mu_r on the grid's bound) is not an error: loop.json states what could not be traced.
nlohmann::json run_loop(const LabData& data, const std::string& out_dir,
                        const LoopSettings& settings = {});

/// The plan of the loop's baseline (pile/run_plan.hpp): every test's piles on the mu_r grid
/// with every seed, planned from the test's scene, settings.workers side by side. The
/// fingerprints, refits and extra pours of a jam come on top; the baseline is the part known
/// before anything runs, and already most of the loop's cost on the shipped designs.
BatchPlan plan_loop_baseline(const LabData& data, const LoopSettings& settings);

}  // namespace reposetwin::experiments
