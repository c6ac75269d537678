#include <algorithm>
#include <cstdio>
#include <iostream>
#include <memory>

#include "apps/reposetwin/commands.hpp"
#include "apps/reposetwin/plan_gate.hpp"
#include "apps/reposetwin/validators.hpp"
#include "experiments/campaign/case_runner.hpp"
#include "experiments/pile/run_folder.hpp"
#include "experiments/reproduce/paper_index.hpp"
#include "experiments/reproduce/paper_page.hpp"

namespace reposetwin::cli {
namespace {

struct PaperArgs {
  std::string index = "experiments/paper/index.toml";
  std::string out = "runs/paper";
  bool list = false;
  bool page = false;
  bool force = false;
  std::vector<std::string> only;
  int workers = 2;
  std::string mode = "processes";
  int views = 4;
  std::shared_ptr<PlanArgs> plan = std::make_shared<PlanArgs>();
};

// What the items a call runs (those named in `only`, or all) cost by their plans.
struct PaperCost {
  int runs = 0;
  double cpu_hours = 0.0;      // [CPU-h]
  long long particles = 0;     // the largest pile's
};

PaperCost paper_cost(const experiments::PaperIndex& index, const std::vector<std::string>& only) {
  PaperCost c;
  for (const experiments::PaperItem& item : index.items) {
    if (!only.empty() && std::find(only.begin(), only.end(), item.name) == only.end()) continue;
    const experiments::ItemPlan plan = experiments::plan_item(item);
    c.runs += plan.runs;
    c.cpu_hours += plan.cpu_hours;
    for (const experiments::PlanGroup& g : plan.groups)
      c.particles = std::max<long long>(c.particles, g.plan.particles);
  }
  return c;
}

// The items a call runs against the plan limits: their CPU-hours over the workers as the wall
// time, and their largest pile. Empty when within them.
std::string paper_refusal(const experiments::PaperIndex& index, const PaperArgs& a) {
  const PaperCost cost = paper_cost(index, a.only);
  const long long particles = cost.particles;
  const double wall_s = 3600.0 * cost.cpu_hours / std::max(1, a.workers);
  const experiments::PlanSettings& lim = a.plan->limits;
  if (particles > lim.max_particles)
    return "a pile of " + std::to_string(particles) + " particles is above --max-particles " +
           std::to_string(lim.max_particles) + "; pass --yes to run it anyway";
  if (wall_s > lim.max_wall_s)
    return "the items planned take about " + experiments::duration_text(wall_s) + " with " +
           std::to_string(a.workers) + " workers, above --max-hours " +
           experiments::duration_text(lim.max_wall_s) + "; pass --yes to run them anyway";
  return "";
}

void print_listing(const nlohmann::json& l) {
  std::printf("%-22s %-26s %-11s %5s %8s %9s  %s\n", "item", "paper", "kind", "runs", "CPU-h",
              "particles", "status");
  for (const auto& i : l["items"]) {
    long long pmin = -1, pmax = 0;
    for (const auto& g : i["groups"]) {
      const long long n = g["particles"].get<long long>();
      pmin = pmin < 0 ? n : std::min(pmin, n);
      pmax = std::max(pmax, n);
    }
    const std::string parts = pmin < 0       ? std::string("-")
                              : pmin == pmax ? std::to_string(pmax)
                                             : std::to_string(pmin) + "-" + std::to_string(pmax);
    const std::string detail = i["status_detail"].get<std::string>();
    std::printf("%-22s %-26s %-11s %5d %8.2f %9s  %s%s\n", i["name"].get<std::string>().c_str(),
                i["paper"].get<std::string>().c_str(), i["kind"].get<std::string>().c_str(),
                i["planned_runs"].get<int>(), i["planned_cpu_hours"].get<double>(), parts.c_str(),
                i["status"].get<std::string>().c_str(),
                detail.empty() ? "" : (" (" + detail + ")").c_str());
  }
  std::printf(
      "total: %d runs, %.2f CPU-hours planned (budget %.1f, %s); rate %.2g "
      "particle-steps/s per thread (pile/run_plan.hpp)\n",
      l["planned_runs"].get<int>(), l["planned_cpu_hours"].get<double>(),
      l["budget_cpu_hours"].get<double>(), l["within_budget"].get<bool>() ? "within" : "ABOVE",
      l["items"].empty() ? 0.0 : l["items"][0]["rate_particle_steps_per_s"].get<double>());
}

}  // namespace

void add_paper_command(CLI::App& app) {
  auto a = std::make_shared<PaperArgs>();
  auto* cmd = app.add_subcommand(
      "paper",
      "Reproduce the paper: run every item of the index (experiments/paper/index.toml) in "
      "order, each into OUT/<item>/ with its provenance (resumable; spreads over MPI ranks)");
  cmd->add_option("index", a->index, "Paper index file (TOML)")->capture_default_str();
  cmd->add_option("--out,-o", a->out, "Results folder (one sub-folder per item)")
      ->capture_default_str();
  cmd->add_flag("--list,--dry-run", a->list,
                "Print the items with their planned runs, CPU-hours and status; run nothing");
  cmd->add_flag("--page", a->page,
                "Build OUT/paper_page/index.html (the paper beside ours) from what exists; "
                "run nothing");
  cmd->add_flag("--force", a->force, "Rebuild the page over an earlier one");
  cmd->add_option("--only", a->only, "Run only these items (by name)")->delimiter(',');
  add_workers_option(cmd, a->workers, "Runs side by side on this machine");
  cmd->add_option("--mode", a->mode, "Local pool: processes or threads")
      ->check(CLI::IsMember({"processes", "threads"}))
      ->capture_default_str();
  cmd->add_option("--views", a->views, "Side views per pile for the image angle")
      ->check(whole_number_in(1, 64))
      ->capture_default_str();
  add_plan_options(cmd, a->plan);
  cmd->callback([a]() {
    const experiments::PaperIndex index = experiments::load_paper_index(a->index);
    if (a->list) {
      print_listing(experiments::paper_listing(index, a->out));
      return;
    }
    if (a->page) {
      const std::string page = experiments::build_paper_page(index, a->out, a->force);
      std::cout << "paper page " << page << "\n";
      return;
    }
    experiments::check_output_folder(a->out);
    // The listing is the plan: printed before anything runs, and above the limits only with
    // --yes.
    const PaperCost planned = paper_cost(index, {});
    char line[160];
    std::snprintf(line, sizeof line,
                  "plan: %d runs of the index, %.2f CPU-hours (reposetwin paper --list shows "
                  "each item)\n",
                  planned.runs, planned.cpu_hours);
    if (!accept_plan(line, paper_refusal(index, *a), *a->plan, false)) {
      set_exit_code(ExitCode::kPlanRefused);
      return;
    }
    experiments::RunnerSettings rs;
    rs.workers = a->workers;
    rs.mode = a->mode == "threads" ? experiments::WorkerMode::kThreads
                                   : experiments::WorkerMode::kProcesses;
    rs.outcome_of = experiments::case_outcome_word;
    experiments::CaseRunSettings cs;
    cs.image.side_views = a->views;
    experiments::PaperRunOptions opt;
    opt.only = a->only;
    const nlohmann::json l =
        experiments::run_paper(index, a->out, experiments::pile_case_fn(cs), rs, opt);
    print_listing(l);
    if (l.value("failed_items_this_call", 0) > 0) set_exit_code(ExitCode::kSomeFailed);
  });
}

}  // namespace reposetwin::cli
