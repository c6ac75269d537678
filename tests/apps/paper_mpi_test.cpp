// `reposetwin paper` under `mpirun`, as a cluster user starts it: the runs spread over the ranks
// (each rank runs its share, rank 0 writes the records) and every run's result has the same bits
// as the local pool's, so a paper item may be made on either and compared.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "tests/apps/cli_support.hpp"
#include "tests/support/tiny_scene.hpp"

namespace {
namespace fs = std::filesystem;
using reposetwin::test_support::fresh_dir;
using reposetwin::test_support::quoted;
using reposetwin::test_support::read_text;
using reposetwin::test_support::write_text;

constexpr const char* kIndex = R"(title = "tiny"
budget_cpu_hours = 1.0
[[item]]
name = "sweep"
paper = "Fig. 6"
kind = "campaign"
file = "sweep.toml"
reductions = "the tiny scene"
x_key = "contacts.rock-rock.rolling_friction"
)";

constexpr const char* kSweep = R"(name = "tiny_sweep"
scene = "tiny.toml"
seeds = [1, 2]
[sweep]
key = "contacts.rock-rock.rolling_friction"
values = [0.4]
)";

// The command's exit code; its messages go to `log`.
int shell(const std::string& cmd, const fs::path& log) {
  const int status = std::system((cmd + " </dev/null >" + quoted(log) + " 2>&1").c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

nlohmann::json run_result(const fs::path& out, int seed) {
  const fs::path f =
      out / "sweep" / "cases" / "rolling_friction_0.4" / ("seed_" + std::to_string(seed)) /
      "result.json";
  return nlohmann::json::parse(read_text(f));
}

TEST(PaperMpi, RanksSplitTheRunsAndGiveThePoolsBits) {
  const fs::path d = fresh_dir("paper_mpi");
  write_text(d / "tiny.toml", reposetwin::test_support::kTinyScene);
  write_text(d / "sweep.toml", kSweep);
  write_text(d / "index.toml", kIndex);
  const std::string bin = quoted(REPOSETWIN_BIN);
  const std::string index = quoted(d / "index.toml");

  // install_deps.sh installs OpenMPI; a machine without mpirun cannot show this, so say so.
  ASSERT_EQ(shell("command -v mpirun", d / "which.log"), 0)
      << "mpirun not found (scripts/install_deps.sh installs openmpi-bin)";
  const int mpi = shell("mpirun --allow-run-as-root --oversubscribe -n 2 -x OMP_NUM_THREADS=1 " +
                            bin + " paper " + index + " --out " + quoted(d / "mpi"),
                        d / "mpi.log");
  ASSERT_EQ(mpi, 0) << read_text(d / "mpi.log");
  const int pool = shell(bin + " paper " + index + " --workers 2 --out " + quoted(d / "pool"),
                         d / "pool.log");
  ASSERT_EQ(pool, 0) << read_text(d / "pool.log");

  // Each rank ran one of the two runs.
  const std::string log = read_text(d / "mpi.log");
  EXPECT_NE(log.find("rank 0/2] 1 run(s) to do"), std::string::npos) << log;
  EXPECT_NE(log.find("rank 1/2] 1 run(s) to do"), std::string::npos) << log;
  for (int seed : {1, 2}) {
    const nlohmann::json a = run_result(d / "mpi", seed), b = run_result(d / "pool", seed);
    ASSERT_TRUE(a["result"].contains("headline_angle_deg")) << a.dump(1);
    EXPECT_EQ(a["result"]["headline_angle_deg"], b["result"]["headline_angle_deg"]) << seed;
    EXPECT_EQ(a["result"]["pile"], b["result"]["pile"]) << seed;
  }
  // Rank 0 wrote the item's records, once, naming both runs finished.
  const nlohmann::json listing = nlohmann::json::parse(read_text(d / "mpi" / "paper.json"));
  ASSERT_EQ(listing["items"].size(), 1u);
  EXPECT_EQ(listing["items"][0]["status"], "done") << listing.dump(1);
  EXPECT_EQ(listing["items"][0]["finished_runs"], 2) << listing.dump(1);
  EXPECT_TRUE(fs::is_regular_file(d / "mpi" / "sweep" / "provenance.json"));
  fs::remove_all(d);
}

}  // namespace
