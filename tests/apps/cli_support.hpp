// Helpers for tests that run the built `reposetwin` as a script would: its exit code and its
// messages (stdout and stderr together), in temporary folders of their own.
//
// Design note. ctest runs each test in its own process, two at a time, so the log of a command
// and the folders a test makes carry the process id: two tests never share one.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "experiments/io/process.hpp"

namespace reposetwin::test_support {

namespace fs = std::filesystem;

struct CliResult {
  int code = -1;
  std::string out;  // stdout and stderr together
};

inline std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Runs reposetwin with `args` (shell words) and stdin from /dev/null, as a script would.
inline CliResult run_cli(const std::string& args) {
  const fs::path log =
      fs::temp_directory_path() / ("reposetwin_cli_test." + std::to_string(getpid()) + ".log");
  const std::string cmd =
      std::string("'") + REPOSETWIN_BIN + "' " + args + " </dev/null >'" + log.string() + "' 2>&1";
  const int status = std::system(cmd.c_str());
  CliResult r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = read_text(log);
  fs::remove(log);
  return r;
}

// Runs reposetwin with `args` as its argument vector (no shell: a path may hold any character)
// in the folder `cwd`, stdin from /dev/null, killed after `timeout_s` seconds (exit 124) so that
// a read that hangs fails the test instead of stopping the suite.
inline CliResult run_cli_argv(const std::vector<std::string>& args, const fs::path& cwd,
                              int timeout_s = 60) {
  const fs::path log = fs::temp_directory_path() /
                       ("reposetwin_cli_argv_test." + std::to_string(getpid()) + ".log");
  experiments::ProgramCall call;
  call.argv = {"timeout", "-s", "KILL", std::to_string(timeout_s), REPOSETWIN_BIN};
  call.argv.insert(call.argv.end(), args.begin(), args.end());
  call.working_dir = cwd;
  call.log = log;
  const experiments::ProgramResult p = experiments::run_program(call);
  CliResult r;
  r.code = p.status == experiments::ProgramStatus::kExited ? p.code : -1;
  r.out = read_text(log);
  fs::remove(log);
  return r;
}

// An empty folder for one test.
inline fs::path fresh_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() /
                     ("reposetwin_cli_" + name + "." + std::to_string(getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

inline void write_text(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p, std::ios::binary) << text;
}

inline void touch(const fs::path& p) { write_text(p, "{}"); }

// `p` quoted for the shell.
inline std::string quoted(const fs::path& p) {
  std::string s = p.string();
  s.insert(s.begin(), '\'');
  s.push_back('\'');
  return s;
}

}  // namespace reposetwin::test_support
