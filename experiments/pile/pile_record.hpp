// The record of one pile run: what run_pile_test() returns and what result.json holds.
//
// Design note. A pile run crosses every later stage (photographs, campaigns, calibration, the
// loop, reports), so it travels as this typed record, never as a JSON object searched by key.
// Its one JSON form is written and read here (to_json / *_from_json), and keeps the result.json
// fields the files have always had. Readers take what identifies a record (a stop's reason, a
// pile's status) as required and every other field with its default when absent, so result
// files of older versions and reduced results (a case's) are still read. Why a run
// stopped is an enum carried from the engine's sim::Status (a physics stop) or from the
// controller (settled, clogged, time limits); its text form ("settled", "physics: nan") exists
// only in the file.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "sim/pile_geometry.hpp"
#include "sim/psd.hpp"
#include "sim/world.hpp"

namespace reposetwin::experiments {

/// Why a pile run ended.
enum class StopReason {
  kSettled,          // the pile's kinetic energy per particle fell below the threshold
  kSettleTimeLimit,  // the last settling reached procedure.final_settle_max
  kTimeLimit,        // the whole run reached procedure.max_time
  kClogged,          // particles arched in the outlet: no pile
  kPhysics,          // the engine reported trouble (RunStop::physics says which)
};

/// How and why a run ended.
struct RunStop {
  StopReason reason = StopReason::kSettled;
  sim::Status physics = sim::Status::kOk;  // the engine's status when reason is kPhysics
  std::string detail;                      // a sentence: which particle, how many lodged, ...
  std::string likely_cause;                // a physics stop: the scene keys that most likely
                                           // caused it (physics_stop_hint); else ""
  bool is_physics() const { return reason == StopReason::kPhysics; }
};

/// The file text of a stop ("settled", "settle time limit", "time limit", "clogged",
/// "physics: nan" ...).
std::string stop_reason_text(const RunStop& stop);
/// The stop of a result file's "stop" object; std::invalid_argument for an unknown reason.
RunStop stop_from_json(const nlohmann::json& j);
nlohmann::json to_json(const RunStop& stop);

/// One protractor slice as recorded (angles in degrees).
struct PileSliceRecord {
  double azimuth_deg = 0.0;
  bool valid = false;
  double angle_deg = 0.0;
  double equal_area_angle_deg = 0.0;
};

/// The pile measured from particle positions (sim/pile_geometry), or the clogged outlet's
/// "no pile" with the particles lodged in it.
struct PileMeasure {
  sim::PileStatus status = sim::PileStatus::kNoPile;
  bool clogged = false;               // the outlet clogged: only status, detail, lodged are set
  bool not_measured = false;          // the run ended in a state that is no pile (a physics stop):
                                      // only status (kNoPile) and detail are set
  std::int64_t lodged = 0;            // particles lodged in the container (clogged) [-]
  std::string detail;                 // why there is no pile (clogged)
  double height_m = 0.0;              // H [m]
  double base_diameter_m = 0.0;       // D [m]
  double theta_hd_deg = 0.0;          // atan(2H/D) [deg]
  double slice_angle_mean_deg = 0.0;  // protractor on centre slices, mean over azimuths [deg]
  double slice_angle_sd_deg = 0.0;    // its spread over azimuths [deg]
  double flank_angle_sd_deg = 0.0;    // spread of the single flanks [deg]
  int valid_slices = 0;
  double equal_area_angle_deg = 0.0;
  double centre_of_mass_angle_deg = 0.0;
  double centre_x_m = 0.0, centre_y_m = 0.0;  // footprint centre [m]
  std::int64_t pile_count = 0, footprint_count = 0, stray_count = 0;
  double median_diameter_m = 0.0;
  std::vector<PileSliceRecord> slices;
};

/// The record of a measured pile geometry (angles converted to degrees).
PileMeasure pile_measure(const sim::PileGeometry& g);
/// The record of a clogged outlet.
PileMeasure clogged_pile(std::int64_t lodged, const std::string& detail);
/// The record of a run that ended in no pile to measure (a physics stop), saying why.
PileMeasure unmeasured_pile(const std::string& detail);
nlohmann::json to_json(const PileMeasure& p);
PileMeasure pile_measure_from_json(const nlohmann::json& j);

/// One sieve interval as sampled.
struct PsdIntervalRecord {
  double lower_mm = 0.0, upper_mm = 0.0;  // [mm]
  double target_mass_fraction = 0.0, drawn_mass_fraction = 0.0;
  std::int64_t count = 0;
};

/// The PSD as sampled: where the sieve table came from and what was drawn (sizes in mm, the
/// file's unit, so the record round-trips exactly).
struct PsdRecord {
  std::string source, name, provenance, assumption;  // of the sieve table (io/psd_file.hpp)
  double target_mass_kg = 0.0, simulated_target_mass_kg = 0.0, drawn_mass_kg = 0.0;
  std::int64_t count = 0;
  double d_min_mm = 0.0, d_max_mm = 0.0;              // declared cut-off and scalping size
  double d_min_drawn_mm = 0.0, d_max_drawn_mm = 0.0;  // what was drawn
  double fines_fraction_not_simulated = 0.0;          // mass fraction below d_min [-]
  double scalped_fraction = 0.0;                      // mass fraction above d_max [-]
  sim::FinesPolicy fines_policy = sim::FinesPolicy::kRenormalise;
  std::vector<PsdIntervalRecord> intervals;
};
/// The record of a sampling from a sieve table described by source/name/provenance/assumption.
PsdRecord psd_record(const sim::PsdSummary& s, const std::string& source, const std::string& name,
                     const std::string& provenance, const std::string& assumption);
nlohmann::json to_json(const PsdRecord& p);
PsdRecord psd_record_from_json(const nlohmann::json& j);

/// A phase change of the controller, with its simulated time.
struct RunEvent {
  double t = 0.0;                           // [s]
  std::string event;                        // "filled", "lift started", "resumed", ...
  std::optional<std::int64_t> particles;    // "filled": the sample's particle count
  std::optional<std::string> code_version;  // "resumed": the engine that resumed
};
/// An event at `t` [s], with its optional particle count or code version.
RunEvent run_event(double t, std::string what, std::optional<std::int64_t> particles = {},
                   std::optional<std::string> code_version = {});
nlohmann::json to_json(const RunEvent& e);
RunEvent run_event_from_json(const nlohmann::json& j);
nlohmann::json to_json(const std::vector<RunEvent>& events);
std::vector<RunEvent> run_events_from_json(const nlohmann::json& j);

/// The particle count through the run.
struct ParticleCounts {
  std::int64_t initial = 0;                // as filled
  std::int64_t final = 0;                  // in the settled pile's world
  std::int64_t retained_in_container = 0;  // stuck inside and lifted away with the container
  double retained_mass_kg = 0.0;
};
nlohmann::json to_json(const ParticleCounts& c);
ParticleCounts particle_counts_from_json(const nlohmann::json& j);

/// The procedure as it ran.
struct ProcedureRecord {
  double lift_speed_m_s = 0.0;
  double lift_start_s = -1.0, lift_end_s = -1.0, end_s = 0.0;  // [s]; -1 = did not happen
  double clog_window_s = 0.0;
  double max_retained_fraction = 0.0;
  double ke_threshold_j = 0.0;
  std::string container_kind;
  double container_bottom_diameter_m = 0.0, container_top_diameter_m = 0.0;
  double container_height_m = 0.0;
  std::vector<RunEvent> events;
};

/// How fast the run went.
struct RunPerformance {
  std::int64_t steps = 0;
  double wall_s = 0.0;  // all sessions of the run [s]
  double cpu_s = 0.0;   // the process's CPU time (every thread) over all sessions [s]
  double particle_steps_per_s = 0.0;
  std::int64_t neighbor_builds = 0;
  double max_overlap_ratio_seen = 0.0;  // largest overlap / smaller radius at any check [-]
};
nlohmann::json to_json(const RunPerformance& p);
RunPerformance run_performance_from_json(const nlohmann::json& j);

/// How the run was made.
struct RunProvenance {
  std::string scene_file, scene_name;
  std::uint64_t seed = 0;
  std::string code_version;
  std::string engine_version;  // the engine's source hash (engine_version()); empty: older run
  double time_step_s = 0.0, rayleigh_time_s = 0.0;
  std::optional<double> softened_youngs_modulus_pa;  // absent: the material's own modulus
  double youngs_modulus_real_pa = 0.0;
  int threads = 0;
  std::string created_utc;
  nlohmann::json extra = nlohmann::json::object();  // the caller's additions (campaign case,
                                                    // loop overrides), written as given
};
nlohmann::json to_json(const RunProvenance& p);
RunProvenance run_provenance_from_json(const nlohmann::json& j);

/// One grain shape of a clump sample as drawn (io/grain_shape.hpp).
struct GrainShapeRecord {
  std::string name, kind;              // kind: "template", "generated" or "blocky"
  double target_mass_fraction = 0.0;   // as declared [-]
  double drawn_mass_fraction = 0.0;    // of the drawn sample [-]
  std::int64_t count = 0;              // grains drawn
  int components = 0;                  // spheres per grain
  double elongation = 1.0, flatness = 1.0, roundness = 1.0;  // nominal (generated) [-]
  double angularity = 0.0;                                     // nominal (blocky) [-]
  double measured_elongation = 1.0, measured_flatness = 1.0; // L/I, I/S of the body built [-]
  double volume_per_cube = 0.0;        // volume / sieve size^3 of the union of its spheres [-]
  double outlet_diameter = 0.0;        // smallest round outlet it passes lengthwise, in sieve
                                       // sizes [-]
};

/// The grains of a clump sample; absent from the result of a sphere sample.
struct ShapeRecord {
  std::string sieve_convention;        // how a clump's sieve size is defined
  std::vector<GrainShapeRecord> shapes;
  std::int64_t bodies_initial = 0, bodies_final = 0;          // clumps as filled, in the pile
  std::int64_t components_initial = 0, components_final = 0;  // their spheres
};
nlohmann::json to_json(const ShapeRecord& s);
ShapeRecord shape_record_from_json(const nlohmann::json& j);

/// The spheres of a pile: centres [m], radii [m] and material ids, in one order; for clumps,
/// the component spheres with their body's id (empty for a sphere sample).
struct PileSpheres {
  std::vector<Eigen::Vector3d> x;
  std::vector<double> radius;
  std::vector<int> material;
  std::vector<std::int64_t> body{};  // body id of each sphere; empty when none is a clump's
};

/// One finished pile run (result.json).
struct PileRun {
  RunProvenance provenance;
  RunStop stop;
  PileMeasure pile;
  PsdRecord psd;
  ParticleCounts particles;  // grains: spheres, or clumps (bodies) for a clump sample
  std::optional<ShapeRecord> shape;  // a clump sample's shapes and counts; none for spheres
  ProcedureRecord procedure;
  RunPerformance performance;
  /// The final state's spheres, in memory only (the file holds them in final.vtp): empty for a
  /// run read back from its result.json.
  PileSpheres final_spheres;
  /// True when the pile's geometry was measured in full ("ok": not clogged, flanks found).
  bool pile_ok() const {
    return !pile.clogged && !pile.not_measured && pile.status == sim::PileStatus::kOk;
  }
};
nlohmann::json to_json(const PileRun& r);
/// Reads a result.json; std::invalid_argument (nlohmann's errors are rethrown as such) naming
/// the field when it is not a pile run's result.
PileRun pile_run_from_json(const nlohmann::json& j);

}  // namespace reposetwin::experiments
