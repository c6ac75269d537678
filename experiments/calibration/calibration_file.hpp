// calibration.json as one typed record: what a finished calibration says of its answer.
//
// Design note. `reposetwin calibrate` writes calibration.json and every later command (predict,
// report, export, the paper's page and runs) reads it. It is written by the one to_json of
// CalibrationRecord and read by the one calibration_record_from_json, and the commands work on
// the record's fields, never on the file's keys, so the file's keys are spelled in this file's
// .cpp (and the bracketing driver's working, written and never read, in bracket_calibration.cpp).
//  * Required: what every calibrate writes today, whichever driver: the status and its message,
//    the target, mu_r (a number or null), the reachable range, the simulations, the fit and the
//    observations (with the search runs the confirmation replaced), the campaign, the keys, the
//    mu_r range, the tolerance, the seeds per point, the Table 1 sample (or null), the scene, its
//    rolling model, the angle method and the time it was made. A calibrated mu_r carries its
//    interval, the interval's level and open ends, and the fitted angle with its half-width.
//  * Optional, because files written by earlier versions (results/ holds some) lack them:
//    "method" (absent: the sequential driver), "keys" (absent: the single "key"), "material"
//    (io/calibration_record.hpp; absent before calibrations recorded it, null without a mu_r),
//    "angle" and "code_version" (written by the calibrate command, not by every caller), the
//    lab photos of the target, the bracketing driver's pour counts per mu_r, and the marks a
//    paper run adds to a calibration it reuses ("copied_from", "not_calibrated": the usable point
//    closest to a target it could not reach, which then stands as mu_r with a zero-width
//    interval and no fitted angle). Within the pour counts, "time_limits" and "not_settled"
//    are absent (none counted) in the bracketing records written before they were counted.
//  * Strict where it reads: a top level that is not an object, a required key missing, a value
//    of the wrong type, a status word that is not one of CalibrationStatus, a mu_r without a
//    two-number interval: each an InputError naming the file, the key as written and the value.
//    The interval is not required to hold mu_r: a bootstrap's central 95% need not. Inside a sub-record we write (target, fit, observations, pour counts, the rolling
//    model, not_calibrated, material) an unknown key is refused too, with the nearest known one.
//  * Tolerant at the top level only: the bracketing driver writes its working there (the pours,
//    the seeds, its stop rule's numbers), which no command reads by key. Such keys are kept in
//    `working` as they were written and written back beside the record's own, so a paper run
//    that copies a calibration copies all of it.
//  * The lab photos' vision measurement (target_photos) is kept whole in the same way: the
//    report reads only the photos and how their scale was known, which are typed.
// The order in which from_json reads matters for the message: the status, the target angle and
// the answer (mu_r and its interval) first, then the working, so a record without its answer
// says that before it says anything of the fit.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "experiments/calibration/calibration.hpp"
#include "experiments/io/calibration_record.hpp"
#include "experiments/io/campaign_file.hpp"

