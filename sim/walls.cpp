#include "sim/walls.hpp"

#include <algorithm>
#include <cmath>

namespace reposetwin::sim {

bool wall_contact(const WallSpec& wall, const Vec3& offset, const Vec3& x, double r, Vec3* n,
                  double* delta) {
  if (wall.kind == WallKind::kPlane) {
    const double dist = (x - wall.point - offset).dot(wall.normal);
    if (dist >= r || dist <= -r) return false;
    *n = wall.normal;
    *delta = r - dist;
    return true;
  }
  // Shell: work in the meridional half-plane of the sphere's centre.
  const double px = x.x() - wall.axis_xy.x() - offset.x();
  const double py = x.y() - wall.axis_xy.y() - offset.y();
  const double pz = x.z() - offset.z();
  const double rho = std::sqrt(px * px + py * py);
  // Cheap rejection: outside the shell's slab and radial band.
  if (pz < wall.z_bottom - r || pz > wall.z_top + r) return false;
  const double ax = wall.r_bottom, az = wall.z_bottom;
  const double bx = wall.r_top - ax, bz = wall.z_top - az;
  const double len2 = bx * bx + bz * bz;
  double t = len2 > 0.0 ? ((rho - ax) * bx + (pz - az) * bz) / len2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  const double dr = rho - (ax + t * bx);
  const double dz = pz - (az + t * bz);
  const double d2 = dr * dr + dz * dz;
  if (d2 >= r * r) return false;
  const double d = std::sqrt(d2);
  const double ex = rho > 0.0 ? px / rho : 1.0;
  const double ey = rho > 0.0 ? py / rho : 0.0;
  double nr, nz;
  if (d > 0.0) {
    nr = dr / d;
    nz = dz / d;
  } else {  // centre exactly on the shell: push inwards along the segment's normal
    const double l = std::sqrt(len2);
    nr = -bz / l;
    nz = bx / l;
  }
  *n = Vec3(nr * ex, nr * ey, nz);
  *delta = r - d;
  return true;
}

}  // namespace reposetwin::sim
