#pragma once
// The pile run's controller state: the phase it is in, its clocks and counts, why it stopped.
// It is saved as controller.json beside every engine checkpoint, so a run resumes in the phase,
// with the counters, it was checkpointed in; the engine's own state lives in checkpoint.bin.
// Internal to experiments/pile (pile_run.cpp is its one user).

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "experiments/pile/pile_record.hpp"

namespace reposetwin::experiments::pile_detail {

enum class Phase { kFill, kLift, kSettle, kDone };

const char* phase_name(Phase p);
Phase phase_from(const std::string& s);

/// The controller's own state: saved beside each engine checkpoint (controller.json).
struct Controller {
  Phase phase = Phase::kFill;
  double phase_start = 0.0;       // [s]
  double lift_start = -1.0;       // [s]
  double lift_end = -1.0;         // [s]
  std::int64_t inside_last = -1;  // particles inside the container at the last check
  double inside_changed = 0.0;    // when that count last changed [s]
  double next_frame = 0.0;        // [s]
  int frames = 0;
  double ke_threshold = 0.0;        // KE per particle below which the pile is settled [J]
  double r_min = 0.0, r_max = 0.0;  // particle radii the model was built for [m]
  double wall_seconds = 0.0;        // wall time of earlier sessions of this run [s]
  double cpu_seconds = 0.0;         // CPU time of earlier sessions of this run [s]
  double max_overlap_seen = 0.0;    // largest overlap / smaller radius at any check [-]
  std::int64_t retained = 0;        // particles left in the container and lifted away with it
  double retained_mass = 0.0;       // their mass [kg]
  std::string scene_hash;           // FNV-1a of the resolved scene the run was started from
  std::string templates_hash;       // FNV-1a of the clump templates ("" for spheres)
  std::string code_version;         // the code that wrote this state
  std::string engine_version;       // its engine's source hash (engine_version())
  std::int64_t step = -1;           // the engine step of the checkpoint written with it
  RunStop stop;                     // why the run ended (when phase is kDone)
  PsdRecord psd;                    // the PSD sampling
  std::vector<RunEvent> events;     // phase changes with their times


  nlohmann::json to_json() const;
  static Controller from_json(const nlohmann::json& j);
};

}  // namespace reposetwin::experiments::pile_detail
