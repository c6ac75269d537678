// The one door to other programs (gnuplot, and any other a command starts).
//
// Design note. A program is started from an argument vector with posix_spawnp, its working
// folder set by the spawn itself (posix_spawn_file_actions_addchdir_np), never through a shell:
// no word of a folder or file name is ever parsed as a command, so a run folder named
// `O'Brien; rm -rf ~` is only a name. Its output goes to a log file (kept and named when the
// program fails) or to /dev/null, never to our stdout, whose last line is the command's result.
// The result is typed: how the program ended is an enum, and run_program_checked() turns every
// ending but a clean exit into an error that names the program and the file it worked on, so a
// page is never left silently without its figure. Nothing else in non-test code may call
// std::system, popen or exec* (the build check tests/no_shell_check.cmake refuses them).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace reposetwin::experiments {

/// What a program is started with.
struct ProgramCall {
  std::vector<std::string> argv;      // argv[0] is looked up in PATH (posix_spawnp)
  std::filesystem::path working_dir;  // empty: this process's working folder
  std::filesystem::path log;          // stdout and stderr (truncated); empty: /dev/null
};

/// How a started program ended.
enum class ProgramStatus {
  kExited,      // exited with status `code` (0: success)
  kSignaled,    // killed by signal `code`
  kNotStarted,  // could not be started; `code` is the errno (ENOENT: not found)
};

/// The end of one program call.
struct ProgramResult {
  ProgramStatus status = ProgramStatus::kNotStarted;
  int code = 0;  // exit status, signal number or errno, by `status`
  bool ok() const { return status == ProgramStatus::kExited && code == 0; }
};

/// Starts `call` and waits for it. Never throws for the program's own failure (that is the
/// result); throws std::invalid_argument for an empty argv, or an argument with a NUL.
ProgramResult run_program(const ProgramCall& call);

/// "exited with status 1", "was killed by signal 9 (Killed)", "could not be started (No such
/// file or directory)".
std::string describe(const ProgramResult& r);

/// Runs `call` and throws std::runtime_error unless it exits 0. The message names the program,
/// `about` (the file it was given, e.g. a gnuplot script) and how it ended, and the log when
/// there is one; for a program not found, it says so.
void run_program_checked(const ProgramCall& call, const std::string& about);

}  // namespace reposetwin::experiments
