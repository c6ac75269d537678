// Campaigns: many runs of one scene with overrides and seeds, resumable, on a local worker pool or
// spread over MPI ranks. The campaign file is read by io/campaign_file.hpp; the workers and the
// MPI position come from campaign/pool.hpp; this runner owns the run folders.
//
// Design.
//  * One folder per run (case x seed): out/cases/<case>/seed_<n>/. A run is finished exactly when
//    its result.json exists; that file is written atomically (temporary name + rename) as the last
//    step, so a killed run leaves either no result or a whole one. A run without result.json is
//    started again: when its started.json records the same inputs (it was killed, or the machine
//    was lost) its folder is handed back to the case function, which continues from what it left
//    (a pile run from its last checkpoint, bit-identically), and result.json lists the earlier
//    attempts; otherwise (failed, forced, other inputs) from a clean folder. A finished run is
//    never redone (unless forced) and never overwritten. A finished result made from different
//    inputs (the campaign file was edited) is an error, not a silent mix. A failing run writes
//    error.json; the campaign goes on.
//  * campaign.json (atomic) summarises every run's status for reports, and, given a classifier,
//    counts the finished runs that formed a pile apart from the others by reason (a jammed
//    outlet, a physics stop), so a summary never counts a run without a pile as a result;
//    run_batch writes batch.json instead, for the runs a driver (calibration, prediction,
//    loop) asks for.
//  * Local runs hold an exclusive lock on the output folder, so two campaign processes cannot
//    run into the same folder; the kernel releases it when the process ends, even by SIGKILL.
//  * Under MPI rank r runs the runs i with i % size == r, one at a time (the launcher decides the
//    parallelism), and rank 0 waits for every result or error file and writes the manifest
//    (run_batch: every rank waits, so every rank can go on with the results). A cluster runs the
//    same campaign file unchanged.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "experiments/campaign/pool.hpp"
#include "experiments/io/campaign_file.hpp"
#include "experiments/pile/run_plan.hpp"
#include "experiments/io/scene_overrides.hpp"

namespace reposetwin::experiments {

/// The run's scene: the scene file with the run's overrides applied (the seed is given separately
/// in CaseSpec: SceneDoc::set_seed). Throws InputError naming the case, the key and the value.
SceneDoc build_case_scene(const CaseSpec& spec);

/// The inputs of a run as JSON (stored in its result.json and checked when resuming).
nlohmann::json to_json(const CaseSpec& spec);

/// Runs one case in `case_dir` and returns its result. The folder exists and holds only the
/// runner's started.json, or, when an earlier attempt at the same inputs was interrupted (killed,
/// machine lost), also what that attempt left there, which the function may continue from (a pile
/// run resumes from its checkpoint) or clear.
using CaseFn = std::function<nlohmann::json(const CaseSpec&, const std::string& case_dir)>;

/// Settings of the campaign runner.
struct RunnerSettings {
  int workers = 2;                                   // concurrent runs on this machine (local pool)
  WorkerMode mode = WorkerMode::kProcesses;          // fork per run, or threads
  bool force = false;                                // redo finished runs too
  bool progress = true;                              // progress lines on stderr
  std::optional<RankInfo> rank = detect_mpi_rank();  // MPI position; nothing = local pool
  double poll_interval_s = 0.5;  // rank 0: pause between checks for other ranks [s]
  double wait_timeout_s = 0.0;   // rank 0: give up waiting after this long [s]; 0 = never
  /// Classifies a finished run's result (the case function's JSON) for the counts: "pile" when
  /// it formed one, else the reason it did not ("jam", "physics_stop"); empty = runs are not
  /// classified (the runner knows nothing of piles: pile campaigns pass case_outcome).
  std::function<std::string(const nlohmann::json& case_result)> outcome_of;
};

/// What run_campaign did.
struct CampaignSummary {
  int total = 0;            // runs in the campaign
  int finished = 0;         // runs with a result (before or now)
  int failed = 0;           // runs with an error
  int skipped = 0;          // finished runs found and not redone
  int ran = 0;              // runs started by this call (this rank)
  int piles = 0;            // finished runs that formed a pile (with RunnerSettings::outcome_of)
  std::map<std::string, int> without_pile;  // the other finished runs, by reason
  nlohmann::json manifest;  // the manifest written (rank 0) or this rank's view
};

/// Runs every unfinished run of `campaign` into `out_dir` through `case_fn` (see the design note).
/// Throws std::runtime_error if out_dir holds another campaign or a finished result whose inputs
/// differ from the campaign's.
CampaignSummary run_campaign(const Campaign& campaign, const std::string& out_dir,
                             const CaseFn& case_fn, const RunnerSettings& settings = {});

/// A run outside the campaign's list (e.g. one the calibration driver asks for): the base scene
/// with the campaign's common overrides plus `overrides`. Throws std::invalid_argument naming the
/// campaign file and the run if the name is unsafe or an override does not apply.
CaseSpec make_run(const Campaign& campaign, const std::string& case_name,
                  const std::vector<Override>& overrides, std::uint64_t seed);

/// The run of the campaign's [calibration] at one mu_r and seed: named "calib_<leaf>_<mu_r>",
/// with the calibration key set to mu_r. Throws if the campaign has no [calibration].
CaseSpec calibration_run(const Campaign& campaign, double mu_r, std::uint64_t seed);

/// The run of prediction `p` at one mu_r and seed: named "predict_<name>_<leaf>_<mu_r>", the
/// test's scene with its overrides and every calibration key set to mu_r.
CaseSpec prediction_run(const Campaign& campaign, const PredictionCase& p, double mu_r,
                        std::uint64_t seed);

/// Runs an explicit list of runs with the same folder, resume and failure rules as run_campaign
/// (finished runs are reused, so a killed calibration resumes without redoing simulations) and
/// returns each run's result (the case function's JSON) in order. Under MPI every rank runs its
/// share and waits for all, so every rank gets the results. Writes batch.json (status of this
/// batch). Throws std::runtime_error naming every failed run.
std::vector<nlohmann::json> run_batch(const Campaign& campaign, const std::vector<CaseSpec>& runs,
                                      const std::string& out_dir, const CaseFn& case_fn,
                                      const RunnerSettings& settings = {});

/// The result.json of a finished run (spec, timing, provenance and the case's "result"), or
/// nothing if the run has not finished.
std::optional<nlohmann::json> read_run_result(const std::string& out_dir, const CaseSpec& spec);

/// Scans out_dir and builds the manifest of `campaign` (status of every run) without running;
/// with `outcome_of` (RunnerSettings) each finished run's outcome and the counts by outcome.
nlohmann::json campaign_manifest(
    const Campaign& campaign, const std::string& out_dir,
    const std::function<std::string(const nlohmann::json&)>& outcome_of = {});

/// The plan of a campaign's runs (pile/run_plan.hpp): one part per case, planned from its first
/// run's scene, with as many runs as the case has seeds; `workers` runs side by side. What every
/// command that runs a campaign prints before it starts, and refuses above the limits.
BatchPlan plan_campaign(const Campaign& campaign, int workers);

}  // namespace reposetwin::experiments