namespace reposetwin::experiments {

/// The bracketing driver's pours at one mu_r ("jam_rate_per_mu_r"), by outcome.
struct PourCount {
  double mu_r = 0.0;      // [-]
  int pours = 0;          // runs at this mu_r
  int piles = 0;          // runs that formed a pile
  int jams = 0;           // runs that jammed
  int physics_stops = 0;  // runs the engine stopped
  int time_limits = 0;    // runs the time limit stopped before the pile settled
  int not_settled = 0;    // runs whose last settling ended still moving
  double jam_rate = 0.0;  // jams / pours [-]
  bool in_fit = false;    // the point's piles entered the fit
  bool operator==(const PourCount&) const = default;
};

/// The rolling law behind the calibrated key, as sim::kRollingModels words it. The three texts
/// are empty when the keyword was unknown to the build that calibrated.
struct RollingModelRecord {
  std::string keyword;           // the scene's rolling_model ("epsd", "cdt", ...)
  bool stated_in_scene = false;  // false: the scene format's default
  std::string torque, radius, angular_velocity;
  bool operator==(const RollingModelRecord&) const = default;
};

/// The lab's photos a target angle was measured from, and how their scale was known, so a report
/// measures them again the same way.
struct TargetPhotosRecord {
  std::vector<std::string> photos;           // the photos, as the campaign named them
  std::string camera_sidecar;                // their camera sidecar; empty: none
  std::optional<double> declared_mm_per_px;  // a declared scale [mm/px]; none: from the photo
  nlohmann::json measurement = nlohmann::json::object();  // vision's record of them, kept whole
  bool operator==(const TargetPhotosRecord&) const = default;
};

/// A paper run's mark on a reused calibration that reached no mu_r: the point it predicts at
/// instead, and what the calibration itself said.
struct NotCalibrated {
  CalibrationStatus status = CalibrationStatus::kBudgetSpent;  // the calibration's own
  std::string message;                                         // the calibration's own
  std::string mu_r_basis;  // which point stands as mu_r, and that it is not a calibrated value
  bool operator==(const NotCalibrated&) const = default;
};

/// calibration.json (see the design note).
struct CalibrationRecord {
  // The answer.
  CalibrationStatus status = CalibrationStatus::kBudgetSpent;
  std::string message;         // a sentence explaining the status
  Target target;               // the measured angle it was fitted to [deg]
  std::optional<double> mu_r;  // calibrated mu_r [-]; none when not reached
  double mu_r_lo = 0.0;        // its interval [-] (when mu_r is set)
  double mu_r_hi = 0.0;
  double interval_level = 0.95;                 // coverage of [mu_r_lo, mu_r_hi]
  bool interval_open_low = false;               // the interval reaches the low end of the range
  bool interval_open_high = false;              // the interval reaches the high end of the range
  std::optional<double> fitted_angle_deg;       // the fit at mu_r [deg]
  double fitted_angle_halfwidth_deg = 0.0;      // its 95% half-width [deg]
  std::optional<NotCalibrated> not_calibrated;  // mu_r is a paper run's closest point
  double reachable_low_deg = 0.0;               // fitted angle at the lowest evaluated mu_r [deg]
  double reachable_high_deg = 0.0;              // fitted angle at the highest evaluated mu_r [deg]
  // The working readers show.
  CalibrationMethod method = CalibrationMethod::kSequential;
  int simulations = 0;     // pile runs that produced observations
  std::string fit_method;  // the fit in words
  MonotoneFit fit;
  std::vector<Observation> observations;  // of the final fit
  std::vector<Observation> excluded;      // search runs replaced by fresh seeds
  std::vector<PourCount> pour_counts;     // the bracketing driver's; empty for the sequential
  // The question and where it came from.
  std::string campaign;           // the campaign file
  std::string campaign_name;      // its name
  std::vector<std::string> keys;  // the scene keys set to mu_r (the first is the campaign's key)
  double mu_r_range_lo = 0.0;     // the range searched [-]
  double mu_r_range_hi = 0.0;
  double tolerance_deg = 0.0;  // [deg]
  int seeds_per_point = 0;
  std::optional<int> table1_sample;  // the paper's Table 1 sample it calibrates, if one
  std::string scene;                 // the campaign's scene file
  RollingModelRecord rolling_model;
  std::string angle_method;                         // how the angle is measured, in words
  std::optional<AngleMeasure> angle;                // the measure matched; none: not recorded
  std::optional<TargetPhotosRecord> target_photos;  // when the target was measured from photos
  std::optional<CalibratedMaterial> material;       // when mu_r was reached (and recorded)
  std::string created_utc;                          // when it was written
  std::string code_version;                         // the code that wrote it; empty: not recorded
  std::string copied_from;  // the calibration.json a paper run copied it from; empty: none
  nlohmann::json working = nlohmann::json::object();  // other top-level keys, as written

  /// Whether a mu_r stands in the record (calibrated, or a paper run's closest point).
  bool reached() const { return mu_r.has_value(); }
  bool operator==(const CalibrationRecord&) const = default;
};

/// The status word's status ("calibrated" -> kCalibrated); std::invalid_argument naming the
/// word and the known words otherwise.
CalibrationStatus calibration_status_from_string(const std::string& word);

/// The record's answer and working from a calibration result; the question and provenance fields
/// are the caller's to fill.
CalibrationRecord calibration_record(const CalibrationResult& result);

/// calibration.json's content.
nlohmann::json to_json(const CalibrationRecord& r);

/// The record from calibration.json's content; `file` names it in errors (and places relative
/// paths of the material). Throws InputError naming the file, the key as written and the value
/// (see the design note).
CalibrationRecord calibration_record_from_json(const nlohmann::json& j, const std::string& file);

/// The lab photos' record from the JSON measure_target_photos (campaign_target.hpp) gives a
/// campaign's target_photos; InputError naming `file` and the key for one without its photos.
TargetPhotosRecord target_photos_from_json(const nlohmann::json& j, const std::string& file);

/// Reads the record from `file`: InputError naming the file when it cannot be read, is not
/// JSON, or is not a calibration record.
CalibrationRecord read_calibration_record(const std::string& file);

/// Reads the calibrated material of the calibration in `folder` (its calibration.json). Throws
/// InputError naming the folder or the file for a folder without one, a file that is not a
/// calibration record, a calibration without a calibrated mu_r (its status and message), a
/// record written before calibrations recorded their material, and a base scene that is gone or
/// was edited since.
CalibratedMaterial read_calibrated_material(const std::string& folder);

}  // namespace reposetwin::experiments
