// Calibration of mu_r in a handful of pile runs: bracketing with a monotone fit and common random
// numbers.
//
// Design. A pile run of the paper's sample 1 costs about a core-hour here, so the sequential
// driver of calibration.hpp (both range ends, a secant, then fresh confirmation seeds: 12-16
// runs) is too dear for a whole Table 3. This driver spends runs only where they move the answer:
//  * Common random numbers: every mu_r point is run with the same seeds. A seed fixes the fill
//    (positions, sizes), so a seed's angles at two mu_r differ mostly by the effect of mu_r: the
//    slope and the side of the target come out of two points with little noise, and each seed
//    gives its own curve and its own crossing of the target.
//  * Ends first (ends_first, as a lab's calibration from its sheets runs): the first batch is
//    both ends of the mu_r range, so a target outside what the range reaches is known after
//    those two points (step_out finds no new point: the range end has run) and reported as
//    cannot reach with the reachable interval; otherwise the next point is the fitted crossing.
//  * Bracketing: the first point is mu_r_start (a prior guess, default the middle of the range),
//    the next one a secant step from the fitted slope (the declared slope_guess_deg before two
//    points exist), stretched by a quarter so that it lands beyond the target and brackets it;
//    once the target is bracketed the next point is the fitted crossing itself.
//  * Fit and answer: the isotonic piecewise-linear fit of calibration.hpp over the point means
//    (jammed pours left out); mu_r is its inverse at the target, and the 95% interval is that
//    file's bootstrap over the same observations, so predictions use the same machinery.
//  * Stop rule: the target is bracketed and the uncertainty of mu_r is below mu_r_tolerance. The
//    uncertainty combines (in quadrature) the seed spread, the standard error of the mean of the
//    per-seed crossings (each seed's own angle at the fitted mu_r, from its own isotonic curve,
//    moved to the target along the mean fit's slope: a seed whose own points do not straddle the
//    target still counts), and the interpolation error, the distance between the
//    piecewise-linear crossing and that of a parabola through the three points nearest to it
//    (with two points, half the bracket: a third point is needed to see the curvature). One seed
//    cannot measure its own spread, so at least two seeds are required. Once bracketed, the next
//    point is the crossing, or a tolerance into the bracket from a point already run there.
//  * Jams: a pour whose outlet arched (no pile) has no angle. It is counted in its point's jam
//    rate, never averaged in; a point where more than max_jam_rate of the pours jam is beyond the
//    usable range (the jam rate rises with mu_r), and the search stays below it. A physics stop and
//    a run that a time limit stopped before its pile settled are listed the same way, each as
//    its own reason, and never give an angle.
//  * Measured on the synthetic curve of the tests (a saturating angle(mu_r), slope about 28 deg
//    per unit mu_r at the root, seed offsets of 0.3 deg and 0.15 deg run-to-run noise): the
//    calibration ends in 6 runs with |mu_r - truth| below the 0.02 tolerance (see the test).
#pragma once

#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "experiments/calibration/calibration.hpp"
#include "experiments/calibration/calibration_file.hpp"
#include "experiments/io/calibration_settings.hpp"

namespace reposetwin::experiments {

/// What one pour (a pile run) gave the calibration.
enum class PourOutcome {
  kPile,         // a pile formed: angle_deg is its angle
  kJam,          // the outlet arched or the particles lodged: no pile, no angle
  kPhysicsStop,  // the engine stopped the run (overlap, NaN, escape): no angle
  kTimeLimit,    // procedure.max_time_s stopped the run before its pile settled: no angle
  kNotSettled,   // the last settling reached its own time limit still moving: no angle
};

/// The outcome as a word for files ("pile", "jam", "physics_stop", "time_limit",
/// "not_settled").
std::string to_string(PourOutcome outcome);

/// One pour: where it ran and what it gave.
struct Pour {
  double mu_r = 0.0;       // [-]
  std::uint64_t seed = 0;  // run seed
  PourOutcome outcome = PourOutcome::kPile;
  double angle_deg = 0.0;  // [deg], only for kPile
  std::string detail;      // why it made no pile (free text), empty for a pile
};

/// The pours run at one mu_r.
struct PourPoint {
  double mu_r = 0.0;      // [-]
  int pours = 0;          // runs at this mu_r
  int piles = 0;          // runs that formed a pile
  int jams = 0;           // runs that jammed (no pile)
  int physics_stops = 0;  // runs the engine stopped
  int time_limits = 0;    // runs procedure.max_time_s stopped before the pile settled
  int unsettled = 0;      // runs whose last settling ended still moving
  double jam_rate() const { return pours > 0 ? static_cast<double>(jams) / pours : 0.0; }
};

/// Runs a batch of pours (mu_r, seed) and returns their outcomes in order.
using PourBatchFn =
    std::function<std::vector<Pour>(const std::vector<std::pair<double, std::uint64_t>>&)>;

/// Outcome of a bracketing calibration.
struct BracketCalibration {
  CalibrationResult result;         // fit, mu_r and its 95% interval over the pile runs, status
  std::vector<Pour> pours;          // every pour in the order run
  std::vector<PourPoint> points;    // per mu_r, sorted: pours, piles, jams, physics stops
  std::vector<double> seed_roots;   // each seed's own crossing of the target [-]
  double mu_r_seed_se = 0.0;        // standard error of mu_r from the seed roots' spread [-]
  double mu_r_interpolation = 0.0;  // interpolation error estimate of mu_r [-]
  double mu_r_uncertainty = 0.0;    // the two in quadrature, compared with the tolerance [-]
  bool bracketed = false;           // the fitted curve crosses the target
};

/// Calibrates mu_r by bracketing with common random numbers (see the design note). Throws
/// std::invalid_argument for invalid settings or target, std::runtime_error if a pour that
/// formed a pile returns an angle outside [0, 90] deg or the callback returns the wrong count.
BracketCalibration calibrate_bracket(const PourBatchFn& pour, const Target& target,
                                     const BracketSettings& settings);

/// The calibration file's record of it: calibration_record(result) with the method and the pours
/// per mu_r by outcome, and the driver's working (the pours in order, the seed roots, the
/// uncertainty terms, the settings) kept for the file as it is written.
CalibrationRecord calibration_record(const BracketCalibration& c, const BracketSettings& settings);

}  // namespace reposetwin::experiments
