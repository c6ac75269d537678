// The plan of a pile run, printed before it simulates: what it will cost and whether to start.
//
// Design note. A sieve sheet down to 0.075 mm draws hundreds of thousands of particles and a
// time step set by the smallest, so a run can cost days where the user expected minutes. Before
// anything is simulated, plan_run() predicts from the scene alone (no sampling, no world): the
// particle count (the PSD's expected count, sim::expected_particle_count), the fines fraction
// the cut-off leaves out, the time step (the model's, as the run will use), the simulated time
// (fill settling, the lift over the fill height, the final settling, capped at max_time) and so
// the number of steps, and the wall time at a stated particle-steps/s rate. The rate is a
// setting whose default was measured on whole pile runs on the development machine; the
// simulated time is a rough estimate (within about 30% of the shipped funnel scenes' runs).
// plan_refusal() says why a plan is above the limits (a setting each) and which key shrinks it.
// The plan also says when the pile will not be representative of the lab's test (too low for its
// grains, most of the sieve sheet not simulated, an outlet that jams): representativeness.hpp.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "experiments/io/scene.hpp"
#include "experiments/pile/representativeness.hpp"

namespace reposetwin::experiments {

/// Limits and rates of the plan; every field has a default.
struct PlanSettings {
  // Whole pile runs (fill, lift, settle; contacts, walls, neighbour rebuilds included) of the
  // table1_s1 reduced scene (29.8k particles) on the shared 2-core development machine ran at
  // 0.95-1.5e6 particle-steps/s with one thread and 2.6-3.0e6 with two.
  double particle_steps_per_s_per_thread = 1.3e6;  // [1/s]
  double max_wall_s = 3600.0;                      // above: refused without --yes [s]
  std::int64_t max_particles = 1'000'000;          // above: refused without --yes [-]
};

/// What a run will cost, predicted from its scene.
struct RunPlan {
  std::int64_t particles = 0;             // expected grain (body) count [-]
  std::int64_t components = 0;            // their spheres: = particles for spheres, more for
                                          // clumps, which a step costs by [-]
  double fines_fraction = 0.0;            // mass fraction below d_min, not simulated [-]
  double d_min_mm = 0.0, d_max_mm = 0.0;  // the simulated size range [mm]
  double time_step_s = 0.0;               // the smallest component's, as the run's [s]
  double fill_height_m = 0.0;             // the loose sample's height in the container [m]
  double simulated_time_s = 0.0;          // estimated simulated time of the whole run [s]
  std::int64_t steps = 0;                 // simulated_time_s / time_step_s [-]
  int threads = 1;                        // threads the rate is scaled by [-]
  double particle_steps_per_s = 0.0;      // the rate assumed (per thread x threads), in
                                          // component-steps (a clump's spheres each cost about
                                          // a sphere's step: 155 against 185 ns) [1/s]
  double wall_s = 0.0;                    // estimated wall time [s]
  Representativeness representative;      // pile height, mass not simulated, outlet width
  std::string psd_source, psd_note;       // the sieve table's file, and how it was read when
                                          // not as written (io/psd_file.hpp), or empty
};

/// The plan of `scene` run with `threads` threads. Throws InputError as the scene's checks do.
RunPlan plan_run(const SceneConfig& scene, int threads, const PlanSettings& settings = {});

/// The plan as a few lines for a person (each ending in a newline), with a warning line for each
/// representativeness rule the scene breaks (pile/representativeness.hpp).
std::string plan_text(const RunPlan& plan, const PlanSettings& settings = {});

/// Where the command that plans a run takes its scene keys from, so a refusal's advice names
/// only what a user can type to that command: `run --set`, a scene file's key (timestep), a
/// campaign file's overrides (campaign, calibrate FILE) or a test sheet's column (calibrate
/// --tests, loop).
struct KeySource {
  enum class Kind { kSetOption, kSceneFile, kCampaignFile, kTestSheet };
  Kind kind = Kind::kSetOption;
  std::string file;  // the scene, campaign file or test sheet the key is set in
};

/// How to set scene key `key` to the TOML value `value` through `source`, as words to type.
std::string how_to_set(const KeySource& source, const std::string& key, const std::string& value);

/// Empty when the plan is within the settings' limits; otherwise why not, naming the limit, the
/// key that shrinks the run (sample.d_min_mm, sample.mass_kg), how to set it through `source`
/// and how to go ahead anyway.
std::string plan_refusal(const RunPlan& plan, const KeySource& source,
                         const PlanSettings& settings = {});

/// The plan of many pile runs (a calibration and its predictions): every kind of run with its
/// own plan and count, and the wall time with `workers` runs side by side. The runs of a batch
/// use one thread each, as the campaign pool runs them.
struct BatchPlan {
  struct Part {
    std::string what;  // which runs, for a person ("calibration runs of test t1")
    RunPlan plan;      // one run's plan (threads = 1)
    int runs = 0;      // how many runs of it at most [-]
  };
  std::vector<Part> parts;
  int workers = 1;   // runs side by side [-]
  int runs = 0;      // sum of the parts' runs [-]
  double wall_s = 0.0;  // sum(runs x wall) / workers [s]
};

/// A batch of `parts` on `workers` runs at once.
BatchPlan plan_batch(std::vector<BatchPlan::Part> parts, int workers);

/// The batch's plan for a person: its total, then every part's plan_text, indented.
std::string plan_text(const BatchPlan& plan, const PlanSettings& settings = {});

/// As plan_refusal of one run: the largest run's particles and the batch's wall time against
/// the limits; empty when within them.
std::string plan_refusal(const BatchPlan& plan, const KeySource& source,
                         const PlanSettings& settings = {});

/// "45s", "12m5s", "3h20m", "4d6h": a duration for a person.
std::string duration_text(double seconds);

}  // namespace reposetwin::experiments
