// The one-page summary a run ends with: the twin's photographs, its headline angle, every other
// measure by name, the inputs and the provenance, and the one line a person reads.
//
// Design note. `reposetwin run` is the main job, so it ends where a user wants to be: the pile
// photographed like the lab's (photos/pile_images.hpp, from the run's final state in memory)
// and its angle read from the photos as the lab reads its own (pile/headline.hpp). The page is
// written beside the run's files (RUN_DIR/summary.html) and links only relatively (images/...,
// result.json), so a copied run folder still opens. It uses the report's page skeleton, table
// and figure templates (templates.hpp); C++ only fills typed page data. finish_run() also adds
// the headline fields to result.json (atomically, keeping every field it had).
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "experiments/io/scene.hpp"
#include "experiments/pile/headline.hpp"
#include "experiments/pile/pile_record.hpp"

namespace reposetwin::experiments {

/// What the summary shows besides the run record.
struct RunSummaryInputs {
  std::string run_dir;
  std::vector<std::string> overrides;    // the --set arguments as given
  std::optional<nlohmann::json> images;  // images/measurement.json; absent: no photographs
  std::string images_note;               // why there are none ("--no-images", "no pile")
  std::string images_error;  // photographs were asked for and could not be written or measured:
                             // the path and the reason; non-empty means no headline
  double wall_s = 0.0;                   // the command's wall time, photographs included [s]
};

/// What finish_run() made.
struct RunSummary {
  std::optional<Headline> headline;       // absent when the run has none: then no_headline
  std::optional<NoHeadline> no_headline;  // why there is no headline angle
  std::string page;                       // RUN_DIR/summary.html
};

/// The headline of a run (from its photographs, or its particles when none were asked for), or
/// why it has none (pile/headline.hpp).
RunSummary run_headline(const PileRun& run, const RunSummaryInputs& in);

/// Adds the headline (or headline_angle_deg = null and no_headline) to RUN_DIR/result.json,
/// replacing every field an earlier summary added (so a summary without images leaves no
/// earlier image fields behind): the run's `summarised` stage.
RunSummary summarise_run(const PileRun& run, const SceneConfig& scene, const RunSummaryInputs& in);

/// Writes RUN_DIR/summary.html for a summary summarise_run made: the `reported` stage. Returns
/// the page's path.
std::string write_run_summary_page(const PileRun& run, const SceneConfig& scene,
                                   const RunSummaryInputs& in, RunSummary& s);

/// summarise_run, then write_run_summary_page.
RunSummary finish_run(const PileRun& run, const SceneConfig& scene, const RunSummaryInputs& in);

/// The summary page's HTML (finish_run writes it).
std::string run_summary_html(const PileRun& run, const SceneConfig& scene,
                             const RunSummaryInputs& in, const RunSummary& s);

/// The run's last line on stdout: headline angle, H, D, particle count, wall time, the page;
/// without a headline "no angle of repose: " and the reason instead of the angle.
std::string headline_line(const PileRun& run, const RunSummary& s, double wall_s);

}  // namespace reposetwin::experiments
