// The calibration and prediction sections of a report: calibration.json and predictions.json as
// tables a person reads, and the calibration plot with its fitted curve and calibrated mu_r.
//
// Design note. The page never pastes a result file: each field the calibration wrote becomes a
// named row (with its unit) or a column, and the file itself is linked for whoever wants every
// digit. The plot draws the monotone fit as the calibration used it, piecewise linear through the
// fitted points of its record (calibration/calibration.hpp), so the curve on the page is the one
// that was inverted; the calibrated mu_r is a vertical line in its 95% interval band, the target a
// horizontal line, and the check runs at the calibrated mu_r their own points.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "experiments/calibration/calibration_file.hpp"

namespace reposetwin::experiments::report {

/// The calibration plot of the calibration `cal` (runs, the monotone fit, the target, the
/// calibrated mu_r in its interval band, the check runs of `predictions` at it): writes
/// out/STEM.png with its script STEM.gp and data STEM_*.dat. Returns false when there is
/// nothing to plot; throws when gnuplot fails (gnuplot.hpp).
bool calibration_plot(const CalibrationRecord& cal, const nlohmann::json& predictions,
                      const std::filesystem::path& out, const std::string& stem);

/// The calibration section for the calibration `cal`; writes the plot (script, data, PNG) into
/// `out`. `predictions` (predictions.json, or null) gives the check runs at the calibrated mu_r.
/// `link` is calibration.json relative to `out`.
std::string calibration_section(const CalibrationRecord& cal, const nlohmann::json& predictions,
                                const std::filesystem::path& out, const std::string& link);

/// The predictions section for predictions.json; `link` is that file relative to the page.
std::string predictions_section(const nlohmann::json& predictions, const std::string& link);

}  // namespace reposetwin::experiments::report
