// Particles as a struct of arrays whose field list is written once.
//
// REPOSETWIN_PARTICLE_FIELDS names every per-particle array with its type and unit. Resizing,
// reordering (the spatial sort), checkpoints and VTK output iterate this list, so a new field
// cannot be forgotten by any of them (after MuJoCo's mjxmacro.h).
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

// X(type, name, unit and meaning)
#define REPOSETWIN_PARTICLE_FIELDS(X)                                   \
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

  /// Appends one particle at rest; returns its index.
  std::size_t add(const Vec3& position, double radius, double density, std::int32_t material,
                  std::int64_t id);
};

}  // namespace reposetwin::sim
