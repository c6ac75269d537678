// Synthetic lab datasets with an undeclared effect, to prove the loop (reposetwin loop-synth).
//
// Design note. A synthetic lab is the twin itself run with hidden settings: a true mu_r, effects
// switched on (any registry row at any value), seeds the loop never uses, and photographs taken
// by a different camera (distance, image noise, and for measurement effects its true height or
// distortion) than the one the lab declares. Only what a lab has is written: the CSV of
// conditions and measured values, the photographs and their declared-camera sidecars, and the
// base scene as the lab's model of its test. The hidden settings stay in memory (the caller
// knows them; the tests assert the loop finds them). Each test is repeated on several piles
// (seeds), as labs repeat a test; the CSV's photo column lists all of its photographs and
// `repeats` says how many piles they show.
//
// The sidecars always declare the camera level with the plate and undistorted, whatever its true
// height, aim and k1; a pile whose photos vision refuses through that declared camera (a tilt its
// base ellipse shows) keeps its photos, its typed H, D and angle averaging only the piles vision
// measured (left empty when none did), so reading the dataset meets the refusal a lab would.
//
// Design file (TOML, strict; a value out of range is an error naming the file, key and value):
//   scene = "tiny_scene.toml"             # base scene, relative to the design file
//   mu_r = 0.2                            # hidden true mu_r
//   seeds = [7001, 7002]                  # hidden pile seeds (one pile per seed and test)
//   [camera]                              # hidden true camera (all optional)
//   distance_radii = 15.0                 # in [10, 1000] pile radii
//   noise_sd = 3.0                        # grey levels, in [0, 128]
//   width_px = 960                        # [64, 8192]
//   height_px = 720                       # [64, 8192]
//   side_views = 2                        # [1, 36]
//   height_m = 0.0                        # true height above the plate [m], in [0, 1]
//   aim_at_axis_foot = false              # true: pitched down at the pile's axis foot
//   k1 = 0.0                              # true lens radial distortion, in [-0.5, 0.5]
//   [hidden]                              # hidden effects: registry name = value (optional)
//   plate_friction = 0.1
//   [[test]]                              # one per lab test; condition columns of docs/loop.md
//   id = "m4_w20"
//   role = "calibrate"
//   mass_kg = 0.004
//   W_mm = 20.0
//   plate = "wood"                        # text columns (the plate material) as strings
#pragma once

#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "experiments/io/synth_design_file.hpp"
#include "experiments/loop/loop_sim.hpp"
#include "experiments/pile/run_plan.hpp"

namespace reposetwin::experiments {

/// A synthetic dataset's design, hidden settings included.
struct SynthDesign {
  std::string scene;                       // absolute path of the base scene
  std::string mu_key = "contacts.{sample}-{sample}.rolling_friction";
  double mu_r = 0.2;                       // hidden true mu_r [-]
  std::vector<std::uint64_t> seeds = {7001, 7002};  // hidden pile seeds
  std::vector<std::pair<std::string, double>> hidden;  // registry name -> value
  ImageVariant camera;                     // true camera (distance, noise, resolution)
  std::vector<SynthTest> tests;
};

/// Reads a design file (see the design note). Throws InputError naming the file and key.
SynthDesign read_synth_design(const std::string& path);

/// The hidden settings as JSON (the truth a validation compares the loop's answer with): the
/// design file, mu_r and the key it is set by, every hidden effect with its value and units, the
/// pile seeds and the true camera. Never written into the dataset's folder (reposetwin
/// loop-synth --truth refuses a path there): the loop must not be able to read it.
nlohmann::json synth_truth_json(const SynthDesign& design, const std::string& design_path);

/// Where loop-synth keeps its simulation cache: `cache` as given, else the folder beside the
/// dataset's, OUT.synth-cache. Never inside the dataset's folder, where the loop reads: the
/// cache's records hold the hidden settings. Throws InputError naming the option for a given
/// cache (or `truth_file`, when not empty) inside OUT.
std::string synth_cache_dir(const std::string& out_dir, const std::string& cache,
                            const std::string& truth_file = "");

/// Runs the hidden twin through `cache` and writes OUT/measured.csv, OUT/scene.toml and
/// OUT/photos/. Returns the path of the CSV. Throws InputError for unknown effect names or
/// condition columns, std::runtime_error when a run fails or forms no pile.
std::string make_synthetic_dataset(const SynthDesign& design, const std::string& out_dir,
                                   SimCache& cache);

/// The piles make_synthetic_dataset() pours, before any is poured: one part per test (its scene
/// with the test's conditions), one run per hidden seed, `workers` side by side. The hidden
/// effects change a pile's physics, not its particle count, so the plan is the base scene's.
BatchPlan plan_synth_dataset(const SynthDesign& design, int workers);

}  // namespace reposetwin::experiments
