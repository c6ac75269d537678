// Particle snapshots and the lab's fixtures as VTK XML PolyData (.vtp) in a ParaView .pvd series
// (VTK's IOXML).
//
// Each particle snapshot holds the particle centres as points with point data radius [m],
// diameter [m], velocity [m/s], angular_velocity [rad/s], material (an index) and id, and field
// data naming the materials (string array "material_names", entry k the name of material k),
// the time and the run's phase; ParaView draws the particles with its Point Gaussian
// representation scaled by "radius" or with a Glyph filter. The point arrays are one table
// (kPointArrays in vtk_output.cpp), so a new per-particle array (a clump's body id) is one row.
//
// The fixtures are written beside them as their own parts of each time step, so ParaView shows
// them in place as the series plays: the plate (one box, the same file every step) and the
// funnel or column where it stood at that moment (a surface of revolution, absent once it is
// removed). Optionally, the contacts between particles as one line per touching pair, from
// centre to centre, with cell data force [N] (on the first particle) and force_magnitude [N].
// Files are written under a temporary name and renamed into place.
//
// With rigid clumps, each point is one component sphere and three arrays more say whose: body_id
// (the body's stable id), component (its place in the body's template) and orientation (the
// body's unit quaternion w, x, y, z, body to world); ParaView colours by body_id to show the
// grains. A snapshot without clumps has exactly the sphere arrays.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "sim/bodies.hpp"
#include "sim/particles.hpp"

namespace reposetwin::sim {
struct State;
}

namespace reposetwin::experiments {

/// An axisymmetric shell about the z axis where it stands (funnel: r_bottom < r_top; column:
/// equal radii).
struct ShellPlacement {
  double z_bottom_m = 0.0;  // lower rim height [m]
  double z_top_m = 0.0;     // upper rim height [m]
  double r_bottom_m = 0.0;  // lower rim radius [m]
  double r_top_m = 0.0;     // upper rim radius [m]
};

/// What a snapshot shows besides the particles: when it was taken, what the run was doing and
/// where the fixtures stood. Written as field data of the particle file and read back with it,
/// so whoever photographs a frame knows whether it is the settled pile and where the funnel was.
struct FrameInfo {
  double time_s = 0.0;                     // simulated time [s]
  std::string phase;                       // "fill", "lift", "settle" or "done"; "" = unknown
  bool settled = false;                    // the snapshot is the settled pile (the run's end)
  std::optional<ShellPlacement> container;  // the funnel or column, when still in place
  double plate_half_size_m = 0.0;          // half the square plate's side; 0 = no plate [m]
  double plate_thickness_m = 0.015;        // drawn thickness below z = 0 [m]
  std::vector<std::string> material_names;  // entry k names material k
  std::string scene_fnv1a;  // FNV-1a of the resolved scene the run was made from; "" = unknown
};

/// Writes one snapshot of the particles, with `info` as field data; with `bodies` (the clumps
/// the particles' body indices refer to), also the clump arrays of the design note.
void write_vtp(const std::string& path, const sim::Particles& particles,
               const FrameInfo& info = {}, const sim::Bodies* bodies = nullptr);

/// Writes the plate as a box (top face at z = 0) of info's size.
void write_plate_vtp(const std::string& path, const FrameInfo& info);

/// Writes a shell as a surface of revolution (`segments` facets around).
void write_shell_vtp(const std::string& path, const ShellPlacement& shell, int segments = 96);

/// Writes the particle-particle contacts of the state's last force phase: one line per touching
/// pair, with cell data force [N] and force_magnitude [N]. Returns the number of contacts.
std::size_t write_contacts_vtp(const std::string& path, const sim::State& state);

/// Particles read back from a .vtp written by write_vtp (positions, radii, materials), with
/// its frame information when the file has it (files written before it existed have none).
struct SnapshotParticles {
  std::vector<Eigen::Vector3d> x;  // [m]
  std::vector<double> radius;      // [m]
  std::vector<int> material;
  std::vector<std::int64_t> body{};  // body_id per point (-1: a sphere); empty without clumps
  std::optional<FrameInfo> info;
};
SnapshotParticles read_vtp(const std::string& path);

/// A .pvd collection: the list of (time, part, file) of a series; several parts of one time
/// step (particles, plate, funnel, contacts) are shown together by ParaView.
class PvdSeries {
 public:
  explicit PvdSeries(std::string path) : path_(std::move(path)) {}
  /// Adds a snapshot (file relative to the .pvd's folder) and rewrites the .pvd atomically.
  void add(double time, const std::string& relative_file);
  /// Adds the parts of one time step (part k = files[k]) and rewrites the .pvd atomically.
  void add(double time, const std::vector<std::string>& relative_files);
  /// Forgets entries later than `time` (used when resuming from a checkpoint).
  void truncate_after(double time);
  /// Reads an existing .pvd written by this class (resume); missing file = empty series.
  void load();

 private:
  struct Entry {
    double time;
    int part;
    std::string file;
  };
  void write() const;
  std::string path_;
  std::vector<Entry> entries_;
};

}  // namespace reposetwin::experiments
