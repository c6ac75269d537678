// Reports: a self-contained HTML page with plots (gnuplot) and tables for a run, a campaign or
// a calibration folder.
//
// Design note. A report only reads result files (never reruns anything), so it can be rebuilt
// at any time from a folder a campaign is still filling. Every case is listed with its inputs
// (overrides, seeds) and provenance; every angle appears with the method that measured it,
// because atan(2H/D) from an image, atan(2H/D) from particle positions and the flank angle differ
// on the same heap. Plots are made by gnuplot (pngcairo) from data files written beside them.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace reposetwin::experiments {

struct ReportSettings {
  std::string lab_photo;          // a lab photo to measure and show beside the render (optional)
  double lab_mm_per_px = 0.0;     // its scale [mm/px]; 0 = find the scale bar in the photo
  std::string title;              // default: the folder's campaign or scene name
};

/// Builds DIR/report/index.html (+ PNGs and data files) and returns the summary it shows
/// (per case: seeds, mean and spread of the image and particle angles). Throws InputError when
/// the folder holds no run, campaign or calibration results.
nlohmann::json build_report(const std::string& dir, const ReportSettings& settings = {});

}  // namespace reposetwin::experiments
