// Fuzz harness: the scene parser (experiments/io/scene), as `reposetwin run SCENE` reads a file
// (with the PSD files it may name). Beyond a clear refusal, a property of what is accepted: an
// accepted scene's plan is finite and within the limits the parser promises (a positive, finite
// time step; at most 1e11 steps to the time limit; at most 1e4 frames; a positive particle
// count), so no input the parser lets through can make a run that never ends or an overflowed
// count.
#include <cmath>
#include <optional>
#include <string>

#include "experiments/io/scene.hpp"
#include "experiments/pile/run_plan.hpp"
#include "fuzz/fuzz_support.hpp"

namespace {

void check_plan(const reposetwin::experiments::SceneConfig& scene) {
  using reposetwin::fuzz::finding;
  reposetwin::experiments::RunPlan plan;
  try {
    plan = reposetwin::experiments::plan_run(scene, 1);
  } catch (const std::exception& e) {
    finding(std::string("an accepted scene's plan throws: ") + e.what());
  }
  const double dt = plan.time_step_s;
  if (!(dt > 0 && std::isfinite(dt)))
    finding("an accepted scene has time step " + std::to_string(dt));
  if (!(scene.procedure.max_time / dt <= 1e11))
    finding("an accepted scene runs " + std::to_string(scene.procedure.max_time / dt) + " steps");
  if (!(plan.steps > 0))
    finding("an accepted scene plans " + std::to_string(plan.steps) + " steps");
  if (!(plan.particles > 0)) finding("an accepted scene plans no particles");
  if (!std::isfinite(plan.wall_s) || plan.wall_s < 0)
    finding("an accepted scene's wall time is not finite");
  const double every = scene.output.frame_interval;
  if (every > 0 && !(scene.procedure.max_time / every <= 1e4))
    finding("an accepted scene writes " + std::to_string(scene.procedure.max_time / every) +
            " frames");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace reposetwin;
  const std::string path = fuzz::write_input(data, size, "fuzz_scene.toml");
  std::optional<experiments::SceneConfig> scene;
  fuzz::expect_clear_refusal("fuzz_scene.toml",
                             [&] { scene = experiments::parse_scene_file(path); });
  if (scene) check_plan(*scene);
  return 0;
}
