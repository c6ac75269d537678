// Campaigns: many runs of one scene with overrides and seeds, resumable, on a local worker pool or
// spread over MPI ranks.
//
// Design.
//  * A campaign file (TOML, strict: unknown keys are errors) names a base scene, seeds, and either
//    a list of [[case]] tables (each with dotted-key overrides) or one [sweep] over a key; every
//    case runs once per seed. Loading checks everything a run would trip on later (missing scene
//    files, overrides that do not apply to the scene) so a campaign fails at once, not after hours.
//  * One folder per run (case x seed): out/cases/<case>/seed_<n>/. A run is finished exactly when
//    its result.json exists; that file is written atomically (temporary name + rename) as the last
//    step, so a killed run leaves either no result or a whole one. A run without result.json is
//    started again: when its started.json records the same inputs (it was killed, or the machine
//    was lost) its folder is handed back to the case function, which continues from what it left
//    (a pile run from its last checkpoint, bit-identically), and result.json lists the earlier
//    attempts; otherwise (failed, forced, other inputs) from a clean folder. A finished run is
//    never redone (unless forced) and never overwritten. A finished result made from different inputs (the campaign file was edited) is an
//    error, not a silent mix. A failing run writes error.json; the campaign goes on.
//  * campaign.json (atomic) summarises every run's status for reports.
//  * Local pool: processes (fork per run; the parent waits; the child writes its result and calls
//    _exit) or threads. Processes isolate a crashing or leaking run and give each run a clean
//    address space; forking must happen before the parent has started OpenMP threads (libgomp's
//    pool does not survive fork). Children die with the parent (PR_SET_PDEATHSIG), so a killed
//    campaign leaves no orphan writing into a folder that the resumed campaign restarts.
//  * MPI without linking MPI: under mpirun the rank and size come from OMPI_COMM_WORLD_RANK/SIZE
//    (or PMIX_RANK and OMPI_COMM_WORLD_SIZE); rank r runs runs i with i % size == r, one at a time
//    (the launcher decides the parallelism), and rank 0 waits for every result or error file and
//    writes the manifest. A cluster runs the same campaign file unchanged.
//  * Processes vs threads, measured (bench scratch, 8 CPU-bound runs, 2 workers, on the shared
//    2-core machine at load ~8): equal within +-10% run to run; a process costs about 1-3 ms more
//    per run (fork), nothing next to a DEM run. Processes are the default for the isolation.
//
// File format (paths relative to the campaign file; every key below, nothing else):
//   name = "mass_sensitivity"                 # filesystem-safe
//   description = "..."                       # optional
//   paper = "Fig. 8"                          # optional: the paper item it reproduces
//   scene = "../../data/scenes/quick.toml"    # base scene
//   seeds = [1, 2, 3]                         # or a count: seeds = 3 means 1, 2, 3
//   overrides = { "sample.mass_kg" = 0.2 }    # optional, common to every case
//   [[case]]                                  # either cases ...
//   name = "m200"
//   description = "200 g"                     # optional
//   scene = "other.toml"                      # optional
//   overrides = { "sample.mass_kg" = 0.2 }    # quoted dotted keys or nested tables
//   [sweep]                                   # ... or one sweep (case names <leaf>_<value>)
//   key = "sample.mass_kg"
//   values = [0.05, 0.2, 0.9]
//   name = "mass"                             # optional prefix instead of the key's leaf
//   [calibration]                             # optional, for the calibrate command
//   target_deg = 33.47                        # measured angle, in (0, 90)
//   target_sd_deg = 0.3                       # optional, its 1-sigma uncertainty
//   # or, instead of target_deg, the lab's side photos of the pile, measured with vision/ as the
//   # renders are (atan(2H/D) for image/particles, the flank angle for image_flank/slice; sd:
//   # the measurement's uncertainty of the mean unless target_sd_deg is given):
//   # target_photos = ["lab/side_0.png", "lab/side_90.png"]
//   # target_photo_camera = "lab/camera.json"  # optional scale: a camera sidecar, or
//   # target_mm_per_px = 0.21                  # mm per pixel at the pile axis, or STEM.json
//   #                                          # beside each photo, or the scale reference
//   mu_r_range = [0.02, 0.4]
//   key = "contacts.rock-rock.rolling_friction"  # optional (this is the default)
//   seeds_per_point = 3                       # optional, as are first_seed (1), tolerance_deg
//   max_simulations = 40                      # (0.5), bootstrap_replicates (2000), confirm
//   table1_sample = 3                         # optional: the paper's Table 1 sample (reports)
//   angle = "image"                           # optional: which simulated angle is matched
//                                             # (image, image_flank, particles, slice; below)
//   [[predict]]                               # optional, with [calibration]: other tests run at
//   name = "sample4"                          # the calibrated mu_r (filesystem-safe, unique)
//   scene = "s4.toml"                         # required: the other test's scene
//   measured_deg = 37.17                      # required: its measured angle, in (0, 90)
//   measured_sd_deg = 0.3                     # optional, its 1-sigma uncertainty
//   seeds = [1, 2, 3]                         # optional: list or count (default: the campaign's
//                                             # seeds, else seeds_per_point from first_seed)
//   overrides = { ... }                       # optional, on top of the common overrides
//   interval_ends = true                      # optional (true): also run the seeds at the ends
//                                             # of the calibrated mu_r's 95% interval
//   table1_sample = 4                         # optional: the paper's Table 1 sample (reports)
//   description = "..."                       # optional
// `calibration.angle` names the simulated angle compared with the measured one (AngleMeasure):
// "image" (default) is atan(2H/D) read by vision on the renders, as the lab photo is read;
// "image_flank" is the flank-line angle vision fits on the same renders (a protractor laid on the
// photo); "particles" and "slice" are atan(2H/D) and the protractor on centre slices from the
// particle positions (the latter is EDEM's simulated angle in the paper). Matching a flank angle
// to a lab atan(2H/D) assumes the lab pile is a full cone (its two angles equal): declare it.
// `calibration.key` may also be a list of keys that all take the calibrated value (e.g. rock-rock
// and rock-plate rolling friction); the first names the calibration runs.
//
// Calibrate, then predict. run_calibration() drives calibrate_batch() through run_batch() and
// writes calibration.json; run_predictions() runs every [[predict]] test at the calibrated mu_r
// (and, unless interval_ends = false, at both ends of its 95% interval) through the same
// resumable pool, and writes predictions.json. A prediction's mu_r comes from calibration.json,
// whose numbers round-trip exactly through JSON, so a resumed or predict-only call names the same
// run folders and reuses every finished run. The interval's effect on a prediction is measured by
// those end runs; with interval_ends = false it is estimated by shifting the prediction by the
// calibration test's own fitted angle change over the interval (stated as such in the file).
#pragma once

