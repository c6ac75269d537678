// What a results folder holds for its report, read once (report.cpp renders it): a single run,
// a campaign's or a calibration's finished runs grouped by case, the calibration record and the
// predictions. A run without a headline is counted by its reason and never enters a mean.
#pragma once

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "experiments/calibration/calibration.hpp"
#include "experiments/calibration/calibration_file.hpp"

namespace reposetwin::experiments::report {

/// One case of the report: its runs' results.
struct CaseRows {
  std::string name;
  std::string scene;  // the scene file of its runs ("" for a single run)
  nlohmann::json overrides;
  std::vector<double> image_deg, flank_deg, particle_deg, slice_deg;
  std::vector<std::string> stops;
  std::map<std::string, int> without_pile;  // runs that formed no pile, by reason
  // Per run, relative to the report's source folder: the pile run's folder, its record
  // (result.json) and its photographs' folder.
  std::vector<std::string> run_dirs, records, image_dirs;
  nlohmann::json provenance;
};

/// Everything a folder holds for its report, read once.
struct FolderResults {
  std::filesystem::path dir;
  std::string title;
  std::vector<CaseRows> cases;  // in the order first met
  std::optional<CalibrationRecord> calibration;  // calibration.json, when the folder has one
  std::optional<nlohmann::json> predictions;
  // A single run folder stopped between its stages (pile/run_state.hpp): what its record says
  // and what is missing; "" for a complete run or another kind of folder. Such a run is listed
  // without an angle, by the reason "incomplete".
  std::string incomplete;
};

/// The statistics of a case's angles [deg].
struct CaseStats {
  SampleStats image, particle, slice, flank;
};

/// Throws InputError naming `dir`, what it is and which folder to report instead when it is
/// part of another command's results rather than a folder of its own: a pile of a pile store
/// (STORE/piles/KEY or its run/, whose photographs and headline the store's caller keeps) or one
/// seed's record of a campaign case (cases/CASE/seed_N). Such a folder has no stage record
/// because it is not a `reposetwin run` folder, which `report` must say rather than call it an
/// incomplete run.
void refuse_part_folder(const std::filesystem::path& dir);
/// A folder is a calibration folder when it holds calibration.json.
bool is_calibration_dir(const std::filesystem::path& d);
/// The folder is a single run's (its result, stage record or checkpoint, and no campaign).
bool is_run_dir(const std::filesystem::path& d);
/// The folder holds a run, a campaign or a calibration.
bool holds_results(const std::filesystem::path& d);
/// A JSON file, or an InputError naming it.
nlohmann::json read_json(const std::filesystem::path& p);
/// Reads every finished run of `dir` (a run, a campaign or a calibration folder); InputError when
/// it holds none. `title` empty: the campaign's name or the folder's.
FolderResults read_folder_results(const std::string& dir, const std::string& title);
CaseStats case_stats(const CaseRows& c);
/// Whether case `c` ran the calibration's own test: its overrides, but the calibrated keys, are a
/// calibration run's ("calib_*"). A prediction of
/// another test at the calibrated mu_r shares the scene but not its conditions (another mass,
/// another funnel), so a render of it is no picture of the test the lab photographed. True when
/// the folder holds no calibration run to compare with.
bool same_test_as_calibration(const FolderResults& f, const CaseRows& c);

/// The data of the "Angles per case" plot, a line a case: index, image mean and sd, particle
/// mean and sd, the label (the case's inputs), flank mean and sd. A measure no run of the case
/// gave is NaN (gnuplot draws no point), never 0; a case none of whose runs gave an angle says
/// so in its label, with its runs' reasons ("no angle: 2 time_limit").
std::string angles_plot_data(const FolderResults& f);

/// The cases as summary.json lists them.
nlohmann::json case_summary(const FolderResults& f);

}  // namespace reposetwin::experiments::report
