#include "experiments/report/run_stages.hpp"

#include <filesystem>
#include <stdexcept>

#include "experiments/io/files.hpp"
#include "experiments/pile/headline.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::size_t index(RunStage s) { return static_cast<std::size_t>(s); }

RunState recorded(const std::string& dir) {
  const std::optional<RunState> s = read_run_state(dir);
  if (!s) throw std::logic_error("finish_run_stages: " + dir + " has no stage record");
  return *s;
}

// The photographs stage and the measured stage: the images taken and measured, or (recorded as
// measured) read back. Sets in.images, or in.images_error with the reason.
void photographs_stages(const PileRun& run, const RunStagesRequest& req, RunState& state,
                        RunSummaryInputs& in) {
  const std::string& dir = req.run_dir;
  const fs::path measurement = fs::path(dir) / "images" / "measurement.json";
  if (index(state.stage) >= index(RunStage::kMeasured)) {
    in.images = read_json_file(measurement.string());
    return;
  }
  // Photographs without their measurement are taken again with it.
  if (state.stage != RunStage::kSimulated) rewind_run_state(dir, RunStage::kSimulated, true);
  try {
    json m = render_and_measure_run(run, dir, req.images,
                                    [&] { record_stage(dir, RunStage::kPhotographed); });
    if (!m.contains("theta_deg") || !m["theta_deg"].is_number())
      throw std::runtime_error(dir + "/images: vision measured no side view");
    record_stage(dir, RunStage::kMeasured);
    in.images = std::move(m);
  } catch (const std::exception& e) {
    in.images_error = e.what();
    in.images_note = "the photographs could not be taken: " + in.images_error;
  }
  state = recorded(dir);
}

}  // namespace

bool run_has_photographs(const PileRun& run, bool no_images) {
  return !no_images && !no_headline(run.stop, run.pile);
}

RunStagesOutcome finish_run_stages(const PileRun& run, const SceneConfig& scene,
                                   const RunStagesRequest& req) {
  const std::string& dir = req.run_dir;
  RunStagesOutcome out;
  out.state = recorded(dir);
  RunSummaryInputs& in = out.inputs;
  in.run_dir = dir;
  in.overrides = req.overrides;
  if (out.state.photographs) {
    photographs_stages(run, req, out.state, in);
  } else {
    in.images_note = !req.no_images_note.empty() ? req.no_images_note
                     : no_headline(run.stop, run.pile)
                         ? "the run ended with no settled pile to photograph"
                         : "--no-images";
  }
  const auto wall = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - req.started).count();
  };
  in.wall_s = wall();
  // The summary is recorded only for photographs that were taken: one that failed leaves the
  // run incomplete (its page and result still say why), and --resume takes them again.
  // A summary already recorded is made again the same (from the same run and measurement),
  // as the page needs it; only its record is not repeated.
  out.summary = summarise_run(run, scene, in);
  const bool photographs_failed = !in.images_error.empty();
  if (!photographs_failed && index(recorded(dir).stage) < index(RunStage::kSummarised))
    record_stage(dir, RunStage::kSummarised);
  write_run_summary_page(run, scene, in, out.summary);
  if (photographs_failed)
    record_note(dir, "the photographs failed: " + in.images_error);
  else
    record_stage(dir, RunStage::kReported);
  out.state = recorded(dir);
  return out;
}

}  // namespace reposetwin::experiments
