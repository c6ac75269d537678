// The pile measured from particle positions: height, base diameter, centre and angles.
//
// Design note. The paper reads its lab angle as atan(2H/D) from a photo, and its simulated angle
// with EDEM's protractor on a slice through the pile centre. Both are measured here from the
// particles alone (no images), with definitions that a lone particle cannot move:
//
// 1. The pile is one cluster. Two particles are connected when their centre distance is at most
//    (1 + contact_tolerance) (r_i + r_j). Of the connected clusters that touch the plate, the
//    pile is the one with the largest solid volume. Lone strays (rolled away, bounced, still
//    falling) form their own clusters and are ignored; `stray_count` says how many there were.
// 2. The footprint is the set of pile particles on the plate: bottom z - r <= footprint_tolerance
//    * r. Plate at z = plate_z (default 0), gravity along -z; heights are above the plate.
// 3. The centre is found from the footprint, not assumed: start at the mean footprint position;
//    split the azimuth around it into `sectors`; in each sector take the footprint particle
//    reaching furthest out (radial distance + radius) and its outer point; fit a circle to these
//    points (algebraic least squares; sectors whose reach differs from the median by more than
//    three robust deviations or one particle diameter are left out); move the centre there and
//    repeat until it stops moving.
// 4. D = 2 * the median over sectors of the furthest reach in each sector, measured from the
//    centre. The median over sectors ignores a few particles that rolled out together on one
//    side. H = the top (z + r) of the highest pile particle. theta_hd = atan(2H/D).
// 5. Protractor slices: for `slice_azimuths` directions over 180 degrees, take the pile particles
//    whose centres lie within slice_half_width of the vertical plane through the centre. Each is
//    placed at its distance from the vertical axis (on the side of the plane it lies on): a thin
//    slab of an axisymmetric pile then has the exact profile of the pile, however thick the slab.
//    The outer surface on each side is, per radial bin, the highest particle top in the bin, at
//    that particle's radial position. A straight line z = a + b rho fitted (least squares) to the
//    surface points with heights in [flank_low H, flank_high H] gives that flank's angle
//    atan(-b): the toe and the apex are excluded, as with a protractor laid on the flank.
//    The slice angle is the mean of its two flanks; their mean and sample standard deviation
//    over azimuths are reported.
// 6. Also reported, for comparison with other definitions in use: the equal-area triangle angle
//    atan(4A/D^2), A the area under a slice's surface profile, averaged over slices; and the
//    centre-of-mass angle atan(4 z_com / (D/2)), exact for a solid cone (z_com = H/4).
//
// On a pile of spheres these definitions are exact for a cone whose outer surface particles
// touch the cone and whose outermost plate particles reach the base circle. On a packed heap the
// bottom spheres cannot fill the corner between the flank and the plate: the footprint ends about
// r (cot(theta/2) - 1) inside the point where the flank line meets the plate (2.3 r at 34
// degrees), so D is that much smaller than the flank cone's base and atan(2H/D) reads higher than
// the flank angle by about sin(theta) cos(theta) * 2.3 r / (D/2) (0.8 degrees for r = 0.75 mm and
// D = 110 mm), as a photo would. Compare like with like. All angles are in radians.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "sim/particles.hpp"

namespace reposetwin::sim {

/// Settings of the pile measurement; every field has a default.
struct PileGeometrySettings {
  double plate_z = 0.0;              // height of the plate; all heights are measured from it [m]
  double contact_tolerance = 0.1;    // particles connect within (1 + this)(r_i + r_j) [-]
  double footprint_tolerance = 0.5;  // on the plate when bottom z - r <= this * r [-]
  int sectors = 36;                  // azimuth sectors for the footprint (>= 4) [-]
  int centre_iterations = 20;        // most centre refinements [-]
  int slice_azimuths = 16;           // protractor slices over 180 degrees (>= 1) [-]
  double slice_half_width = 1.0;     // half thickness of a slice, in median diameters [-]
  double bin_width = 1.0;            // radial bin of the surface profile, in median diameters [-]
  double flank_low = 0.2;            // lower end of the flank fit, fraction of H [-]
  double flank_high = 0.8;           // upper end of the flank fit, fraction of H [-]
  int min_flank_points = 3;          // fewer surface points on a flank: no angle for it [-]
};

/// What the measurement found.
enum class PileStatus {
  kOk,        // H, D and the slice angles were measured
  kNoPile,    // no particle touches the plate: no pile (H, D and angles are 0)
  kNoFlanks,  // H and D measured, but no flank had enough surface points for a fit
};

/// Returns "ok", "no pile" or "no flanks".
std::string to_string(PileStatus status);

/// One flank of one slice.
struct FlankFit {
  bool valid = false;  // enough surface points in the band for a line fit
  int points = 0;      // surface points used in the fit [-]
  double angle = 0.0;  // atan(-slope) of the fitted line: positive when the flank falls outward
                       // [rad]
  double rms = 0.0;    // root mean square height residual of the fit [m]
};

/// One protractor slice through the pile centre.
struct PileSlice {
  double azimuth = 0.0;           // direction of the slice plane from the +x axis [rad]
  FlankFit positive;              // flank on the side the azimuth points to
  FlankFit negative;              // flank on the opposite side
  double angle = 0.0;             // mean of the valid flanks' angles; 0 if none is valid [rad]
  bool valid = false;             // at least one valid flank
  double area = 0.0;              // area under the surface profile over both sides [m^2]
  double equal_area_angle = 0.0;  // atan(4 area / D^2) [rad]
};

/// The measured pile; every number is defined in the design note above.
struct PileGeometry {
  PileStatus status = PileStatus::kNoPile;
  std::size_t particle_count = 0;                    // particles given [-]
  std::size_t pile_count = 0;                        // particles in the pile cluster [-]
  std::size_t footprint_count = 0;                   // pile particles on the plate [-]
  std::size_t stray_count = 0;                       // particles given but not in the pile [-]
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();  // pile axis on the plate (x, y) [m]
  double height = 0.0;                               // H: top of the highest pile particle [m]
  double base_diameter = 0.0;          // D: 2 * median over sectors of the furthest reach [m]
  std::vector<double> sector_reach;    // furthest reach from the centre per sector; NaN when a
                                       // sector holds no footprint particle (sectors) [m]
  double theta_hd = 0.0;               // atan(2H/D) [rad]
  std::vector<PileSlice> slices;       // (slice_azimuths)
  int valid_slices = 0;                // slices with at least one valid flank [-]
  double slice_angle_mean = 0.0;       // mean over valid slices of the slice angle [rad]
  double slice_angle_sd = 0.0;         // sample standard deviation of the same [rad]
  double flank_angle_sd = 0.0;         // sample standard deviation over all valid flanks [rad]
  double equal_area_angle = 0.0;       // mean over slices of atan(4A/D^2) [rad]
  double centre_of_mass_height = 0.0;  // z_com of the pile, solid spheres of one density [m]
  double centre_of_mass_angle = 0.0;   // atan(4 z_com / (D/2)) [rad]
  double median_diameter = 0.0;        // median diameter of the pile particles [m]
};

/// Measures the pile formed by spheres at `positions` (n) [m] with `radii` (n) [m] on a plate at
/// z = settings.plate_z. Throws std::invalid_argument if the sizes differ, a position is not
/// finite, a radius is not positive, or a setting is out of range. An empty input or no particle on
/// the plate gives status kNoPile, not an exception.
PileGeometry measure_pile(std::span<const Vec3> positions, std::span<const double> radii,
                          const PileGeometrySettings& settings = {});

}  // namespace reposetwin::sim
