// Particles as a struct of arrays whose field list is written once.
//
// REPOSETWIN_PARTICLE_FIELDS names every per-particle array with its type and unit. Resizing,
// reordering (the spatial sort), removal and checkpoints iterate this list, so a new field cannot
// be forgotten by any of them (after MuJoCo's mjxmacro.h). VTK output writes, by name, the fields
// a viewer needs.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "sim/contact.hpp"
#include "sim/huge_pages.hpp"

namespace reposetwin::sim {

/// Most walls a scene may have (plate, funnel, column, gate, ...).
inline constexpr int kMaxWalls = 6;

/// The contact history of one particle with each wall.
using WallHistory = std::array<ContactHistory, kMaxWalls>;

// X(type, name, unit and meaning). The list is the core fields, then the clump fields (kept apart
// because checkpoints written before clumps existed hold the core fields only).
#define REPOSETWIN_PARTICLE_FIELDS(X) \
  REPOSETWIN_PARTICLE_CORE_FIELDS(X)  \
  REPOSETWIN_PARTICLE_CLUMP_FIELDS(X)

#define REPOSETWIN_PARTICLE_CORE_FIELDS(X)                              \
  X(Vec3, x, "position [m]")                                            \
  X(Vec3, v, "velocity [m/s]")                                          \
  X(Vec3, w, "angular velocity [rad/s]")                                \
  X(Vec3, force, "force accumulated this step [N]")                     \
  X(Vec3, torque, "torque accumulated this step [N m]")                 \
  X(double, radius, "radius [m]")                                       \
  X(double, mass, "mass [kg]")                                          \
  X(double, inertia, "moment of inertia, 2/5 m r^2 [kg m^2]")           \
  X(std::int32_t, material, "material index into Model::materials")     \
  X(std::int64_t, id, "stable particle id, unchanged by reordering")         \
  X(WallHistory, wall_history, "tangential and rolling springs per wall")

// A component of a clump has the body's mass in `mass` (the contact kernels' damping then uses
// the body's mass, as LIGGGHTS multisphere does: the mass that actually moves) and 2/5 of the
// body's mass times its own radius squared in `inertia` (read only by the EPSD rolling dashpot's
// effective inertia, which for a one-sphere clump is then the sphere's).
#define REPOSETWIN_PARTICLE_CLUMP_FIELDS(X)                                          \
  X(std::int32_t, body, "index of the particle's clump in State::bodies; -1 = a sphere") \
  X(std::int32_t, component, "the particle's place in its clump's template; -1 = a sphere")

/// Per-particle arrays, all of the same length.
struct Particles {
#define REPOSETWIN_DECLARE_FIELD(type, name, doc) HugeVector<type> name;  // doc
  REPOSETWIN_PARTICLE_FIELDS(REPOSETWIN_DECLARE_FIELD)
#undef REPOSETWIN_DECLARE_FIELD

  std::size_t size() const { return x.size(); }

  void resize(std::size_t n) {
#define REPOSETWIN_RESIZE_FIELD(type, name, doc) name.resize(n);
    REPOSETWIN_PARTICLE_FIELDS(REPOSETWIN_RESIZE_FIELD)
#undef REPOSETWIN_RESIZE_FIELD
  }

  /// Reorders every field by `order` (new index i takes old index order[i]).
  void permute(const std::vector<std::size_t>& order);

  /// Keeps the particles whose flag is true, in order.
  void keep(const std::vector<char>& flags);

  /// Appends one particle (a sphere, in no clump) at rest; returns its index.
  std::size_t add(const Vec3& position, double radius, double density, std::int32_t material,
                  std::int64_t id);
};

/// Mass of a sphere, density 4/3 pi r^3 [kg] (one expression, so that a one-sphere clump and a
/// sphere of the same radius have the same bits).
inline double sphere_mass(double density, double r) {
  return density * 4.0 / 3.0 * 3.14159265358979323846 * r * r * r;
}

}  // namespace reposetwin::sim
