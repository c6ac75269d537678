// Scene loading with command-line overrides ("--set rolling.mu_r=0.1" style), shared by the
// run, render and campaign commands.
#pragma once

#include <string>
#include <vector>

#include "experiments/io/scene.hpp"

namespace reposetwin::experiments {

/// Loads a scene file (or the embedded quick scene when `path` is empty) and applies
/// "dotted.key=value" overrides (the value is TOML: 0.1, "epsd", true, [1, 2]) before parsing.
SceneConfig load_scene(const std::string& path, const std::vector<std::string>& sets = {});

}  // namespace reposetwin::experiments
