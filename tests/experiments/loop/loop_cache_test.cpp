// The loop's cache across machines: a session's machine may not be kept, so a long loop is
// carried to the next one by its small files (scripts/collect_results.sh: every JSON and TOML,
// no snapshots, frames or checkpoints). A pile run and its photograph count as done when their
// result.json exists, so a collected cache must resume with nothing simulated again and the
// same measurements.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "experiments/io/hash.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/loop/loop.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;

TEST(LoopCache, ACollectedCacheResumesOnAnotherMachineWithoutSimulating) {
  const fs::path root = fs::temp_directory_path() /
                        ("reposetwin_loop_cache_test_" + fnv1a_hex(code_version()));
  fs::remove_all(root);
  const LabData data =
      read_lab_csv(std::string(REPOSETWIN_SOURCE_DIR) + "/data/loop/example.csv");
  ImageVariant img;
  img.width_px = 640;
  img.height_px = 480;
  const std::vector<SimRequest> req = {
      make_request(data.tests[1], "contacts.{sample}-{sample}.rolling_friction", 0.3, 7, {}, img)};

  SimCache first((root / "machine_a" / "cache").string(), {1, false});
  const SimOutcome a = first.run(req).at(0);
  ASSERT_TRUE(a.pile);
  EXPECT_EQ(first.simulations_started(), 1);
  EXPECT_EQ(first.photos_started(), 1);

  // What a session commits: the collected small files, without the pile's particles.
  const std::string cmd = "bash " + std::string(REPOSETWIN_SOURCE_DIR) +
                          "/scripts/collect_results.sh " + (root / "machine_a").string() + " " +
                          (root / "machine_b").string() + " > /dev/null";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  int vtp = 0;
  for (const auto& e : fs::recursive_directory_iterator(root / "machine_b"))
    vtp += e.path().extension() == ".vtp";
  EXPECT_EQ(vtp, 0) << "the collected cache carries particle snapshots";

  SimCache second((root / "machine_b" / "cache").string(), {1, false});
  const SimOutcome b = second.run(req).at(0);
  EXPECT_EQ(second.simulations_started(), 0);
  EXPECT_EQ(second.photos_started(), 0);
  ASSERT_TRUE(b.pile);
  EXPECT_EQ(b.angle_deg, a.angle_deg);
  EXPECT_EQ(b.height_mm, a.height_mm);
  EXPECT_EQ(b.diameter_mm, a.diameter_mm);
  EXPECT_EQ(b.seed, a.seed);
  EXPECT_EQ(b.provenance, a.provenance);
  fs::remove_all(root);
}

}  // namespace
}  // namespace reposetwin::experiments
