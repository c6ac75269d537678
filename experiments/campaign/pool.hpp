// A local pool of workers and the MPI position of this process: how a campaign spreads its runs.
//
// Design.
//  * run_jobs() runs jobs 0..N-1 through a callback on W workers, either as forked processes
//    (one per job; the parent waits) or as threads. Processes isolate a crashing or leaking job
//    and give each a clean address space; forking must happen before the parent has started
//    OpenMP threads (libgomp's pool does not survive fork). Children die with the parent
//    (PR_SET_PDEATHSIG), so a killed campaign leaves no orphan writing into a folder that the
//    resumed campaign restarts.
//  * MPI without linking MPI: under mpirun the rank and size come from OMPI_COMM_WORLD_RANK/SIZE
//    (or PMIX_RANK and OMPI_COMM_WORLD_SIZE), and the job id from the PMIx/OpenMPI job variables.
//    The launcher decides the parallelism; the caller picks its share of the jobs by rank.
//  * Processes vs threads, measured (8 CPU-bound runs, 2 workers, on a shared 2-core machine at
//    load ~8): equal within +-10% run to run; a process costs about 1-3 ms more per job (fork),
//    nothing next to a DEM run. Processes are the default for the isolation.
// The pool knows nothing of campaigns: what a job is and what its end means is the caller's.
#pragma once

#include <cstddef>
#include <functional>
#include <optional>
#include <string>

namespace reposetwin::experiments {

/// How jobs are spread over local workers.
enum class WorkerMode { kProcesses, kThreads };

/// Position of this process in an MPI job.
struct RankInfo {
  int rank = 0;
  int size = 1;
  std::string job;  // id shared by the ranks of one job ("" = compare file times instead)
};

/// The MPI rank from the environment (OpenMPI / PMIx variables), or nothing outside mpirun.
std::optional<RankInfo> detect_mpi_rank();

/// How one job ended, as the pool saw it.
struct JobExit {
  bool ok = false;      // the job's callback returned true
  bool started = true;  // false when no worker could be made for it (fork failed)
  std::string how;      // a forked worker's end: "killed by signal 9", "exit code 1" (""
                        // when unknown, and always for threads)
};

/// A job: returns true when it succeeded. In process mode it runs in the forked child, so it
/// reports through files, not memory.
using JobFn = std::function<bool(std::size_t job)>;
/// Called in the calling thread (processes) or under a lock (threads) as each job ends.
using JobDoneFn = std::function<void(std::size_t job, const JobExit& exit)>;

/// Runs jobs 0..n-1 on `workers` workers (at least one) and returns when every job has ended.
void run_jobs(std::size_t n, int workers, WorkerMode mode, const JobFn& job,
              const JobDoneFn& on_done);

}  // namespace reposetwin::experiments
