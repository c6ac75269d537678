// A lab's own calibration from its sheets: the test sheet and the sieve sheet as a campaign.
//
// Design note. A lab keeps a test sheet (one row per pile test: its id, mass, funnel, and the
// side photos or typed H, D, angle) and a sieve sheet. `reposetwin calibrate --tests SHEET.csv
// --sieve SIEVE --scene BASE.toml` takes them as they are and runs the one calibration pipeline
// there is (calibration/calibrate_campaign.hpp): the sheets become the text of an ordinary
// campaign file, which parse_campaign reads with all its checks and the calibrate command runs
// as any campaign. The text is written to OUT/campaign.toml, so the calibration says how it was
// made and reruns as `reposetwin calibrate OUT/campaign.toml`.
//  * The test sheet is read by the loop's reader (loop_data.hpp, the one reader of a lab's test
//    rows; columns in docs/calibration.md) in its calibration form: the base scene is the
//    command's, and the row whose role is `calibrate` (without a role column: the first row) is
//    the calibration target; every other row is a [[predict]] test at the calibrated mu_r.
//  * The calibration row's conditions are the campaign's common overrides, so a prediction
//    row must set every condition the calibration row sets: an empty cell there would silently
//    take the calibration test's value, and is refused, naming the row and the column.
//  * The sieve sheet (CSV or TOML) replaces the base scene's sieve table for every test.
//  * The target is the calibration row's photos (calibration.target_photos, measured by vision
//    as the twin's renders are, with the row's camera sidecar or mm_per_px), or its typed angle,
//    or atan(2H/D) of its typed H and D.
//  * The search is the bracketing driver with the two ends of the mu_r range first
//    (bracket_calibration.hpp, ends_first), two seeds a point, at most four points, so a target
//    the range cannot reach is known after the first two points.
#pragma once

#include <string>

#include "experiments/campaign/campaign.hpp"
#include "experiments/loop/loop_data.hpp"

namespace reposetwin::experiments {

/// What a calibration from the lab's sheets is asked.
struct SheetCalibrationRequest {
  std::string tests_csv;    // the test sheet (CSV), as typed
  std::string sieve_sheet;  // the sieve sheet (CSV or TOML), as typed; empty: the scene's own
  std::string scene;        // the base scene (TOML), as typed
  double mu_r_lo = 0.02;    // the mu_r range searched [-]
  double mu_r_hi = 0.5;
  AngleMeasure angle = AngleMeasure::kImage;  // the twin's angle matched to the lab's
  std::string campaign_file;  // where the campaign text will be written (names it in messages)
};

/// The sheets as a campaign.
struct SheetCampaign {
  LabData tests;      // the test sheet as read (photos measured)
  std::string text;   // the campaign file's text (TOML, absolute paths)
  Campaign campaign;  // parsed from `text`, its target photos measured
};

/// Reads the sheets and makes the campaign (see the design note). Throws InputError naming the
/// file, the row, the column and the value for a bad sheet (a missing or unknown column, a cell
/// that is not a number, a photo path that does not exist, a prediction row without a
/// condition the calibration row sets, no or two calibration rows), before anything runs.
SheetCampaign sheet_campaign(const SheetCalibrationRequest& request);

}  // namespace reposetwin::experiments
