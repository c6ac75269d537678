// The repose-angle pile test as a run of the engine: fill, settle, lift, settle, measure.
//
// Design note. The lab procedure is a sequence of phases; the controller below is a small state
// machine over them, checked every few milliseconds of simulated time:
//   fill    the PSD sample is placed on a loose lattice inside the container (standing on the
//           plate, which closes the outlet as in the lab) and settles until its kinetic energy
//           per particle falls below the threshold;
//   lift    the container rises at the set speed until no particle is left inside it; if the
//           count inside stops changing for clog_window seconds, the flow has stopped: with at
//           most max_retained_fraction of the sample inside (cohesive grains stuck to the wall),
//           that material stays in the container and is lifted away with it (removed from the
//           run, counted in the result as retained_in_container), and the pile settles; with
//           more, particles have arched in the outlet and the run ends jammed, with no pile
//           and no headline angle (pile/headline.hpp);
//   settle  the container is gone; the pile settles until the energy threshold again;
//   done    the pile is measured from the particle positions (sim/pile_geometry).
// The run stops by itself and records why. Everything needed to resume (the engine checkpoint
// and this controller's state) is written together, atomically, every few minutes of wall time.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>

#include "experiments/io/scene.hpp"
#include "experiments/pile/pile_record.hpp"

namespace reposetwin::experiments {

struct RunOptions {
  std::string out_dir = "runs/quick";  // the run folder
  bool force = false;       // overwrite a finished result in out_dir
  bool resume = false;      // continue from out_dir's checkpoint
  bool progress = true;     // progress lines on stderr
  int threads = 0;          // OpenMP threads; 0 = the scene's setting
  double stop_after_wall_s = 0.0;  // stop (with a checkpoint) after this wall time [s]; 0 = never
  std::int64_t stop_after_steps = 0;  // stop (with a checkpoint) after this many steps of this
                                      // session; 0 = never (deterministic, for tests)
  nlohmann::json extra_provenance = nlohmann::json::object();  // e.g. the campaign case
  bool lock_held = false;  // the caller holds out_dir's RunFolderLock for its whole command
};

/// Thrown by run_pile_test with opt.resume when the folder's checkpoint or controller state cannot
/// be read (damaged, or written by an incompatible version); nothing has been run or written.
class ResumeError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Runs the scene's pile test into opt.out_dir and returns its record (also written to
/// out_dir/result.json), or nothing when opt's wall-time or step limit stopped it first (it is
/// checkpointed; resume continues it). Throws InputError for bad input (including a finished
/// result that would be overwritten without force).
std::optional<PileRun> run_pile_test(const SceneConfig& scene, const RunOptions& opt);

/// Runs the pile test in opt.out_dir, continuing what an interrupted attempt left there (for
/// campaigns and the loop's cache, whose runs may be killed or lose their machine): a finished
/// run (result.json) is returned as it is, a checkpoint is resumed (bit-identical to an
/// uninterrupted run), anything else is cleared and run afresh. A checkpoint that cannot be
/// resumed (ResumeError: damaged, or written by an incompatible version) is cleared too and the
/// run started again, never half-mixed.
std::optional<PileRun> run_pile_test_or_continue(const SceneConfig& scene, const RunOptions& opt);

}  // namespace reposetwin::experiments
