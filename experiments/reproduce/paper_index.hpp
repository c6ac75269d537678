// The paper as one index of campaigns: what `reposetwin paper` reads, plans and runs.
//
// Design. Every table and figure of the paper the project reproduces is one item of an index
// file (experiments/paper/index.toml): a committed campaign or calibration file, the paper's
// stated values for it (points where the text gives numbers, a trend where the figure is shape
// only), and the reductions it declares in words. The numbers behind a reduction (particles,
// d_min and the fines fraction left out, softened E, dt) are not typed in: plan_item() reads them
// from the run plan of every run the item will do (pile/run_plan.hpp, the same estimate `run`
// prints), so they cannot drift from the files, and sums the plans' wall times at one thread into
// the item's CPU-hours. The index states its budget; a test holds the sum to it.
//  * Strict like every input: unknown keys refused, naming the file, the key and the value; every
//    item's file must exist and parse as a campaign (a calibration item's must have a
//    [calibration]) before anything runs.
//  * A derived item (Fig. 7: calibrated mu_r against d_max) runs nothing: it names the earlier
//    calibration items it is drawn from, and costs nothing.
//  * The paper's other figures are predictions at the calibrated mu_r: an item with
//    `calibrated_by` names an earlier calibration item of the same [calibration] (same campaign
//    name, keys, target, range and angle, checked on loading), takes its calibration.json and
//    runs only its own [[predict]] tests (calibrate --predict-only), costing only those runs.
//  * A calibration item's cost is its budget (max_simulations pours) plus every prediction's
//    seeds, three times for one run at the ends of the mu_r interval too: the most it can take.
//  * Running (paper_run.cpp) goes item by item in index order, each into OUT/<name>/ with the
//    campaign runner's resume rules, so a killed `reposetwin paper` continues where it stopped.
#pragma once

#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "experiments/campaign/campaign.hpp"
#include "experiments/pile/run_plan.hpp"

namespace reposetwin::experiments {

/// What an item is run with.
enum class PaperItemKind {
  kCampaign,     // `reposetwin campaign FILE`
  kCalibration,  // `reposetwin calibrate FILE` (calibration, then its [[predict]] tests)
  kDerived,      // no runs of its own: drawn from earlier calibration items (`from`)
};

/// The paper's stated values for an item (FACTS.md), as points where the text gives numbers.
struct PaperPoints {
  std::string x_label;                            // what x is, e.g. "mu_r (EDEM)", "mass [g]"
  std::string y_label = "angle of repose [deg]";  // what y is
  std::vector<double> x;                          // the paper's x values
  std::vector<double> y;                          // its values there (same length as x), in [0, 90]
  std::string source;                             // where the paper states them
};

/// Angles the paper states as a level rather than at a point ("stabilises at about 36.5 deg"),
/// drawn as horizontal lines on the item's own axes.
struct PaperLevels {
  std::vector<double> y;  // the levels [deg], in [0, 90]
  std::string source;     // where the paper states them
};

/// One item of the index.
struct PaperItem {
  std::string name;   // filesystem-safe, unique: the results folder OUT/<name>
  std::string paper;  // the paper's table or figure, e.g. "Fig. 6"
  PaperItemKind kind = PaperItemKind::kCampaign;
  std::string file;               // absolute path of the campaign or calibration file ("" derived)
  std::vector<std::string> from;  // derived items: the calibration items it is drawn from
  std::string calibrated_by;      // calibration items: reuse this earlier item's calibration and
                                  // run only the [[predict]] tests at its mu_r (same [calibration])
  bool closest_if_not_calibrated = false;  // with calibrated_by: when that calibration found no
                                           // mu_r, predict at its usable point closest to the
                                           // target (marked not calibrated) instead of skipping
  std::string reductions;         // the declared reductions and why, in words
  std::string x_key;              // the scene key whose value (a campaign case's, a prediction's)
                                  // is the plot's x
  std::string x_label;            // its label on the page (default: x_key)
  double x_scale = 1.0;           // x shown = value x x_scale (e.g. 1000 for kg -> g)
  std::optional<std::pair<double, double>> x_range;  // the figure's x axis, where the paper's
                                                     // statement spans more than our points
  std::string trend;              // the paper's shape-only statement, if it gives no numbers
  std::optional<PaperPoints> paper_points;
  std::optional<PaperLevels> paper_levels;
  std::string angle = "image";  // campaign items: the angle shown (image, image_flank, ...)
};

/// A parsed index file.
struct PaperIndex {
  std::string file;  // absolute path
  std::string title;
  double budget_cpu_hours = 15.0;  // the whole set must fit in this [CPU-h]
  std::vector<PaperItem> items;    // in run order
};

/// Reads an index file strictly (see the design note); InputError naming the file, the key as
/// written and the value. Every item's file is loaded as a campaign to check it.
PaperIndex load_paper_index(const std::string& path);

/// The plan of one group of an item's runs: the same scene and overrides, different seeds.
struct PlanGroup {
  std::string label;               // case name, "calibration" or "predict <name>"
  int runs = 0;                    // planned runs of this group
  RunPlan plan;                    // the run plan of one of them (one thread)
  double softened_e_pa = 0.0;      // the softened Young's modulus (0: the real one) [Pa]
  double rayleigh_fraction = 0.0;  // dt as a fraction of the Rayleigh time [-]
  bool clumps = false;             // grains are clumps of spheres
};

/// What an item will cost and the reductions its runs use.
struct ItemPlan {
  int runs = 0;            // planned pile runs (a calibration: its most)
  double cpu_hours = 0.0;  // the runs' planned wall time at one thread [CPU-h]
  std::vector<PlanGroup> groups;
};

/// Plans every run of an item (campaign runs; a calibration's budget at mu_r_start or the middle
/// of its range, and its predictions' runs).
ItemPlan plan_item(const PaperItem& item, const PlanSettings& settings = {});

/// The state of an item's results folder.
struct ItemStatus {
  std::string state;   // "not started", "partial", "done", "cannot reach", "failed"
  int finished = 0;    // finished runs found (a calibration: pours and prediction runs)
  std::string detail;  // a short sentence (what is missing, the calibration's status)
};
ItemStatus item_status(const PaperItem& item, const std::string& out_dir);

/// The item's JSON for listings and the paper page: name, paper, kind, file, reductions, plan
/// (runs, CPU-hours, groups), paper points or trend.
nlohmann::json to_json(const PaperItem& item, const ItemPlan& plan);

/// Options of run_paper.
struct PaperRunOptions {
  std::vector<std::string> only;  // run only these items (by name); empty = all
  bool images = true;             // photograph the piles (the image angles need it)
};

/// Runs the items in order into OUT/<name>/ (resumable: finished items and runs are kept), each
/// with OUT/<name>/provenance.json (code version, commit, dirty flag, the index and item file,
/// every attempt's start and end), and writes OUT/paper.json (every item's plan and status).
/// A calibration that cannot reach its target is an outcome (status "cannot reach"), not a stop.
/// Returns paper.json's content.
nlohmann::json run_paper(const PaperIndex& index, const std::string& out_dir, const CaseFn& case_fn,
                         const RunnerSettings& runner, const PaperRunOptions& options = {});

/// Listing without running: every item with its plan and status (what `--list` prints).
nlohmann::json paper_listing(const PaperIndex& index, const std::string& out_dir);

/// The commit and dirty flag of the code version ("0.1.0+abc1234-dirty" -> abc1234, true).
struct CodeCommit {
  std::string commit;
  bool dirty = false;
};
CodeCommit code_commit(const std::string& version);

}  // namespace reposetwin::experiments