#include <toml++/toml.h>

#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "experiments/calibration/calibration.hpp"

namespace reposetwin::experiments {

/// One run of a campaign: a case (scene + overrides) with one seed.
struct CaseSpec {
  std::size_t index = 0;   // position in the campaign's run list (used for MPI distribution)
  std::string case_name;   // unique, filesystem-safe
  std::uint64_t seed = 0;  // run seed
  std::string scene_path;  // absolute path of the scene file
  std::string scene_hash;  // FNV-1a 64 of the scene file's text (hex), to detect edited inputs
  toml::table overrides;   // dotted key -> value, applied to the scene before parsing
  /// The run's folder relative to the campaign output folder ("cases/<case>/seed_<n>").
  std::string relative_dir() const;
  /// A short id for messages ("<case>/seed_<n>").
  std::string id() const;
};

/// Which simulated angle a calibration or a prediction compares with the measured one.
enum class AngleMeasure {
  kImage,       // vision on the renders: atan(2H/D), as the lab photo is read
  kImageFlank,  // vision on the renders: mean flank-line angle over the views
  kParticles,   // particle positions: atan(2H/D)
  kSlice,       // particle positions: protractor on slices through the pile centre (EDEM's)
};

/// The file name of a measure ("image", "image_flank", "particles", "slice").
std::string angle_measure_name(AngleMeasure m);
/// A sentence saying how the measure is taken, for result files and reports.
std::string angle_measure_method(AngleMeasure m);
/// Parses a measure's name; std::invalid_argument naming `where` and the value otherwise.
AngleMeasure parse_angle_measure(const std::string& name, const std::string& where);
/// True when the measure is read from renders (the runs must be photographed).
inline bool angle_measure_needs_images(AngleMeasure m) {
  return m == AngleMeasure::kImage || m == AngleMeasure::kImageFlank;
}

/// The [calibration] table of a campaign file, for the calibrate command.
struct CampaignCalibration {
  std::string key = "contacts.rock-rock.rolling_friction";  // dotted scene key that is varied
  std::vector<std::string> keys;     // every key set to mu_r (keys.front() == key); empty = {key}
  Target target;                     // measured angle to match
  CalibrationSettings settings;      // mu_r range, seeds per point, tolerance, budget
  std::optional<int> table1_sample;  // the paper's Table 1 sample it calibrates on (reports)
  AngleMeasure angle = AngleMeasure::kImage;  // the simulated angle matched to the target
  nlohmann::json target_photos;      // the lab photos' measurement when the target came from
                                     // target_photos (null: target_deg typed in)
};

/// One [[predict]] entry: another test, run at the calibrated mu_r with its own seeds.
struct PredictionCase {
  std::string name;                  // filesystem-safe, unique among the predictions
  std::string description;           // free text (optional)
  std::string scene_path;            // absolute path of the test's scene
  std::string scene_hash;            // FNV-1a 64 of the scene file's text (hex)
  toml::table overrides;             // the campaign's common overrides, then the entry's own
  Target measured;                   // the test's measured angle and its 1-sigma uncertainty
  std::vector<std::uint64_t> seeds;  // run seeds
  bool interval_ends = true;         // also run the seeds at both ends of the mu_r interval
  std::optional<int> table1_sample;  // the paper's Table 1 sample it predicts (reports)
};

/// A parsed campaign file.
struct Campaign {
  std::string name;         // filesystem-safe
  std::string description;  // free text (optional)
  std::string paper;        // the paper item it reproduces, e.g. "Fig. 8" (optional)
  std::string file;         // absolute path of the campaign file
  std::string scene_path;   // absolute path of the base scene
  std::vector<std::uint64_t> seeds;
  toml::table overrides;       // the file's top-level overrides, common to every run
  std::vector<CaseSpec> runs;  // cases x seeds, in file order then seed order
  std::optional<CampaignCalibration> calibration;
  std::vector<PredictionCase> predictions;  // [[predict]] entries (only with [calibration])
};

/// Reads a campaign file. Throws std::invalid_argument (or std::runtime_error for unreadable files)
/// whose message names the file, the key and the value: unknown keys, wrong types, missing or
/// unreadable scenes, duplicate or unsafe case names, overrides that do not apply to the scene.
Campaign load_campaign(const std::string& path);

/// Parses campaign text; `path` names it in messages and anchors relative scene paths.
Campaign parse_campaign(std::string_view text, const std::string& path);

/// Whether a name is safe as a folder name: [A-Za-z0-9][A-Za-z0-9._-]*, at most 100 characters.
bool is_safe_name(std::string_view name);

/// The run's scene: the scene file parsed as TOML with the run's overrides applied. The caller's
/// scene parser reads it (the seed is given separately in CaseSpec).
toml::table build_case_scene(const CaseSpec& spec);

/// The inputs of a run as JSON (stored in its result.json and checked when resuming).
nlohmann::json to_json(const CaseSpec& spec);

/// Runs one case in `case_dir` and returns its result. The folder exists and holds only the
/// runner's started.json, or, when an earlier attempt at the same inputs was interrupted (killed,
/// machine lost), also what that attempt left there, which the function may continue from (a pile
/// run resumes from its checkpoint) or clear.
using CaseFn = std::function<nlohmann::json(const CaseSpec&, const std::string& case_dir)>;

/// How runs are spread over local workers.
enum class WorkerMode { kProcesses, kThreads };

/// Position of this process in an MPI job.
struct RankInfo {
  int rank = 0;
  int size = 1;
  std::string job;  // id shared by the ranks of one job ("" = compare file times instead)
};

/// The MPI rank from the environment (OpenMPI / PMIx variables), or nothing outside mpirun.
std::optional<RankInfo> detect_mpi_rank();

/// Settings of the campaign runner.
struct RunnerSettings {
  int workers = 2;                                   // concurrent runs on this machine (local pool)
  WorkerMode mode = WorkerMode::kProcesses;          // fork per run, or threads
  bool force = false;                                // redo finished runs too
  bool progress = true;                              // progress lines on stderr
  std::optional<RankInfo> rank = detect_mpi_rank();  // MPI position; nothing = local pool
  double poll_interval_s = 0.5;  // rank 0: pause between checks for other ranks [s]
  double wait_timeout_s = 0.0;   // rank 0: give up waiting after this long [s]; 0 = never
};

/// What run_campaign did.
struct CampaignSummary {
  int total = 0;            // runs in the campaign
  int finished = 0;         // runs with a result (before or now)
  int failed = 0;           // runs with an error
  int skipped = 0;          // finished runs found and not redone
  int ran = 0;              // runs started by this call (this rank)
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
                  const toml::table& overrides, std::uint64_t seed);

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

/// Scans out_dir and builds the manifest of `campaign` (status of every run) without running.
nlohmann::json campaign_manifest(const Campaign& campaign, const std::string& out_dir);

/// The angle a calibration or prediction uses from one run's result (the case function's JSON).
/// For a prediction it may return NaN for a run that made no pile (a clogged outlet): such runs
/// are listed and counted (no_pile), never averaged.
using AngleFn = std::function<double(const nlohmann::json& case_result)>;

/// What the calibrate command records beside the numbers.
struct CalibrateOptions {
  std::string angle_method;  // how the angle is measured, in words (stored in the JSON files)
  nlohmann::json extra;      // more fields for calibration.json (e.g. code version)
};

/// Keeps only the [[predict]] tests named in `names`, in that order; std::invalid_argument naming
/// the campaign file, the unknown name and the names there are otherwise.
void keep_only_predictions(Campaign& c, const std::vector<std::string>& names);

/// Calibrates the campaign's [calibration] through run_batch (resumable: finished runs are
/// reused) and writes OUT/calibration.json atomically; returns its content. Besides to_json of the
/// result it records the campaign (file, name), the keys, the mu_r range, table1_sample, the
/// scene and the scene's rolling model (keyword and the exact law, from sim::kRollingModels).
/// Throws std::invalid_argument if the campaign has no [calibration].
nlohmann::json run_calibration(const Campaign& campaign, const std::string& out_dir,
                               const CaseFn& case_fn, const AngleFn& angle_of,
                               const RunnerSettings& runner = {},
                               const CalibrateOptions& options = {});

/// Reads OUT/calibration.json and checks that it is this campaign's finished calibration (same
/// campaign name, keys, target and mu_r range, and the angle method when `angle_method` is given).
/// Throws std::runtime_error naming the file and the field that differs or is missing.
nlohmann::json read_calibration(const Campaign& campaign, const std::string& out_dir,
                                const std::string& angle_method = "");

/// Runs every [[predict]] test at the calibration's mu_r (and at its interval ends unless the
/// entry says interval_ends = false) through run_batch, and writes OUT/predictions.json
/// atomically; returns its content: per prediction the angles per seed, mean, seed sd, the
/// measured angle, the error (mean - measured) and the mu_r interval's effect with its method.
/// Throws std::runtime_error if the calibration has no calibrated mu_r (cannot reach).
nlohmann::json run_predictions(const Campaign& campaign, const nlohmann::json& calibration,
                               const std::string& out_dir, const CaseFn& case_fn,
                               const AngleFn& angle_of, const RunnerSettings& runner = {},
                               const CalibrateOptions& options = {});

}  // namespace reposetwin::experiments
