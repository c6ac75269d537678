// Particle snapshots as VTK XML PolyData (.vtp) in a ParaView .pvd series (VTK's IOXML).
//
// Each snapshot holds the particle centres as points with point data radius [m], velocity
// [m/s], angular_velocity [rad/s], material and id; ParaView draws them with its Point Gaussian
// representation scaled by "radius" or with a Glyph filter. Files are written under a temporary
// name and renamed into place.
#pragma once

#include <string>
#include <vector>

#include "sim/particles.hpp"

namespace reposetwin::experiments {

/// Writes one snapshot of the particles.
void write_vtp(const std::string& path, const sim::Particles& particles);

/// Particles read back from a .vtp written by write_vtp (positions, radii, materials).
struct SnapshotParticles {
  std::vector<Eigen::Vector3d> x;  // [m]
  std::vector<double> radius;      // [m]
  std::vector<int> material;
};
SnapshotParticles read_vtp(const std::string& path);

/// A .pvd collection: the list of (time, file) of a series.
class PvdSeries {
 public:
  explicit PvdSeries(std::string path) : path_(std::move(path)) {}
  /// Adds a snapshot (file relative to the .pvd's folder) and rewrites the .pvd atomically.
  void add(double time, const std::string& relative_file);
  /// Forgets entries later than `time` (used when resuming from a checkpoint).
  void truncate_after(double time);
  /// Reads an existing .pvd written by this class (resume); missing file = empty series.
  void load();

 private:
  void write() const;
  std::string path_;
  std::vector<std::pair<double, std::string>> entries_;
};

}  // namespace reposetwin::experiments
