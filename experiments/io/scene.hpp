// Scene files: a pile test described in TOML, parsed in one place into plain structs.
//
// The engine never sees TOML: parse_scene() reads the file strictly (unknown keys are errors,
// every error names the file, the key and the value), and build_model() turns the structs into a
// sim::Model. Declared assumptions that the paper leaves open (wall friction, the plate, the
// rolling model, the PSD, the softened stiffness) are all inputs here, never constants in code.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "experiments/io/grain_shape.hpp"
#include "experiments/io/psd_file.hpp"
#include "sim/model.hpp"
#include "sim/pile_geometry.hpp"

namespace reposetwin::experiments {

/// Funnel (conical frustum) or cylinder (the large column), standing on the plate.
struct ContainerConfig {
  std::string kind = "funnel";       // "funnel" or "cylinder"
  std::string material = "steel";
  double bottom_diameter = 0.04;     // W, the outlet [m]
  double top_diameter = 0.19;        // [m] (= bottom for a cylinder)
  double height = 0.12;              // [m]
  double gap = 0.0;                  // clearance between its lower rim and the plate [m]
};

struct ProcedureConfig {
  double lift_speed = 0.01;          // [m/s]
  double settle_speed = 0.005;       // settled when KE/particle < 1/2 m_mean v^2 with this v [m/s]
  double fill_settle_max = 3.0;      // longest settling inside the container [s]
  double final_settle_max = 5.0;     // longest settling after the container is empty [s]
  double max_time = 60.0;            // simulated-time limit of the whole run [s]
  double clog_window = 1.0;          // lodged if the count inside does not change for [s]
  double max_retained_fraction = 0.1; // flow stopped with at most this fraction of the sample
                                     // still inside: that material stays in the container and is
                                     // lifted away with it (cohesive grains on its wall, as in the
                                     // lab), and the pile settles; above it the test clogged [-]
  double lattice_gap = 0.05;         // fill lattice spacing = d_max (1 + this) [-]
  double fill_jitter = 0.0;          // each grain moved off its lattice point by up to this
                                     // fraction of its free room in the cell, seeded: breaks the
                                     // lattice's columns that a poured lab fill never has [-]
  double fill_max_speed = 0.3;       // gentle pour: speeds capped at this while filling [m/s]
};

struct OutputConfig {
  double frame_interval = 0.0;       // simulated time between .vtp frames; 0 = final only [s]
  double checkpoint_interval = 120.0; // wall-clock time between checkpoints [s]
  double progress_interval = 5.0;    // wall-clock time between progress lines [s]
  bool contact_forces = false;       // every frame's particle contacts, not the last one's
                                     // only (ParaView) [-]
};

struct SceneConfig {
  std::string file;                  // the scene file ("<embedded>" for the built-in one)
  std::string name;
  std::string description;
  std::uint64_t seed = 1;
  double mass = 0.02;                // sample mass [kg]
  std::string sample_material = "rock";
  PsdFile psd;
  std::vector<GrainShape> shapes;    // grain shapes (io/grain_shape.hpp); empty: spheres
  std::vector<sim::Material> materials;                 // in file order
  std::map<std::pair<std::string, std::string>, sim::PairParams> contacts;  // both orders
  std::vector<std::pair<std::string, std::string>> contact_pairs;  // each [contacts] table once,
                                                                   // as written ("rock-plate")
  ContainerConfig container;
  std::string plate_material = "plate";
  ProcedureConfig procedure;
  sim::Settings settings;            // numerics
  OutputConfig output;
  sim::PileGeometrySettings pile;    // measurement from particle positions
  std::string resolved_toml;         // the scene as read (after overrides), for the run folder,
                                     // with every contact's optional-effect keys written out
};

/// Parses a scene from TOML text; `file` names it in messages and resolves relative paths.
SceneConfig parse_scene_text(const std::string& text, const std::string& file);
/// Reads and parses a scene file.
SceneConfig parse_scene_file(const std::string& path);
/// (A scene with overrides applied: io/scene_doc.hpp.)

/// The built-in quick scene (data/scenes/quick.toml, compiled in).
const std::string& embedded_quick_scene();

/// Index of a material by name; throws InputError naming the key if absent.
int material_index(const SceneConfig& scene, const std::string& name, const std::string& key);

/// The smallest and largest sphere radius [m] of grains with sieve sizes in [d_min, d_max] [m]:
/// d / 2 for spheres, the components' radii scaled by d for shapes.
std::pair<double, double> grain_radius_range(const SceneConfig& scene, double d_min, double d_max);

/// The radius whose Rayleigh time a clump's step is a fraction of, over its smallest sphere's
/// radius [-]: for the scene's smallest grain of each shape, the sphere of the grain's volume
/// against the smallest sphere of any (1 for spheres). Both scale with the sieve size, so it
/// carries a drawn sample's smallest sphere to its step radius.
double clump_step_ratio(const SceneConfig& scene);

/// The engine model of a scene for particle radii in [r_min, r_max] (walls: plate, container).
/// Wall 0 is the plate, wall 1 the container. A scene of clumps steps at its grains' scale:
/// r_min x clump_step_ratio (sim::Model::finalize).
sim::Model build_model(const SceneConfig& scene, double r_min, double r_max);

}  // namespace reposetwin::experiments
