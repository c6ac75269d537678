// Particle snapshots as VTK XML PolyData (.vtp) in a ParaView .pvd series (VTK's IOXML).
//
// Each snapshot holds the particle centres as points with point data radius [m], velocity
// [m/s], angular_velocity [rad/s], material and id; ParaView draws them with its Point Gaussian
// representation scaled by "radius" or with a Glyph filter. With rigid clumps, each point is
// one component sphere and three arrays more say whose: body_id (the body's stable id), component
// (its place in the body's template) and orientation (the body's unit quaternion w, x, y, z,
// body to world); ParaView colours by body_id to show the grains. A snapshot without clumps has
// exactly the sphere arrays. Files are written under a temporary name and renamed into place.
#pragma once

#include <string>
#include <vector>

#include "sim/bodies.hpp"
#include "sim/particles.hpp"

namespace reposetwin::experiments {

/// Writes one snapshot of the particles; with `bodies` (the clumps the particles' body indices
/// refer to), also the clump arrays of the design note when any particle is a component.
void write_vtp(const std::string& path, const sim::Particles& particles,
               const sim::Bodies* bodies = nullptr);

/// Particles read back from a .vtp written by write_vtp (positions, radii, materials).
struct SnapshotParticles {
  std::vector<Eigen::Vector3d> x;  // [m]
  std::vector<double> radius;      // [m]
  std::vector<int> material;
  std::vector<std::int64_t> body{};  // body_id per point (-1: a sphere); empty without clumps
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
