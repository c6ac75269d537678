// Run folders: what `--out` may name, and which of its files are a run's own.
//
// Design note. A run folder holds results a person may have waited hours for, and it may be a
// folder of theirs that a typo named. So before a run writes anything (even its lock file) the
// folder is classified: absent or empty is taken; a finished run needs --force (or --resume is
// told there is nothing to resume); an interrupted run (a checkpoint and no result) needs
// --resume to continue it or --force to start again, never a silent restart that discards the
// checkpoint; anything else (files no run makes) is not a run folder and is refused unless
// --force. --force then removes only the files a run makes, by their names (the list below is
// the one place that knows them); a user's own file beside them stays. `--out` naming a file,
// nothing, or a place the process cannot write is refused with what is wrong, not with the
// lock file's or the filesystem library's error.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace reposetwin::experiments {

/// What a run folder holds.
enum class RunFolderState {
  kAbsent,       // nothing there yet
  kEmpty,        // a folder with no files (a lock file alone counts as none)
  kStarted,      // only files a run makes, neither a checkpoint nor a result
  kInterrupted,  // a run's checkpoint (checkpoint.bin, controller.json) and no result.json
  kFinished,     // a run's result.json
  kForeign,      // files no run makes: not a run folder
};

/// Whether `relative` (a path inside a run folder, as "frames/frame_00003.vtp") is a file a
/// pile run, its photographs or its summary makes.
bool is_run_file(const std::filesystem::path& relative);

/// The state of the folder `dir`; `foreign` receives up to a few files no run makes (relative).
RunFolderState run_folder_state(const std::filesystem::path& dir,
                                std::vector<std::string>* foreign = nullptr);

/// Checks that a run may write into `out` with these flags, before anything is written. Throws
/// InputError naming the folder, what is there and what to pass (--resume, --force, another
/// --out): for an empty path, a path that is a file or lies under one, a folder that cannot be
/// created or written, a finished run (without --force or with --resume), an interrupted run
/// (without --resume or --force) and a folder that is not a run (without --force).
void check_run_folder(const std::string& out, bool resume, bool force);

/// The part of check_run_folder about the place alone, for any command's output folder (a
/// campaign's, a calibration's, a loop's): --out names a folder, or one that can be made in a
/// writable folder. Throws InputError naming `option` (the command's --out, --cache) and the
/// path.
void check_output_folder(const std::string& out, const std::string& option = "--out");

/// Removes the files a run makes from `dir` (and then-empty folders of its own), leaving every
/// other file; the lock file stays (the caller holds it).
void remove_run_files(const std::filesystem::path& dir);

}  // namespace reposetwin::experiments
