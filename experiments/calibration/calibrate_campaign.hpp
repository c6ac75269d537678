// Calibrate, then predict: the drivers behind the calibrate and predict commands.
//
// Design. run_calibration() drives calibrate_batch() (calibration.hpp), or with method =
// "bracket" calibrate_bracket() (bracket_calibration.hpp: a jammed or engine-stopped run is a
// pour without a pile there, counted per mu_r, never an angle), through run_batch()
// (campaign/campaign.hpp) and writes calibration.json; run_predictions() runs every [[predict]]
// test at the calibrated mu_r (and, unless interval_ends = false, at both ends of its 95%
// interval) through the same resumable pool, and writes predictions.json. A prediction's mu_r
// comes from calibration.json, whose numbers round-trip exactly through JSON, so a resumed or
// predict-only call names the same run folders and reuses every finished run. The interval's
// effect on a prediction is measured by those end runs; with interval_ends = false it is
// estimated by shifting the prediction by the calibration test's own fitted angle change over the
// interval (stated as such in the file). A finished calibration.json is a result: calibrating
// again with another question (target, range, keys or angle) into the same folder needs --force.
#pragma once

#include <functional>
#include <optional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "experiments/calibration/calibration_file.hpp"
#include "experiments/campaign/campaign.hpp"
#include "experiments/pile/run_plan.hpp"

namespace reposetwin::experiments {

/// The angle a calibration or prediction uses from one run's result (the case function's JSON).
/// For a prediction it may return NaN for a run that made no pile (a clogged outlet): such runs
/// are listed and counted (no_pile), never averaged.
using AngleFn = std::function<double(const nlohmann::json& case_result)>;

/// What the calibrate command records beside the numbers, in calibration.json and
/// predictions.json.
struct CalibrateOptions {
  std::string angle_method;           // how the angle is measured, in words
  std::string code_version;           // the code that made them; empty: not recorded
  std::optional<AngleMeasure> angle;  // the measure matched; none: the campaign's, unrecorded
};

/// Keeps only the [[predict]] tests named in `names`, in that order; std::invalid_argument naming
/// the campaign file, the unknown name and the names there are otherwise.
void keep_only_predictions(Campaign& c, const std::vector<std::string>& names);

/// Calibrates the campaign's [calibration] through run_batch (resumable: finished runs are
/// reused) and writes OUT/calibration.json atomically; returns its record. Besides the result it
/// records the campaign (file, name), the keys, the mu_r range, table1_sample, the scene, the
/// scene's rolling model (keyword and the exact law, from sim::kRollingModels) and the
/// calibrated material. Throws std::invalid_argument if the campaign has no [calibration].
CalibrationRecord run_calibration(const Campaign& campaign, const std::string& out_dir,
                                  const CaseFn& case_fn, const AngleFn& angle_of,
                                  const RunnerSettings& runner = {},
                                  const CalibrateOptions& options = {});

/// Reads OUT/calibration.json and checks that it is this campaign's finished calibration (same
/// campaign name, keys, target and mu_r range, and the angle method when `angle_method` is given).
/// Throws std::runtime_error naming the file and the field that differs, InputError for a file
/// that is not a calibration record.
CalibrationRecord read_calibration(const Campaign& campaign, const std::string& out_dir,
                                   const std::string& angle_method = "");

/// Runs every [[predict]] test at the calibration's mu_r (and at its interval ends unless the
/// entry says interval_ends = false) through run_batch, and writes OUT/predictions.json
/// atomically; returns its content: per prediction the angles per seed, mean, seed sd, the
/// measured angle, the error (mean - measured) and the mu_r interval's effect with its method.
/// Throws std::runtime_error if the calibration has no calibrated mu_r (cannot reach).
nlohmann::json run_predictions(const Campaign& campaign, const CalibrationRecord& calibration,
                               const std::string& out_dir, const CaseFn& case_fn,
                               const AngleFn& angle_of, const RunnerSettings& runner = {},
                               const CalibrateOptions& options = {});

/// The angle a calibration fits, by `measure`, from a run's result. A clogged run throws: the
/// sequential driver has no place for a run without a pile (the bracketing driver counts it as
/// a jam before it asks for an angle).
AngleFn calibration_angle(AngleMeasure measure);

/// The angle a prediction reports: NaN for a run that made no pile (listed as no_pile).
AngleFn prediction_angle(AngleMeasure measure);

/// The plan of a calibration and its predictions, before anything runs: at most the budget's
/// calibration runs (its scene at the low end of the range, the largest count of grains) and
/// every [[predict]] run, `workers` at a time, one thread each.
BatchPlan plan_calibration(const Campaign& campaign, int workers);

/// How the calibration searches, in a line for the plan: the range, its order (the two ends
/// first, or a start point) and the seeds per point.
std::string calibration_order_text(const Campaign& campaign);

/// Why a calibration did not reach its target, in numbers (the target against the interval the
/// mu_r range reaches, after how many runs), and what to try, one suggestion a line: the grain
/// shape (blocky grains), the plate friction, the mu_r range, and the flank measure as a declared
/// fallback. Empty when the calibration has a mu_r.
std::string cannot_reach_advice(const Campaign& campaign, const CalibrationRecord& calibration,
                                AngleMeasure measure);

/// A command to run after a calibration, and what it makes.
struct NextStep {
  std::string command;  // a shell command a person can paste, the folder quoted as needed
  std::string what;     // "the page", "the LIGGGHTS deck"
};

/// What to run after the calibration in `folder` (its path as it should appear in the
/// commands): its report, and, when it reached a mu_r, the export of its material. The
/// calibrate command's last line and the calibration's page both say these.
std::vector<NextStep> calibration_next_steps(const std::string& folder, bool reached);

/// What calibrate_and_predict() wrote.
struct CalibrateOutcome {
  CalibrationRecord calibration;              // calibration.json
  std::optional<nlohmann::json> predictions;  // predictions.json's, when predictions ran
  bool reached = false;                      // a calibrated mu_r exists (else: cannot reach)
};

/// The calibrate command: calibrates (or, with `predict_only`, reads the finished calibration),
/// then runs the [[predict]] tests when mu_r was reached. Records the angle measure and the code
/// version in both files.
CalibrateOutcome calibrate_and_predict(const Campaign& campaign, const std::string& out_dir,
                                       AngleMeasure measure, const CaseFn& case_fn,
                                       const RunnerSettings& runner, bool predict_only = false);

}  // namespace reposetwin::experiments
