// Wall geometry: the closest-point test between a sphere and a wall.
//
// Walls are analytic (no meshes): an infinite plane, touched from its normal side, and a thin
// axisymmetric shell (conical frustum or cylinder about a vertical axis, open at both ends),
// touched from inside and outside. For the shell the closest point is found in the meridional
// half-plane (rho, z) of the sphere's centre, on the segment from (r_bottom, z_bottom) to
// (r_top, z_top); its end points are the rims, so a sphere resting on a rim is handled too.
#pragma once

#include "sim/contact.hpp"
#include "sim/model.hpp"

namespace reposetwin::sim {

/// Where a wall is now and how fast it moves (translation only).
struct WallState {
  Vec3 offset = Vec3::Zero();    // displacement since time zero [m]
  Vec3 velocity = Vec3::Zero();  // current velocity [m/s]
  bool enabled = true;           // a disabled wall exerts no force (a removed gate)
};

/// Overlap test of a sphere (centre x, radius r) with a wall displaced by `offset`.
/// On contact returns true with the unit normal from the wall to the centre and the overlap.
bool wall_contact(const WallSpec& wall, const Vec3& offset, const Vec3& x, double r, Vec3* n,
                  double* delta);

}  // namespace reposetwin::sim
