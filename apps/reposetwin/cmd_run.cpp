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
                     experiments::plan_refusal(plan, a.plan->limits), *a.plan, a.quiet);
}

// The run's photographs from its final state in memory, measured; nullopt when there are none:
// `note` says why (--no-images, no pile), and `error` names the file and the reason when they
// were asked for and could not be written or measured (then the run has no headline).
std::optional<nlohmann::json> photographs(const RunArgs& a, const experiments::PileRun& run,
                                          std::string& note, std::string& error) {
  if (a.no_images) {
    note = "--no-images";
    return std::nullopt;
  }
  if (experiments::no_headline(run.stop, run.pile)) {
    note = "the run ended with no settled pile to photograph";
    return std::nullopt;
  }
  try {
    nlohmann::json m =
        experiments::render_and_measure_run(run, a.run.out_dir, experiments::ImageSettings{});
    if (!m.contains("theta_deg") || !m["theta_deg"].is_number())
      throw std::runtime_error(a.run.out_dir + "/images: vision measured no side view");
    return m;
  } catch (const std::exception& e) {
    error = e.what();
    note = "the photographs could not be taken: " + error;
    return std::nullopt;
  }
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
      ->check(CLI::Range(0, 4096));
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
    experiments::check_run_folder(args->run.out_dir, args->run.resume, args->run.force);
    if (!accept_run_plan(*args, scene)) {
      set_exit_code(ExitCode::kPlanRefused);
      return;
    }
    args->run.progress = !args->quiet;
    const std::optional<experiments::PileRun> run = experiments::run_pile_test(scene, args->run);
    if (!run) {  // a stop limit (none is set from the command line; kept for completeness)
      std::cout << "stopped before the end; continue with --resume\n";
      return;
    }
    experiments::RunSummaryInputs in;
    in.run_dir = args->run.out_dir;
    in.overrides = args->sets;
    in.images = photographs(*args, *run, in.images_note, in.images_error);
    in.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const experiments::RunSummary summary = experiments::finish_run(*run, scene, in);
    if (args->json) std::cout << experiments::read_file(args->run.out_dir + "/result.json") << "\n";
    std::cout << experiments::headline_line(*run, summary, in.wall_s) << std::endl;
    if (summary.no_headline) {
      const experiments::NoHeadline& n = *summary.no_headline;
      std::cerr << "reposetwin: no angle of repose: " << n.message << "\n";
      if (run->stop.is_physics() && !run->stop.likely_cause.empty())
        std::cerr << run->stop.likely_cause << "\n";
      else
        std::cerr << "try: " << experiments::no_headline_advice(n.reason) << "\n";
    }
    set_exit_code(run_exit_code(summary));
  });
}

}  // namespace reposetwin::cli
