#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "apps/reposetwin/commands.hpp"
#include "experiments/pile/pile_run.hpp"
#include "experiments/io/scene_overrides.hpp"

namespace reposetwin::cli {

void add_run_command(CLI::App& app) {
  struct Args {
    std::string scene;
    std::vector<std::string> sets;
    experiments::RunOptions run;
    bool quiet = false;
  };
  auto args = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "run", "Run a pile test scene (the embedded quick scene when no SCENE is given)");
  cmd->add_option("scene", args->scene, "Scene file (TOML); default: the embedded quick scene");
  cmd->add_option("--out,-o", args->run.out_dir, "Run folder for results, snapshots, checkpoint")
      ->capture_default_str();
  cmd->add_option("--set", args->sets, "Override a scene key: dotted.key=value (repeatable)");
  cmd->add_option("--threads", args->run.threads, "OpenMP threads (0: the scene's setting)")
      ->check(CLI::Range(0, 4096));
  cmd->add_flag("--force", args->run.force, "Overwrite a finished result in the run folder");
  cmd->add_flag("--resume", args->run.resume, "Continue from the run folder's checkpoint");
  cmd->add_flag("--quiet,-q", args->quiet, "No progress lines");
  cmd->callback([args]() {
    const experiments::SceneConfig scene = experiments::load_scene(args->scene, args->sets);
    args->run.progress = !args->quiet;
    const std::optional<experiments::PileRun> run = experiments::run_pile_test(scene, args->run);
    if (!run) {  // a stop limit (none is set from the command line; kept for completeness)
      std::cout << "stopped before the end; continue with --resume\n";
      return;
    }
    std::cout << experiments::to_json(run->pile).dump(2) << "\n";
    if (run->stop.is_physics()) {
      std::cerr << "run stopped (" << experiments::stop_reason_text(run->stop)
                << "): " << run->stop.detail << "\n" << run->stop.likely_cause << "\n";
    }
    set_exit_code(run->stop.is_physics() ? 3 : 0);
  });
}

}  // namespace reposetwin::cli
