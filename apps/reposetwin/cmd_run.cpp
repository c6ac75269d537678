// `reposetwin run`: the plan, the pile test, its photographs and the summary page, then one line.
#include <chrono>
#include <iostream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "apps/reposetwin/commands.hpp"
#include "apps/reposetwin/plan_gate.hpp"
#include "apps/reposetwin/validators.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/io/scene_overrides.hpp"
#include "experiments/photos/pile_images.hpp"
#include "experiments/pile/pile_run.hpp"
#include "experiments/pile/run_folder.hpp"
#include "experiments/pile/run_plan.hpp"
#include "experiments/pile/run_state.hpp"
#include "experiments/report/run_stages.hpp"
#include "experiments/report/run_summary.hpp"

namespace reposetwin::cli {
namespace {

struct RunArgs {
  std::string scene;
  std::vector<std::string> sets;
  experiments::RunOptions run;
  std::shared_ptr<PlanArgs> plan = std::make_shared<PlanArgs>();
  bool quiet = false;
  bool json = false;
  bool no_images = false;
};

// The threads the run will use: the command line's, the scene's, or every core.
int run_threads(const RunArgs& a, const experiments::SceneConfig& scene) {
  if (a.run.threads > 0) return a.run.threads;
  if (scene.settings.threads > 0) return scene.settings.threads;
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

// Prints the plan; a plan above the limits goes ahead only when confirmed (plan_gate.hpp).
bool accept_run_plan(const RunArgs& a, const experiments::SceneConfig& scene) {
  if (a.run.resume) return true;  // planned when it started
  const experiments::RunPlan plan =
      experiments::plan_run(scene, run_threads(a, scene), a.plan->limits);
  return accept_plan(experiments::plan_text(plan, a.plan->limits),
                     experiments::plan_refusal(plan, {}, a.plan->limits), *a.plan, a.quiet);
}

// The exit code of a finished run: 0 with a headline, else its reason's.
ExitCode run_exit_code(const experiments::RunSummary& s) {
  if (s.headline) return ExitCode::kOk;
  switch (s.no_headline->reason) {
    case experiments::NoHeadlineReason::kPhysicsStop:
      return ExitCode::kPhysicsStop;
    case experiments::NoHeadlineReason::kPhotographs:
      return ExitCode::kNoPhotographs;
    default:
      return ExitCode::kNoPile;
  }
}

}  // namespace

void add_run_command(CLI::App& app) {
  auto args = std::make_shared<RunArgs>();
  auto* cmd =
      app.add_subcommand("run",
                         "Run a pile test scene (the embedded quick scene when no SCENE is given), "
                         "photograph the pile and write RUN_DIR/summary.html");
  cmd->add_option("scene", args->scene, "Scene file (TOML); default: the embedded quick scene");
  cmd->add_option("--out,-o", args->run.out_dir, "Run folder for results, snapshots, checkpoint")
      ->capture_default_str();
  cmd->add_option("--set", args->sets, "Override a scene key: dotted.key=value; the value is TOML or a bare word (repeatable)");
  cmd->add_option("--threads", args->run.threads, "OpenMP threads (0: the scene's setting)")
      ->check(whole_number_in(0, 4096));
  auto* force = cmd->add_flag("--force", args->run.force,
                              "Overwrite a finished result in the run folder (start again)");
  // Continue the run and start it again are opposite requests: one of them, never both.
  cmd->add_flag("--resume", args->run.resume, "Continue from the run folder's checkpoint")
      ->excludes(force);
  cmd->add_flag("--quiet,-q", args->quiet, "No plan or progress lines");
  cmd->add_flag("--json", args->json, "Also print result.json on stdout (before the last line)");
  cmd->add_flag(
      "--no-images", args->no_images,
      "No photographs: faster; the headline is then the particle atan(2H/D), and says so");
  add_plan_options(cmd, args->plan);
  cmd->callback([args]() {
    const auto t0 = std::chrono::steady_clock::now();
    const experiments::SceneConfig scene = experiments::load_scene(args->scene, args->sets);
    const std::string& out = args->run.out_dir;
    // Classified before the lock (a folder that is not a run's gets no lock file), and again
    // under it: another command may have changed it in between.
    // A refused plan writes nothing, not even the lock file.
    experiments::check_run_folder(out, args->run.resume, args->run.force);
    if (!accept_run_plan(*args, scene)) {
      set_exit_code(ExitCode::kPlanRefused);
      return;
    }
    const experiments::RunFolderLock lock(out);
    experiments::check_run_folder(out, args->run.resume, args->run.force);
    args->run.progress = !args->quiet;
    args->run.lock_held = true;
    // The stage record decides where a resumed run continues: a run recorded as simulated is
    // not simulated again, only its missing stages are made.
    const std::optional<experiments::RunState> recorded =
        args->run.resume ? experiments::read_run_state(out) : std::nullopt;
    std::optional<experiments::PileRun> run;
    if (recorded) {
      // The stages left are made for the scene the run was simulated from, never another.
      if (experiments::read_file(out + "/scene.resolved.toml") != scene.resolved_toml)
        throw experiments::InputError(
            out + ": the run was simulated from another scene (its scene.resolved.toml differs "
                  "from this one); resume it with the same scene and --set, or pass --force",
            "--resume");
      run = experiments::pile_run_from_json(
          nlohmann::json::parse(experiments::read_file(out + "/result.json")));
    } else {
      run = experiments::run_pile_test(scene, args->run);
      if (!run) {  // a stop limit (none is set from the command line; kept for completeness)
        std::cout << "stopped before the end; continue with --resume\n";
        return;
      }
      experiments::record_simulated(out, experiments::run_has_photographs(*run, args->no_images));
    }
    experiments::RunStagesRequest req;
    req.run_dir = out;
    req.overrides = args->sets;
    req.started = t0;
    if (args->no_images) req.no_images_note = "--no-images";
    const experiments::RunStagesOutcome done = experiments::finish_run_stages(*run, scene, req);
    const experiments::RunSummary& summary = done.summary;
    const double wall_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (args->json) std::cout << experiments::read_file(out + "/result.json") << "\n";
    std::cout << experiments::headline_line(*run, summary, wall_s) << std::endl;
    if (summary.no_headline) {
      const experiments::NoHeadline& n = *summary.no_headline;
      std::cerr << "reposetwin: no angle of repose: " << n.message << "\n";
      if (run->stop.is_physics() && !run->stop.likely_cause.empty())
        std::cerr << run->stop.likely_cause << "\n";
      else
        std::cerr << "try: " << experiments::no_headline_advice(n.reason) << "\n";
    }
    if (!done.state.complete())
      std::cerr << "reposetwin: " << out << " is incomplete (missing: " << done.state.missing()
                << "); continue it with --resume\n";
    set_exit_code(run_exit_code(summary));
  });
}

}  // namespace reposetwin::cli
