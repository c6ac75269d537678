#include <utility>

#include "apps/reposetwin/commands.hpp"

namespace reposetwin::cli {
namespace {
int g_exit_code = 0;

// The README's exit-code table says the same, at more length.
constexpr std::pair<ExitCode, const char*> kMeanings[] = {
    {ExitCode::kOk, "success"},
    {ExitCode::kError, "bad input or another error; the message names the file, key and value"},
    {ExitCode::kPhysicsStop, "run: the engine stopped the run (NaN, overlap, escape)"},
    {ExitCode::kSomeFailed,
     "campaign, timestep: some cases failed or gave no angle; paper: some items failed"},
    {ExitCode::kUnreachable, "calibrate: the target angle cannot be reached in the mu_r range"},
    {ExitCode::kPlanRefused,
     "run, calibrate, campaign, timestep, loop, paper: the plan is above the limits and was "
     "not confirmed (--yes)"},
    {ExitCode::kNoPile,
     "run: no angle: no settled pile to measure (time limit, not settled, jammed, no pile)"},
    {ExitCode::kNoPhotographs, "run: no angle: the photographs could not be written or measured"},
    {ExitCode::kRefused,
     "measure: a photo failed an admission check; the message (and --json's \"refused\") names "
     "the check and the value it measured"},
    {ExitCode::kBusy,
     "run, render, report: another reposetwin command is writing the run folder (its lock is "
     "held); nothing was written: wait for it to end"},
    {ExitCode::kIncomplete,
     "report: a run folder stopped between its stages; no headline is shown, the message says "
     "what is missing (run --resume finishes it)"},
};
}  // namespace

int exit_code() { return g_exit_code; }
void set_exit_code(ExitCode code) { g_exit_code = static_cast<int>(code); }

std::string exit_code_help() {
  std::string text = "Exit codes:\n";
  for (const auto& [code, meaning] : kMeanings)
    text += "  " + std::to_string(static_cast<int>(code)) + "  " + meaning + "\n";
  return text + "  100-127  command-line errors (CLI11)\n";
}

}  // namespace reposetwin::cli
