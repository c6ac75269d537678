#pragma once
// Shared by the campaign-file tests (tests/experiments/io) and the campaign runner's tests: a
// scratch folder holding a small scene, and a campaign of two cases crossed with two seeds.

#include <unistd.h>

#include <filesystem>
#include <string>

#include "experiments/io/provenance.hpp"

namespace reposetwin::experiments::campaign_fixtures {
namespace fs = std::filesystem;

inline constexpr const char* kScene = R"(
seed = 1
[rolling]
model = "epsd"
mu_r = 0.1
[sample]
mass = 0.2
[contacts.rock-rock]
rolling_friction = 0.15
)";

// A fresh folder holding scene.toml.
inline fs::path fresh_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() /
                     ("reposetwin_campaign_test_" + std::to_string(::getpid()) + "_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  write_file_atomic((d / "scene.toml").string(), kScene);
  return d;
}

inline fs::path write_campaign(const fs::path& dir, const std::string& text,
                        const std::string& file = "campaign.toml") {
  write_file_atomic((dir / file).string(), text);
  return dir / file;
}

// A fresh folder removed at the end of the test (forked children _exit and leave it alone).
struct ScratchDir {
  explicit ScratchDir(const std::string& name) : path(fresh_dir(name)) {}
  ~ScratchDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  fs::path path;
};

inline constexpr const char* kCasesCampaign = R"(
name = "cases_demo"
description = "two cases"
paper = "Fig. 8"
scene = "scene.toml"
seeds = [1, 2]
overrides = { "sample.mass" = 0.9 }
[[case]]
name = "low"
overrides = { "rolling.mu_r" = 0.05 }
[[case]]
name = "high"
overrides = { rolling.mu_r = 0.2, "sample.mass" = 1 }
)";

}  // namespace reposetwin::experiments::campaign_fixtures
