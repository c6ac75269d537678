// The worker pool alone: every job runs once in either mode, a forked worker's end is reported
// as it happened, and the MPI position is read from the launcher's variables.
#include "experiments/campaign/pool.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <set>

#include "experiments/io/provenance.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;

TEST(CampaignPool, ThreadsRunEveryJobOnce) {
  std::map<std::size_t, int> runs;  // written under the pool's lock in on_done
  std::set<std::size_t> failed;
  run_jobs(
      7, 3, WorkerMode::kThreads, [](std::size_t k) { return k % 3 != 1; },
      [&](std::size_t k, const JobExit& e) {
        ++runs[k];
        EXPECT_TRUE(e.started);
        EXPECT_TRUE(e.how.empty());
        if (!e.ok) failed.insert(k);
      });
  EXPECT_EQ(runs.size(), 7u);
  for (const auto& [k, n] : runs) EXPECT_EQ(n, 1) << k;
  EXPECT_EQ(failed, (std::set<std::size_t>{1, 4}));
}

TEST(CampaignPool, ProcessesReportHowEachWorkerEnded) {
  const fs::path dir =
      fs::temp_directory_path() / ("reposetwin_pool_test_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  // Job 0 succeeds, 1 returns false, 2 dies by SIGKILL; each child leaves a file to show it ran.
  auto job = [&](std::size_t k) {
    write_file_atomic((dir / std::to_string(k)).string(), "ran");
    if (k == 2) std::raise(SIGKILL);
    return k == 0;
  };
  std::map<std::size_t, JobExit> ends;
  run_jobs(3, 2, WorkerMode::kProcesses, job,
           [&](std::size_t k, const JobExit& e) { ends[k] = e; });
  ASSERT_EQ(ends.size(), 3u);
  EXPECT_TRUE(ends[0].ok);
  EXPECT_EQ(ends[0].how, "exit code 0");
  EXPECT_FALSE(ends[1].ok);
  EXPECT_EQ(ends[1].how, "exit code 1");
  EXPECT_FALSE(ends[2].ok);
  EXPECT_EQ(ends[2].how, "killed by signal 9");
  for (int k = 0; k < 3; ++k) EXPECT_TRUE(fs::exists(dir / std::to_string(k))) << k;
  fs::remove_all(dir);
}

TEST(CampaignPool, MpiRankComesFromTheLaunchersVariables) {
  const char* names[] = {"OMPI_COMM_WORLD_RANK",    "PMIX_RANK",
                         "OMPI_COMM_WORLD_SIZE",    "PMIX_NAMESPACE",
                         "OMPI_MCA_orte_ess_jobid", "OMPI_MCA_ess_base_jobid"};
  for (const char* n : names) ::unsetenv(n);
  EXPECT_FALSE(detect_mpi_rank().has_value());
  ::setenv("PMIX_RANK", "2", 1);
  ::setenv("OMPI_COMM_WORLD_SIZE", "4", 1);
  ::setenv("PMIX_NAMESPACE", "job7", 1);
  auto r = detect_mpi_rank();
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->rank, 2);
  EXPECT_EQ(r->size, 4);
  EXPECT_EQ(r->job, "job7");
  ::setenv("OMPI_COMM_WORLD_RANK", "4", 1);  // a rank outside the size: not an MPI position
  EXPECT_FALSE(detect_mpi_rank().has_value());
  ::setenv("OMPI_COMM_WORLD_RANK", "x", 1);  // unreadable: falls back to PMIX_RANK
  EXPECT_EQ(detect_mpi_rank().value().rank, 2);
  for (const char* n : names) ::unsetenv(n);
}

}  // namespace
}  // namespace reposetwin::experiments
