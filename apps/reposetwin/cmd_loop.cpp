// reposetwin loop DATA.csv --out DIR: close the loop on measured data (experiments/loop/loop.hpp).
// reposetwin loop-synth DESIGN.toml --out DIR: a synthetic lab dataset with hidden settings.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "apps/reposetwin/commands.hpp"
#include "apps/reposetwin/plan_gate.hpp"
#include "experiments/io/numbers.hpp"
#include "apps/reposetwin/validators.hpp"
#include "experiments/loop/loop.hpp"
#include "experiments/loop/loop_synth.hpp"
#include "experiments/pile/run_folder.hpp"
#include "experiments/report/loop_report.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/provenance.hpp"

namespace reposetwin::cli {

namespace fs = std::filesystem;

namespace {

std::vector<double> parse_list(const std::string& text, const std::string& option) {
  std::vector<double> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    out.push_back(experiments::plain_decimal(item, option + " " + text));
  }
  return out;
}

}  // namespace

void add_loop_command(CLI::App& app) {
  struct Args {
    std::string data;
    std::string out = "loop_out";
    std::string grid;
    std::string seeds;
    std::string candidates;
    std::string angle = "image";
    std::string at_bound = "extend";
    std::string mu_range;
    std::string mu_range_reason;
    experiments::LoopSettings settings;
    bool quiet = false;
    bool own_cameras = false;
    std::shared_ptr<PlanArgs> plan = std::make_shared<PlanArgs>();
  };
  auto args = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "loop", "Calibrate mu_r on measured tests, trace the residual to a missing effect, refit, "
              "and report the error before and after (docs/loop.md)");
  cmd->add_option("data", args->data, "Measured data CSV (docs/loop.md)")->required();
  cmd->add_option("--out,-o", args->out, "Output folder (loop.json, index.html, cache/)")
      ->capture_default_str();
  cmd->add_option("--mu-grid", args->grid, "mu_r grid, comma separated (default 0.05,0.15,0.3,0.5)");
  cmd->add_option("--seeds", args->seeds, "Seeds, comma separated (default 1001,1002,1003)");
  cmd->add_option("--mu-key", args->settings.mu_key,
                  "Scene key(s) of the calibrated mu_r, comma separated, all set to the same value "
                  "({sample}, {plate} stand for the test's materials)")
      ->capture_default_str();
  cmd->add_option("--candidates", args->candidates,
                  "Candidate effects to try, comma separated (default: all in the registry but the "
                  "opt-in grain_shape)");
  cmd->add_option("--refit", args->settings.refit,
                  "Refit this candidate even when the trace names another or none (a hypothesis "
                  "you bring; reported as declared, with the trace's own verdict)");
  cmd->add_option("--max-effects", args->settings.max_effects,
                  "Stop after this many effects (0: trace and rank only, no refit)")
      ->check(whole_number_in(0, 10))
      ->capture_default_str();
  cmd->add_option("--refit-follow-ups", args->settings.refit_follow_ups,
                  "Trials a refit adds where its fit lands, until it lands on a simulated value "
                  "(0: the effect's value may be read off a chord beyond the trials)")
      ->check(whole_number_in(0, 10))
      ->capture_default_str();
  cmd->add_option("--max-pours", args->settings.max_pours,
                  "Pours per pile: a pour that forms no pile (the funnel jammed) is repeated with "
                  "a new seed, as a lab repeats it, up to this many pours in all")
      ->check(whole_number_in(1, 100))
      ->capture_default_str();
  cmd->add_option("--min-t", args->settings.rule.min_t, "Significance threshold |c|/se")
      ->check(positive_number())
      ->capture_default_str();
  cmd->add_option("--min-delta-chi2", args->settings.rule.min_delta_chi2,
                  "A candidate is named only when its joint chi^2 (angle, H, D) beats every "
                  "other accepted candidate's by more than this; else they are reported as "
                  "indistinguishable")
      ->check(non_negative_number())
      ->capture_default_str();
  cmd->add_option("--at-bound", args->at_bound,
                  "When the calibrated mu_r sits on an end of the grid: extend (add grid points "
                  "beyond it, at most --grid-extensions, then refuse), refuse (trace nothing, "
                  "saying so), trace (trace anyway with mu_r held inside the grid)")
      ->capture_default_str();
  cmd->add_option("--grid-extensions", args->settings.grid_extensions,
                  "Grid points the loop may add beyond a bound mu_r lands on")
      ->check(whole_number_in(0, 10))
      ->capture_default_str();
  cmd->add_option("--mu-range", args->mu_range,
                  "mu_r's plausible range LO,HI (a prior, e.g. 0.02,0.4 for rock in our "
                  "convention): never simulated or fitted outside it; mu_r alone needing more is "
                  "traced as evidence for an effect. Needs --mu-range-reason");
  cmd->add_option("--mu-range-reason", args->mu_range_reason,
                  "Why mu_r lies in --mu-range (recorded in loop.json)");
  cmd->add_option("--mu-max", args->settings.mu_max, "The grid is never extended above this")
      ->check(positive_number())
      ->capture_default_str();
  cmd->add_option("--probe-scalings", args->settings.probe_scalings,
                  "Doublings of a candidate's probe while its fingerprint does not stand out "
                  "of the seed noise")
      ->check(whole_number_in(0, 10))
      ->capture_default_str();
  add_workers_option(cmd, args->settings.workers, "Concurrent simulations");
  cmd->add_option("--width", args->settings.image.width_px, "Render width [px]")
      ->check(whole_number_in(64, 16384))
      ->capture_default_str();
  cmd->add_option("--height", args->settings.image.height_px, "Render height [px]")
      ->check(whole_number_in(64, 16384))
      ->capture_default_str();
  cmd->add_option("--views", args->settings.image.side_views, "Side views per pile")
      ->check(whole_number_in(1, 64))
      ->capture_default_str();
  cmd->add_flag("--own-cameras", args->own_cameras,
                "Photograph the twin's piles with its own framing (--width, --height, --views) "
                "even where the lab's photos declare their cameras in sidecars");
  cmd->add_option("--cache", args->settings.cache_dir, "Simulation cache (default OUT/cache)");
  cmd->add_option("--angle", args->angle,
                  "Angle compared: image (vision atan(2H/D), as the lab reads its photos), "
                  "image_flank (vision's flank lines; typed lab angles are then taken as flank "
                  "angles, a full cone assumed), particles")
      ->capture_default_str();
  cmd->add_flag("--force", args->settings.force, "Recompute a finished loop.json (cache kept)");
  cmd->add_flag("--quiet,-q", args->quiet, "No progress lines");
  add_plan_options(cmd, args->plan);
  cmd->callback([args]() {
    experiments::LoopSettings s = args->settings;
    if (!args->grid.empty()) {
      s.mu_grid = parse_list(args->grid, "--mu-grid");
      for (std::size_t i = 0; i < s.mu_grid.size(); ++i)
        if (s.mu_grid[i] < 0.0 || (i > 0 && !(s.mu_grid[i] > s.mu_grid[i - 1])) ||
            s.mu_grid.size() < 2)
          throw experiments::InputError("--mu-grid " + args->grid +
                                        ": give at least two increasing values >= 0");
    }
    if (!args->seeds.empty()) {
      s.seeds = experiments::parse_seed_list(args->seeds, "--seeds");
    }
    if (!args->candidates.empty()) {
      std::stringstream ss(args->candidates);
      std::string c;
      while (std::getline(ss, c, ',')) {
        try {
          (void)experiments::find_effect(c);
        } catch (const std::exception& e) {
          throw experiments::InputError("--candidates " + args->candidates + ": " + e.what());
        }
        s.candidates.push_back(c);
      }
    }
    s.angle = experiments::parse_angle_measure(args->angle, "--angle");
    s.at_bound = experiments::parse_grid_bound(args->at_bound, "--at-bound");
    if (!args->mu_range.empty()) {
      const std::vector<double> r = parse_list(args->mu_range, "--mu-range");
      if (r.size() != 2)
        throw experiments::InputError("--mu-range " + args->mu_range + ": give two values, LO,HI");
      if (args->mu_range_reason.empty())
        throw experiments::InputError("--mu-range " + args->mu_range +
                                      ": give its reason with --mu-range-reason");
      s.mu_prior = {r[0], r[1], args->mu_range_reason};
    } else if (!args->mu_range_reason.empty()) {
      throw experiments::InputError("--mu-range-reason given without --mu-range");
    }
    s.progress = !args->quiet;
    s.image.use_lab_cameras = !args->own_cameras;
    s.page = experiments::write_loop_html;
    experiments::check_output_folder(args->out);
    if (!s.cache_dir.empty()) experiments::check_output_folder(s.cache_dir, "--cache");
    // The page goes where the user pointed --out (`-o .` is a folder of theirs): a page there
    // that reposetwin did not make stays unless --force.
    experiments::OutputPlan plan(s.force);
    plan.add_input(args->data);
    plan.add_output((fs::path(args->out) / "index.html").string(), "--out");
    plan.add_output((fs::path(args->out) / "loop.json").string(), "--out");
    plan.check();
    const experiments::LabData data = experiments::read_lab_csv(args->data);
    // The baseline's piles are known before anything runs; a grid of a thousand points is a
    // week of piles, started only when confirmed.
    const experiments::BatchPlan bp = experiments::plan_loop_baseline(data, s);
    if (!accept_plan("The loop's baseline (fingerprints and refits come on top):\n" +
                         experiments::plan_text(bp, args->plan->limits),
                     experiments::plan_refusal(
                         bp, {experiments::KeySource::Kind::kTestSheet, args->data},
                         args->plan->limits), *args->plan,
                     args->quiet)) {
      set_exit_code(ExitCode::kPlanRefused);
      return;
    }
    const nlohmann::json loop = experiments::run_loop(data, args->out, s);
    std::cout << loop["summary"].dump(2) << "\n";
    std::cout << "report: " << args->out << "/index.html, " << args->out << "/loop.json\n";
    set_exit_code(ExitCode::kOk);
  });

  struct SynthArgs {
    std::string design;
    std::string out = "loop_synth";
    std::string cache;
    std::string truth;
    int workers = 2;
    bool force = false;
  };
  auto sargs = std::make_shared<SynthArgs>();
  auto* syn = app.add_subcommand(
      "loop-synth", "Make a synthetic lab dataset (CSV + photos) from the twin with hidden "
                    "settings; the hidden settings are not written");
  syn->add_option("design", sargs->design, "Design file (TOML, see experiments/loop/loop_synth.hpp)")
      ->required();
  syn->add_option("--out,-o", sargs->out, "Output folder")->capture_default_str();
  syn->add_option("--cache", sargs->cache,
                  "Simulation cache, outside the dataset's folder (default: OUT.synth-cache)");
  syn->add_option("--truth", sargs->truth,
                  "Also write the hidden settings as JSON to this file, outside the dataset's "
                  "folder (for a validation to compare the loop's answer with)");
  add_workers_option(syn, sargs->workers, "Concurrent simulations");
  syn->add_flag("--force", sargs->force,
                "Replace an existing --truth file that reposetwin did not make");
  auto synth_plan = std::make_shared<PlanArgs>();
  add_plan_options(syn, synth_plan);
  syn->callback([sargs, synth_plan]() {
    experiments::OutputPlan plan(sargs->force);
    plan.add_input(sargs->design);
    if (!sargs->truth.empty()) plan.add_output(sargs->truth, "--truth");
    plan.check();
    const experiments::SynthDesign d = experiments::read_synth_design(sargs->design);
    experiments::check_output_folder(sargs->out);
    const std::string cache_dir =
        experiments::synth_cache_dir(sargs->out, sargs->cache, sargs->truth);
    experiments::check_output_folder(cache_dir, "--cache");
    const experiments::BatchPlan bp = experiments::plan_synth_dataset(d, sargs->workers);
    if (!accept_plan(
            "The synthetic lab's piles:\n" + experiments::plan_text(bp, synth_plan->limits),
            experiments::plan_refusal(bp, {experiments::KeySource::Kind::kSceneFile, d.scene},
                                      synth_plan->limits),
            *synth_plan, false)) {
      set_exit_code(ExitCode::kPlanRefused);
      return;
    }
    // The loop reads the dataset's folder; the truth and the cache must not be where it could.
    experiments::SimCache cache(cache_dir, {sargs->workers, true});
    std::cout << experiments::make_synthetic_dataset(d, sargs->out, cache) << "\n";
    if (!sargs->truth.empty()) {
      nlohmann::json truth = experiments::synth_truth_json(d, sargs->design);
      truth["code_version"] = experiments::code_version();
      plan.write(sargs->truth, truth.dump(2) + "\n");
    }
    set_exit_code(ExitCode::kOk);
  });
}

}  // namespace reposetwin::cli
