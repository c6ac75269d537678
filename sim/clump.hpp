// Rigid clumps of spheres (multi-sphere grains): templates, their mass properties, and the
// free-rotor step of the rigid-body integrator.
//
// Design note. A clump is a rigid body whose surface is the union of a few component spheres
// (as EDEM's multi-sphere templates, LIGGGHTS multisphere, Yade clumps). Its shape comes in as a
// ClumpShape (plain offsets and radii in any frame, as a scene file would give them);
// make_clump_template() validates it, computes the mass properties of the union of the spheres
// (never the sum of the spheres' masses: overlaps would count twice) and moves the shape into its
// principal frame, centre of mass at the origin and the axes along the principal axes of inertia
// with I1 <= I2 <= I3. The mass properties are per unit density, so one template serves every
// material.
//
// Mass properties (clump_mass_properties). The integrals of 1, x and x x^T over the union are the
// spheres' own integrals (closed form) minus the integrals over the "excess", the points covered
// by more than one sphere, counted once per extra sphere. The excess is integrated on lines
// parallel to x: along each line the spheres' chords are intervals, and the integrals of 1, x and
// x^2 over their sum minus their union are exact; across the lines (y, z) a midpoint rule on a
// grid of MassPropertySettings::cells x cells lines covering the spheres' pairwise overlaps.
// Only the overlaps carry the rule's error, which falls as the grid refines
// (tests/sim/clump_mass_test.cpp measures it against closed-form lens integrals of two and three
// spheres: at the default 1024 x 1024 lines the relative errors of the volume, the centre (in
// radii) and the inertia tensor are 2e-9 to 3e-7, below the 1e-6 the test requires; at 256 x 256
// up to 2.4e-6). A one-sphere shape takes the closed form.
//
// Free rotor (free_rotor_drift). The drift of the body's orientation over a time step is the
// symmetric splitting of the free rigid-body Hamiltonian H = sum_k pi_k^2 / (2 I_k) into its three
// terms (Dullweber, Leimkuhler and McLachlan 1997, J. Chem. Phys. 107:5840; in quaternion form
// the NO_SQUISH scheme, Miller et al. 2002, J. Chem. Phys. 116:8649): exact rotations about the
// body axes 1, 2, 3, 2, 1 for tau/2, tau/2, tau, tau/2, tau/2. Each is the
// exact flow of one term, so the composition is symplectic and time-reversible, keeps the
// world-frame angular momentum exactly (the world State holds it, and the drift never changes it)
// and the energy within O(tau^2) without drift. The kicks v += dt/2 F/M, L += dt/2 T around it
// give the engine's velocity-Verlet kick-drift-kick step.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "sim/contact.hpp"

namespace reposetwin::sim {

using Mat3 = Eigen::Matrix3d;
using Quat = Eigen::Quaterniond;

/// A clump's shape as a scene gives it: component spheres in any frame.
struct ClumpShape {
  std::string name = "clump";
  std::vector<Vec3> offsets;   // component centres [m]
  std::vector<double> radii;   // component radii [m]
};

/// How the overlaps of the components are integrated (clump_mass_properties).
struct MassPropertySettings {
  int cells = 1024;  // lines per axis of the grid across the overlaps [-]
};

/// Volume, centre and inertia of a union of spheres per unit density.
struct MassProperties {
  double volume = 0.0;               // [m^3]
  Vec3 centre = Vec3::Zero();        // centre of volume [m] (in the shape's frame)
  Mat3 inertia = Mat3::Zero();       // inertia tensor about the centre, per unit density [m^5]
};

/// Mass properties of the union of the spheres (design note). Throws std::invalid_argument for an
/// empty shape, a radius that is not positive, or an offset that is not finite.
MassProperties clump_mass_properties(const std::vector<Vec3>& centres,
                                     const std::vector<double>& radii,
                                     const MassPropertySettings& settings = {});

/// A clump template in its principal frame: what the engine uses.
struct ClumpTemplate {
  std::string name;
  std::vector<Vec3> offsets;  // component centres in the principal body frame [m]
  std::vector<double> radii;  // component radii [m]
  double volume = 0.0;        // of the union of the components [m^3]
  Vec3 inertia = Vec3::Zero();  // principal moments per unit density, I1 <= I2 <= I3 [m^5]
  double reach = 0.0;         // largest |offset| + radius: the body's bounding radius [m]
  // Where the principal frame lies in the shape's own frame: a point y of the shape's frame is
  // body point axes^T (y - centre); a shape placed at position p and rotation Q (of its own
  // frame) is the body at x = p + Q centre with orientation Q axes.
  Vec3 centre = Vec3::Zero();   // centre of mass in the shape's frame [m]
  Quat axes = Quat::Identity(); // principal axes in the shape's frame (a proper rotation)

  std::size_t size() const { return radii.size(); }
};

/// Validates the shape and derives its template. Throws std::invalid_argument, naming the shape,
/// the component and the value, for no components, mismatched offsets and radii, a radius that
/// is not positive, a non-finite offset, or components that do not form one connected body (each
/// must touch or overlap another, |c_i - c_j| <= r_i + r_j, in one piece).
ClumpTemplate make_clump_template(const ClumpShape& shape,
                                  const MassPropertySettings& settings = {});

/// The template scaled by `factor` (> 0, finite): offsets, radii, reach and centre times
/// factor, volume times factor^3, inertia per unit density times factor^5, axes unchanged. The
/// mass properties scale exactly, so a shape's overlaps are integrated once, at one size, and
/// every grain of it is a scaled copy. Throws std::invalid_argument for a bad factor.
ClumpTemplate scale_clump_template(const ClumpTemplate& t, double factor);

/// Rotates the orientation q (body to world) of a torque-free rigid body with principal moments
/// `inertia` [kg m^2] and world-frame angular momentum l [kg m^2/s] over time tau [s] by the
/// symmetric splitting 1, 2, 3, 2, 1 (design note); q stays a unit quaternion.
void free_rotor_drift(Quat& q, const Vec3& l, const Vec3& inertia, double tau);

/// World-frame angular velocity R diag(1/I) R^T l of a body at orientation q [rad/s].
inline Vec3 body_angular_velocity(const Quat& q, const Vec3& l, const Vec3& inertia) {
  const Mat3 r = q.toRotationMatrix();
  return r * (r.transpose() * l).cwiseQuotient(inertia);
}

}  // namespace reposetwin::sim
