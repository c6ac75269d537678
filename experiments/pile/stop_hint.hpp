// stop_hint: which scene keys most likely caused a physics stop, in the user's own key names.
//
// Design note. The parser refuses what is out of range before a run, but values inside their
// ranges can still break one (a step near the stability limit on a stiff, fast pour; a softened
// stiffness too low for the impacts). The engine knows only that a state went non-finite, a
// grain escaped or an overlap grew too large; this maps that status to the inputs that govern
// it, with their values as the scene set them, so the message says what to change.
#pragma once

#include <string>

#include "experiments/io/scene.hpp"
#include "sim/world.hpp"

namespace reposetwin::experiments {

/// One sentence naming the scene keys (as written in a scene file, with their values) that most
/// likely caused a physics stop of status `status`, and which way to move them; "" for kOk.
std::string physics_stop_hint(sim::Status status, const SceneConfig& scene);

}  // namespace reposetwin::experiments
