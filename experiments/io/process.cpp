#include "experiments/io/process.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

extern char** environ;

namespace reposetwin::experiments {

namespace {

// posix_spawn's file actions and attributes, destroyed on every path out.
struct SpawnSetup {
  posix_spawn_file_actions_t actions;
  SpawnSetup() { posix_spawn_file_actions_init(&actions); }
  ~SpawnSetup() { posix_spawn_file_actions_destroy(&actions); }
  SpawnSetup(const SpawnSetup&) = delete;
  SpawnSetup& operator=(const SpawnSetup&) = delete;
};

}  // namespace

ProgramResult run_program(const ProgramCall& call) {
  if (call.argv.empty() || call.argv[0].empty())
    throw std::invalid_argument("run_program: no program named");
  std::vector<char*> argv;
  for (const std::string& a : call.argv) {
    if (a.find('\0') != std::string::npos)
      throw std::invalid_argument("run_program: an argument of " + call.argv[0] +
                                  " holds a NUL character");
    argv.push_back(const_cast<char*>(a.c_str()));
  }
  argv.push_back(nullptr);

  SpawnSetup s;
  // stdin from /dev/null: a program waiting for input would hang the command.
  posix_spawn_file_actions_addopen(&s.actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  const std::string out = call.log.empty() ? std::string("/dev/null") : call.log.string();
  posix_spawn_file_actions_addopen(&s.actions, STDOUT_FILENO, out.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&s.actions, STDOUT_FILENO, STDERR_FILENO);
  // The log opens before the chdir, so a relative log path is relative to our folder, as every
  // other path the caller gives.
  if (!call.working_dir.empty())
    posix_spawn_file_actions_addchdir_np(&s.actions, call.working_dir.c_str());

  ProgramResult r;
  pid_t pid = -1;
  const int err = ::posix_spawnp(&pid, argv[0], &s.actions, nullptr, argv.data(), environ);
  if (err != 0) {
    r.status = ProgramStatus::kNotStarted;
    r.code = err;
    return r;
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) {
      r.status = ProgramStatus::kNotStarted;
      r.code = errno;
      return r;
    }
  }
  // glibc's posix_spawnp reports the child's failure to enter the folder, open the log or
  // exec the program as its return value, so kNotStarted covers every failure to start.
  if (WIFEXITED(status)) {
    r.status = ProgramStatus::kExited;
    r.code = WEXITSTATUS(status);
  } else {
    r.status = ProgramStatus::kSignaled;
    r.code = WIFSIGNALED(status) ? WTERMSIG(status) : 0;
  }
  return r;
}

std::string describe(const ProgramResult& r) {
  switch (r.status) {
    case ProgramStatus::kExited:
      return "exited with status " + std::to_string(r.code);
    case ProgramStatus::kSignaled:
      return "was killed by signal " + std::to_string(r.code) + " (" + ::strsignal(r.code) + ")";
    case ProgramStatus::kNotStarted:
      return std::string("could not be started (") + std::strerror(r.code) + ")";
  }
  return "ended in an unknown way";
}

void run_program_checked(const ProgramCall& call, const std::string& about) {
  const ProgramResult r = run_program(call);
  if (r.ok()) return;
  std::string msg = call.argv[0] + " (" + about + "): " + describe(r);
  if (r.status == ProgramStatus::kNotStarted && r.code == ENOENT)
    msg += "; is " + call.argv[0] + " installed and on PATH? (scripts/install_deps.sh)";
  else if (!call.log.empty())
    msg += "; its output is in " + call.log.string();
  throw std::runtime_error(msg);
}

}  // namespace reposetwin::experiments
