// Reports: a self-contained HTML page with plots (gnuplot) and tables for a run, a campaign or
// a calibration folder.
//
// Design note. A report only reads result files (never reruns anything), so it can be rebuilt
// at any time from a folder a campaign is still filling. Every case is listed with its inputs
// (overrides, seeds) and provenance; every angle appears with the method that measured it,
// because atan(2H/D) from an image, atan(2H/D) from particle positions and the flank angle differ
// on the same heap. Plots are made by gnuplot (pngcairo) from data files written beside them
// (gnuplot.hpp). The page layout lives in mustache templates (templates.cpp) filled from typed
// page data (html.hpp); the loop's page (write_loop_html, loop_report.hpp) uses the same skeleton,
// table, plotting and number formats (format.hpp).
//
// Paper comparison. Over one or several calibration folders (calibration.json, and
// predictions.json when the campaign predicted other tests) the report lays our results beside
// the paper's Table 3, read from data/paper/table3_calibration.csv and table1_lab_tests.csv (never
// copied into code): one row per calibration and per prediction, joined to the paper by the Table 1
// sample number the campaign file states (table1_sample). A calibration's angle is the mean of the
// runs at the calibrated mu_r when the campaign ran the calibration test there (a [[predict]] of
// the same scene, marked "check"), else the fit's value there with the pooled seed sd (marked
// "fit"). The caption states both mu_r conventions: ours from sim::kRollingModels for the scene's
// rolling model, the paper's (EDEM) from the CSV's own header.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace reposetwin::experiments {

struct ReportSettings {
  std::string lab_photo;       // a lab photo to measure and show beside the render (optional)
  double lab_mm_per_px = 0.0;  // its scale [mm/px]; 0 = find the scale bar in the photo
  std::string title;           // default: the folder's campaign or scene name
  std::string paper_dir;       // folder of the paper's CSVs; "" = search for data/paper upwards
                               // from each calibration's campaign file, then from the cwd
};

/// Builds DIR/report/index.html (+ PNGs and data files) and returns the summary it shows
/// (per case: seeds, mean and spread of the image and particle angles; the paper comparison for a
/// calibration). A folder holding no results itself but sub-folders with calibration.json (a
/// parent of several calibrations) gets the comparison report over them. Throws InputError when
/// the folder holds no run, campaign or calibration results.
nlohmann::json build_report(const std::string& dir, const ReportSettings& settings = {});

/// The one line `reposetwin report` prints: the calibrated mu_r and its interval (or why there is
/// none), else a run's or a case's angle (or the counts of a campaign's cases and the runs
/// without an angle by reason), then "; report PAGE". `summary` is what build_report returned.
std::string report_line(const nlohmann::json& summary, const std::string& page);

/// Where build_report(dir) writes its page: DIR/index.html for a loop folder (loop.json and no
/// other results; the page the loop itself writes), DIR/report/index.html otherwise.
std::string report_page(const std::string& dir);

/// Builds OUT_DIR/report/index.html over several run, campaign or calibration folders: the paper
/// comparison over the calibration folders among them, with a link to each folder's own report
/// (built too). Throws InputError if a folder holds no results.
nlohmann::json build_report(const std::vector<std::string>& dirs, const std::string& out_dir,
                            const ReportSettings& settings = {});

/// A CSV file of data/paper/: '#' lines skipped, the first other line the header. Returns one
/// object per row, field -> text. Throws InputError naming the file (and line) if unreadable or
/// a row has the wrong number of fields.
std::vector<nlohmann::json> read_paper_csv(const std::string& path);

/// The comparison of our calibrations and predictions with the paper's Table 3 (see the design
/// note): {"rows": [...], "paper_dir", "conventions"}. `paper_dir` "" searches as ReportSettings.
/// Each row: kind ("calibration" or "prediction"), sample, source folder, the paper's d_max, mass,
/// measured angle (Table 1), mu_r and EDEM angle (Table 3), our mu_r with its 95% interval, our
/// angle mean and seed sd with how it was obtained, |ours - measured| and the simulations used.
nlohmann::json paper_comparison(const std::vector<std::string>& calibration_dirs,
                                const std::string& paper_dir = "");

}  // namespace reposetwin::experiments
