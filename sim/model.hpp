// Model: everything fixed for a run (materials, pair parameters, walls, settings).
//
// Design note (after MuJoCo's mjModel/mjData split): the Model is built once from a scene and
// never changes while the run steps; everything that changes every step lives in State
// (sim/world.hpp). Materials are indexed by small integers; the pair table holds the contact
// parameters of every pair of materials, walls included (a wall has a material like a particle),
// so "rock on steel funnel" and "rock on rubber plate" are separate, declared inputs.
#pragma once

#include <Eigen/Core>
#include <limits>
#include <string>
#include <vector>

#include "sim/clump.hpp"
#include "sim/contact.hpp"

namespace reposetwin::sim {

/// Elastic properties and density of one material (particles or walls).
struct Material {
  std::string name = "rock";
  double density = 2760.0;         // [kg/m^3] (ignored for wall materials)
  double youngs_modulus = 46.8e9;  // E [Pa], the material's real value
  double poisson_ratio = 0.19;     // nu [-]
};

/// Contact parameters of one pair of materials (symmetric).
struct PairParams {
  double restitution = 0.79;       // e in (0, 1] [-]
  double friction = 0.466;         // static (Coulomb) friction mu_s [-]
  double rolling_friction = 0.15;  // mu_r [-], meaning depends on the rolling model (contact.hpp)
  RollingModel rolling_model = RollingModel::kEpsd;  // rolling resistance law
  double rolling_damping = 0.3;    // eta_r, EPSD viscous damping ratio [-]
  // Optional effects, off by default (contact.hpp: sjkr_cohesion, rolling_size_factor).
  double cohesion_energy_density = 0.0;  // k_c [J/m^3 = Pa]: simplified-JKR cohesion
                                         // F_c = pi k_c R* delta while overlapping; 0 = none
  double rolling_size_exponent = 0.0;    // alpha [-]: mu_r,eff = mu_r (d_c / d_ref)^alpha,
                                         // d_c = 4 R* (2 R_i on a wall); 0 = mu_r for all sizes
  double rolling_reference_diameter = 0.0;  // d_ref [m], where mu_r,eff = mu_r; must be > 0
                                            // when alpha != 0 (unused otherwise)
};

/// Axisymmetric wall geometry about a vertical axis through `axis_xy`.
enum class WallKind {
  kPlane,  // infinite plane through `point` with unit `normal` (particles on the normal side)
  kShell,  // thin conical frustum (or cylinder), open at both ends, touched from both sides
};

/// A wall's shape at time zero; its displacement since then is in State::walls.
struct WallSpec {
  std::string name = "plate";
  WallKind kind = WallKind::kPlane;
  int material = 1;  // index into Model::materials
  // kPlane
  Eigen::Vector3d point{0.0, 0.0, 0.0};   // a point on the plane [m]
  Eigen::Vector3d normal{0.0, 0.0, 1.0};  // unit normal towards the particles [-]
  // kShell: radius varies linearly from r_bottom at z_bottom to r_top at z_top
  Eigen::Vector2d axis_xy{0.0, 0.0};  // axis position [m]
  double z_bottom = 0.0;              // [m]
  double z_top = 0.12;                // [m]
  double r_bottom = 0.02;             // [m]
  double r_top = 0.095;               // [m]
};

/// Numerical settings. Every field has a default; SI units.
struct Settings {
  Eigen::Vector3d gravity{0.0, 0.0, -9.81};  // [m/s^2]
  double rayleigh_fraction = 0.2;  // dt = fraction * Rayleigh time of the smallest particle [-]
  double time_step = 0.0;          // explicit dt [s]; 0 = from rayleigh_fraction
  double max_rayleigh_fraction = 0.5;  // a dt above this fraction of T_R is refused [-]
  double softened_youngs_modulus = 0.0;  // E used for every material [Pa]; 0 = real E
  double skin = 0.0;           // Verlet skin [m]; 0 = 0.25 * smallest diameter
  int threads = 0;             // OpenMP threads; 0 = OpenMP's default
  int parallel_min_particles = 2000;  // fewer particles run each phase on one thread [-]
  double max_overlap_ratio = 0.2;   // overlap / smaller radius above this stops the run [-]
                                    // (a blow-up guard; the largest overlap seen is reported)
  double initial_overlap_tolerance = 0.01;  // largest overlap allowed at the start [-]
  double escape_distance = 1.0;     // a particle farther than this from the origin escaped [m]
};

/// Precomputed contact constants of one material pair (derived from Material and PairParams).
struct PairTable {
  int n = 0;                            // number of materials
  std::vector<PairParams> params;       // n x n, symmetric
  std::vector<ContactConstants> consts; // n x n, symmetric
  const PairParams& p(int a, int b) const { return params[a * n + b]; }
  const ContactConstants& c(int a, int b) const { return consts[a * n + b]; }
};

struct Model {
  std::vector<Material> materials;
  std::vector<PairParams> pairs;  // n x n, row-major, symmetric
  std::vector<WallSpec> walls;
  std::vector<ClumpTemplate> clumps;  // clump templates (add_clump_template), in the body frame
  // The materials particles may be made of; empty: every material. With the walls' materials
  // they set the time step, so a declared material nothing is made of changes nothing.
  std::vector<int> particle_materials;
  Settings settings;

  // Derived by finalize():
  PairTable table;
  double dt = 0.0;               // the time step used [s]
  double rayleigh_time = 0.0;    // of the smallest particle (a clump's smallest sphere) [s]
  double step_radius = 0.0;      // the radius whose Rayleigh time dt is a fraction of [m]
  double r_min = 0.0;            // smallest particle radius the model was finalised for [m]
  double r_max = 0.0;            // largest [m]

  /// Sets the parameters of the pair (a, b) and (b, a).
  void set_pair(int a, int b, const PairParams& p);

  /// Validates a clump shape, derives its template (sim/clump.hpp: mass properties, principal
  /// frame) and appends it to `clumps`; returns its index. Throws std::invalid_argument for a
  /// bad shape (make_clump_template). The components' radii must lie within the radii passed to
  /// finalize().
  int add_clump_template(const ClumpShape& shape, const MassPropertySettings& settings = {});

  /// Young's modulus in use for material m (softened if asked) [Pa].
  double youngs_modulus_used(int m) const;

  /// Validates every input and derives the pair constants and the time step for particle radii
  /// in [r_min, r_max]. Throws std::invalid_argument naming the field and the value.
  /// The step is rayleigh_fraction of the Rayleigh time at `r_step` (0: r_min), never above
  /// max_rayleigh_fraction of the smallest particle's. A rigid clump's contacts move its whole
  /// mass, so a scene of clumps passes the radius of its smallest grain's sphere of equal volume
  /// (experiments' build_model): the step of its 1.06 mm spheres against the grain's.
  void finalize(double r_min, double r_max, double r_step = 0.0);
};

/// Rayleigh wave time of a sphere, T_R = pi R sqrt(rho/G) / (0.1631 nu + 0.8766) [s].
double rayleigh_time(double radius, double density, double youngs_modulus, double poisson);

/// Hertz collision time of two bodies at impact speed v,
/// t_c = 2.87 (m*^2 / (R* E*^2 v))^(1/5) [s] (elastic, head-on).
double hertz_contact_time(double m_eff, double r_eff, double e_eff, double speed);

}  // namespace reposetwin::sim
