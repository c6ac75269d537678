// A run folder's stage: which of its results are valid, recorded in one small file.
//
// Design note. A run folder is made in stages, each writing files the next one reads:
//   simulated     result.json (the particle record), final.vtp, the series and checkpoint
//   photographed  images/side_az*.png, top.png, their sidecars and overlays
//   measured      images/measurement.json
//   summarised    the headline fields of result.json (headline_angle_deg or no_headline)
//   reported      summary.html, the run's page
// A process killed between two stages leaves the files of the later one absent, half-made or
// stale from an earlier attempt, and no file can tell by itself which. So the stage reached is
// recorded in run_state.json, written atomically right after the stage's last file, and read
// back strictly (its format tag, version, every field, and a checksum over them): whatever a
// stage owns is valid only when the record says that stage was reached, and readers ask the
// record rather than probing files. A folder whose record is below `reported`, or has none, is
// incomplete: it has no headline, `run --resume` continues it from the stage recorded, and
// `report` says what is missing. Rewinding (`render --force`: new views) lowers the record
// first and then removes the files of the stages above, so a kill in between leaves an
// incomplete folder, never new views beside an old headline.
//
// A run without photographs (--no-images, or no settled pile to take) goes from simulated to
// summarised: the record says so (`photographs`), and the transition table below allows the
// skip only then. A run whose photographs failed (exit 8) stays at simulated with the failure
// in `note`: it is incomplete, and --resume takes the photographs again.
//
// Writers of a run folder (run, run --resume, render, report) hold its lock (RunFolderLock) for
// the whole command, so two of them never interleave their stages.
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

#include "experiments/io/input_error.hpp"
#include "experiments/io/provenance.hpp"

namespace reposetwin::experiments {

/// The stages of a run folder, in order.
enum class RunStage { kSimulated = 0, kPhotographed, kMeasured, kSummarised, kReported, kCount };

/// The stage's word in run_state.json and in messages, indexed by the enum.
inline constexpr std::array<const char*, static_cast<std::size_t>(RunStage::kCount)>
    kRunStageNames = {"simulated", "photographed", "measured", "summarised", "reported"};

const char* run_stage_name(RunStage s);
/// The stage of `word`; nothing for an unknown word.
std::optional<RunStage> run_stage_from(std::string_view word);

/// The record of run_state.json.
struct RunState {
  RunStage stage = RunStage::kSimulated;
  bool photographs = true;  // the run's stages include photographed and measured
  std::string note;         // why the run stopped short of its next stage (a failed photograph)

  /// The stage the run needs next; nothing when it is complete.
  std::optional<RunStage> next() const;
  /// Every stage is done: the folder's results are valid and it has its headline (or a reason).
  bool complete() const { return stage == RunStage::kReported; }
  /// "photographed, measured, summarised, reported": the stages still to be made.
  std::string missing() const;
};

/// Whether a run at `from` may record `to` next: the following stage, or summarised straight
/// after simulated when `photographs` is false.
bool run_stage_follows(RunStage from, RunStage to, bool photographs);

/// A run_state.json that cannot be trusted (damaged, edited, from another program or version),
/// refused with the path and what is wrong.
class RunStateError : public InputError {
 public:
  using InputError::InputError;
};

/// The record's file name inside a run folder.
inline constexpr const char* kRunStateFile = "run_state.json";

/// The record's text (JSON with a checksum over its fields), and the record read back from
/// that text; run_state_from_text throws RunStateError naming `path` for anything but a
/// record run_state_text wrote.
std::string run_state_text(const RunState& s);
RunState run_state_from_text(const std::string& text, const std::string& path);

/// DIR/run_state.json read and verified; nothing when the folder has none.
std::optional<RunState> read_run_state(const std::string& dir);

/// Starts the record of a run just simulated (replacing any earlier one).
void record_simulated(const std::string& dir, bool photographs);

/// Records that the run in `dir` reached `stage`. Throws std::logic_error when the folder's
/// record is missing or `stage` does not follow its stage (a bug in the caller's order). With
/// REPOSETWIN_TEST_KILL_AFTER_STAGE set to the stage's word, the process then kills itself
/// with SIGKILL: the hook of the tests that stop a run at each stage boundary.
void record_stage(const std::string& dir, RunStage stage);

/// Records why the run stopped short of its next stage (kept until the next stage).
void record_note(const std::string& dir, const std::string& note);

/// Lowers the record of `dir` to `stage` (with `photographs` as the stages ahead will have it),
/// then removes the files the stages above own (the side and top photographs, their sidecars
/// and overlays, measurement.json, summary.html; a frame's photographs in images/<frame>/ are
/// not the run's and stay). result.json's headline fields are rewritten by the next summary.
/// Throws std::logic_error when `stage` is above the recorded one.
void rewind_run_state(const std::string& dir, RunStage stage, bool photographs);

/// The exclusive lock of a run folder (DIR/.run.lock), held by every command that writes into
/// it for the whole command. Throws FolderBusy naming the folder when another process holds it.
class RunFolderLock {
 public:
  explicit RunFolderLock(const std::string& dir);

 private:
  FolderLock lock_;
};

}  // namespace reposetwin::experiments
