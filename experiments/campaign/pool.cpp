#include "experiments/campaign/pool.hpp"

#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <charconv>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <map>
#include <mutex>
#include <string_view>
#include <thread>
#include <vector>

namespace reposetwin::experiments {
namespace {

std::optional<int> env_int(const char* name) {
  const char* v = std::getenv(name);
  if (v == nullptr || *v == '\0') return std::nullopt;
  int out = 0;
  const std::string_view s(v);
  const auto r = std::from_chars(s.data(), s.data() + s.size(), out);
  if (r.ec != std::errc()) return std::nullopt;
  return out;
}

void run_threads(std::size_t n, int workers, const JobFn& job, const JobDoneFn& on_done) {
  std::atomic<std::size_t> next{0};
  std::mutex m;
  std::vector<std::thread> pool;
  for (int w = 0; w < std::min<int>(workers, static_cast<int>(n)); ++w) {
    pool.emplace_back([&] {
      for (std::size_t k = next++; k < n; k = next++) {
        const bool ok = job(k);
        std::lock_guard<std::mutex> lock(m);
        on_done(k, JobExit{ok, true, ""});
      }
    });
  }
  for (auto& t : pool) t.join();
}

// Forks a worker for job k; returns its pid (or -1 when fork failed). Never returns in the child.
pid_t fork_worker(std::size_t k, pid_t parent, const JobFn& job) {
  const pid_t pid = ::fork();
  if (pid != 0) return pid;
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);
  if (::getppid() != parent) ::_exit(3);  // the parent died before prctl took effect
  const bool ok = job(k);
  std::cout.flush();  // _exit skips the buffers the job's output may sit in
  std::cerr.flush();
  std::fflush(nullptr);
  ::_exit(ok ? 0 : 1);
}

// The end of a reaped worker; `r` is waitpid's return (negative: the status is unknown).
JobExit exit_of(pid_t r, int status) {
  JobExit e;
  e.ok = r > 0 && WIFEXITED(status) && WEXITSTATUS(status) == 0;
  if (r > 0 && WIFSIGNALED(status)) e.how = "killed by signal " + std::to_string(WTERMSIG(status));
  if (r > 0 && WIFEXITED(status)) e.how = "exit code " + std::to_string(WEXITSTATUS(status));
  return e;
}

void run_processes(std::size_t n, int workers, const JobFn& job, const JobDoneFn& on_done) {
  std::fflush(nullptr);  // nothing buffered may be written twice by the children
  const pid_t parent = ::getpid();
  std::size_t next = 0;
  std::map<pid_t, std::size_t> active;
  while (next < n || !active.empty()) {
    while (next < n && static_cast<int>(active.size()) < workers) {
      const std::size_t k = next++;
      const pid_t pid = fork_worker(k, parent, job);
      if (pid < 0) {
        on_done(k, JobExit{false, false, ""});
        continue;
      }
      active[pid] = k;
    }
    bool reaped = false;
    for (auto it = active.begin(); it != active.end();) {
      int status = 0;
      const pid_t r = ::waitpid(it->first, &status, WNOHANG);
      if (r == 0) {
        ++it;
        continue;
      }
      const std::size_t k = it->second;
      it = active.erase(it);
      reaped = true;
      on_done(k, exit_of(r, status));
    }
    if (!reaped) std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

}  // namespace

std::optional<RankInfo> detect_mpi_rank() {
  auto rank = env_int("OMPI_COMM_WORLD_RANK");
  if (!rank) rank = env_int("PMIX_RANK");
  const auto size = env_int("OMPI_COMM_WORLD_SIZE");
  if (!rank || !size || *size < 1 || *rank < 0 || *rank >= *size) return std::nullopt;
  RankInfo info;
  info.rank = *rank;
  info.size = *size;
  for (const char* name :
       {"PMIX_NAMESPACE", "OMPI_MCA_orte_ess_jobid", "OMPI_MCA_ess_base_jobid"}) {
    if (const char* v = std::getenv(name); v && *v) {
      info.job = v;
      break;
    }
  }
  return info;
}

void run_jobs(std::size_t n, int workers, WorkerMode mode, const JobFn& job,
              const JobDoneFn& on_done) {
  workers = std::max(1, workers);
  if (mode == WorkerMode::kThreads) {
    run_threads(n, workers, job, on_done);
  } else {
    run_processes(n, workers, job, on_done);
  }
}

}  // namespace reposetwin::experiments
