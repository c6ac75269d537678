// A run folder as a state machine under one lock (pile/run_state.hpp), through the command line:
// a run killed (SIGKILL) right after each stage is recorded shows no headline in `report`,
// which says what is missing, and `run --resume` finishes it to the result an uninterrupted run
// gives; a second writer on a locked folder is refused with exit 10; `render --force` with other
// views rewrites everything made from the views.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_support.hpp"
#include "experiments/io/provenance.hpp"

namespace reposetwin::test_support {
namespace {

const fs::path kTiny = fs::path(REPOSETWIN_SOURCE_DIR) / "data" / "loop" / "tiny_scene.toml";

// reposetwin with `args`, its environment extended by `env` ("NAME=value"), as a script runs it.
struct Ended {
  experiments::ProgramStatus status;
  int code;
  std::string out;
};
Ended run_with_env(const std::vector<std::string>& env, const std::vector<std::string>& args,
                   const fs::path& cwd) {
  const fs::path log = fs::temp_directory_path() /
                       ("reposetwin_run_state_test." + std::to_string(getpid()) + ".log");
  experiments::ProgramCall call;
  call.argv = {"env"};
  call.argv.insert(call.argv.end(), env.begin(), env.end());
  call.argv.push_back(REPOSETWIN_BIN);
  call.argv.insert(call.argv.end(), args.begin(), args.end());
  call.working_dir = cwd;
  call.log = log;
  const experiments::ProgramResult p = experiments::run_program(call);
  Ended e{p.status, p.code, read_text(log)};
  fs::remove(log);
  return e;
}

// result.json without what differs between two runs of one scene by design: provenance (the
// time it was made) and performance (wall and CPU time).
nlohmann::json comparable(const fs::path& run) {
  nlohmann::json r = nlohmann::json::parse(read_text(run / "result.json"));
  r.erase("provenance");
  r.erase("performance");
  return r;
}

TEST(RunKill, AKillAtEachStageLeavesAnIncompleteRunThatResumeFinishesToTheSameResult) {
  const fs::path dir = fresh_dir("run_kill");
  const CliResult whole =
      run_cli_argv({"run", kTiny.string(), "--out", "whole", "--quiet"}, dir, 300);
  ASSERT_EQ(whole.code, 0) << whole.out;
  const nlohmann::json expected = comparable(dir / "whole");
  ASSERT_TRUE(expected["headline_angle_deg"].is_number());

  for (const char* stage : {"simulated", "photographed", "measured", "summarised", "reported"}) {
    SCOPED_TRACE(stage);
    const std::string out = std::string("killed_") + stage;
    const Ended killed = run_with_env({std::string("REPOSETWIN_TEST_KILL_AFTER_STAGE=") + stage},
                                      {"run", kTiny.string(), "--out", out, "--quiet"}, dir);
    ASSERT_EQ(killed.status, experiments::ProgramStatus::kSignaled) << killed.out;
    ASSERT_EQ(killed.code, SIGKILL);
    const bool complete = std::string(stage) == "reported";

    const CliResult report = run_cli_argv({"report", out}, dir, 120);
    if (complete) {
      EXPECT_EQ(report.code, 0) << report.out;
      EXPECT_NE(report.out.find("angle of repose"), std::string::npos) << report.out;
    } else {
      // No headline, and what is missing.
      EXPECT_EQ(report.code, 11) << report.out;
      EXPECT_EQ(report.out.find("angle of repose"), std::string::npos) << report.out;
      EXPECT_NE(report.out.find("incomplete run, no headline"), std::string::npos) << report.out;
      EXPECT_NE(report.out.find(std::string("stopped after the stage ") + stage), std::string::npos)
          << report.out;
      EXPECT_NE(report.out.find("missing: "), std::string::npos) << report.out;
      // A plain run into it is refused: it is not finished, and not to be started over silently.
      const CliResult again = run_cli_argv({"run", kTiny.string(), "--out", out, "--quiet"}, dir);
      EXPECT_EQ(again.code, 2) << again.out;
      EXPECT_NE(again.out.find("--resume"), std::string::npos) << again.out;
    }

    const CliResult resumed =
        run_cli_argv({"run", kTiny.string(), "--out", out, "--resume", "--quiet"}, dir, 300);
    if (complete) {
      EXPECT_EQ(resumed.code, 2) << resumed.out;
      EXPECT_NE(resumed.out.find("nothing to resume"), std::string::npos) << resumed.out;
    } else {
      ASSERT_EQ(resumed.code, 0) << resumed.out;
      EXPECT_EQ(resumed.out.rfind("angle of repose ", 0), 0u) << resumed.out;
    }
    EXPECT_EQ(comparable(dir / out), expected);
    EXPECT_TRUE(fs::exists(dir / out / "summary.html"));
    const CliResult after = run_cli_argv({"report", out, "--force"}, dir, 120);
    EXPECT_EQ(after.code, 0) << after.out;
    EXPECT_NE(after.out.find("angle of repose"), std::string::npos) << after.out;
  }

  // New views rewrite everything made from the views: measurement, headline, page, images.
  const CliResult one = run_cli_argv({"render", "whole", "--force", "--views", "1"}, dir, 300);
  ASSERT_EQ(one.code, 0) << one.out;
  const nlohmann::json r = nlohmann::json::parse(read_text(dir / "whole" / "result.json"));
  EXPECT_EQ(r["headline_views"], 1);
  const nlohmann::json m =
      nlohmann::json::parse(read_text(dir / "whole" / "images" / "measurement.json"));
  EXPECT_EQ(m["side_views"].size(), 1u);
  EXPECT_EQ(r["image"]["theta_deg"], m["theta_deg"]);
  EXPECT_FALSE(fs::exists(dir / "whole" / "images" / "side_az045.png"));
  EXPECT_NE(read_text(dir / "whole" / "summary.html").find("1 side views"), std::string::npos);
}

TEST(RunLock, ASecondWriterOnALockedRunFolderIsRefusedWithExit10) {
  const fs::path dir = fresh_dir("run_lock");
  // A run folder as far as render and report are concerned; its lock held by this process.
  write_text(dir / "held" / "result.json", "{}");
  const experiments::FolderLock held((dir / "held").string(), ".run.lock", "a test");
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"run", kTiny.string(), "--out", "held", "--force", "--quiet"},
        std::vector<std::string>{"run", kTiny.string(), "--out", "held", "--resume", "--quiet"},
        std::vector<std::string>{"render", "held", "--force"},
        std::vector<std::string>{"report", "held", "--force"}}) {
    const CliResult r = run_cli_argv(args, dir);
    EXPECT_EQ(r.code, 10) << args[0] << ": " << r.out;
    EXPECT_NE(r.out.find("another reposetwin command (run, render or report) is already "
                         "running in this folder"),
              std::string::npos)
        << r.out;
  }
  EXPECT_FALSE(fs::exists(dir / "held" / "report"));
}

}  // namespace
}  // namespace reposetwin::test_support
