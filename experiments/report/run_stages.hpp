// A run folder taken through its stages after the simulation: photographs, their measurement,
// the headline, the page (pile/run_state.hpp holds the record and its rules).
//
// Design note. `run`, `run --resume` and `render` all end the same way, so they share this one
// walk: it reads the folder's stage record, does the stages still missing in their order, and
// records each as its last file is written. Whatever was recorded is not done again (a resume
// after `measured` reads measurement.json, which the record vouches for); photographs taken and
// not measured are taken again, as a measurement can only come with its own photographs. A
// failed photograph records its reason and stops below `measured`: the run is incomplete, has
// no headline, and --resume takes the photographs again.
#pragma once

#include <chrono>
#include <string>
#include <vector>

#include "experiments/io/scene.hpp"
#include "experiments/photos/pile_images.hpp"
#include "experiments/pile/pile_record.hpp"
#include "experiments/pile/run_state.hpp"
#include "experiments/report/run_summary.hpp"

namespace reposetwin::experiments {

/// What the stages after the simulation are asked for.
struct RunStagesRequest {
  std::string run_dir;
  std::vector<std::string> overrides;             // the --set arguments, for the page
  ImageSettings images;                           // the photographs' settings
  std::string no_images_note;                     // why the run has no photographs ("--no-images")
  std::chrono::steady_clock::time_point started;  // when the command began (the page's wall time)
};

/// What the walk made: the summary and its inputs, and the record it left.
struct RunStagesOutcome {
  RunSummary summary;
  RunSummaryInputs inputs;
  RunState state;
};

/// Whether a run just simulated has photographs among its stages: asked for (no --no-images)
/// and a settled pile to take.
bool run_has_photographs(const PileRun& run, bool no_images);

/// Takes the run folder `req.run_dir`, recorded as simulated or later, to `reported` (or to a
/// recorded failure of its photographs). `run` is its record (in memory after a simulation, or
/// read from result.json). Throws std::logic_error when the folder has no stage record.
RunStagesOutcome finish_run_stages(const PileRun& run, const SceneConfig& scene,
                                   const RunStagesRequest& req);

}  // namespace reposetwin::experiments
