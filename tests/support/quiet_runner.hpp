// The campaign runner for tests: threads (no fork inside a test binary), no progress lines, and
// never an MPI rank even under mpirun.
#pragma once

#include "experiments/campaign/campaign.hpp"

namespace reposetwin::test_support {

inline experiments::RunnerSettings quiet_runner() {
  experiments::RunnerSettings r;
  r.mode = experiments::WorkerMode::kThreads;
  r.progress = false;
  r.rank.reset();
  return r;
}

}  // namespace reposetwin::test_support
