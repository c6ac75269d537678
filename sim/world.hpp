// The DEM world: a fixed Model, a changing State, and step().
//
// Design note. step() reads as the table of contents of one velocity-Verlet step:
//   1. kick_drift       v += dt/2 F/m, w += dt/2 T/I, x += dt v      (forces of the last step)
//   1b. kick_drift_bodies  only with clumps (sim/bodies.hpp): the bodies' opening kick
//                       v += dt/2 F/M, L += dt/2 T and drift (the rotation by the free-rotor
//                       splitting, sim/clump.hpp); each component is placed at x + R(q) b with
//                       v + w x r and w, and its displacement measured for the rebuild test
//   2. move_walls       prescribed wall motion (the lift)
//   3. update_neighbors rebuild the Verlet list if a particle moved more than skin/2
//   4. pair_forces      Hertz-Mindlin + rolling kernel once per touching pair, 2 or 4 pairs at
//                       a time in SSE2, AVX or AVX-512VL lanes (sim/pair_simd.hpp, bit-identical
//                       to the scalar kernel); the pair's first member sums its own pairs (and
//                       gravity) in list order, the reaction is stored in the second member's
//                       incoming slot; each thread takes one contiguous range of particle blocks
//                       (about the particles it moved in kick_drift, still in its cache) of
//                       about equal work, weighed by the pairs each block computed last step
//   5. gather_wall_forces, one pass over the particles (each particle's data read once):
//                       each particle adds the stored reactions of the pairs it is second in
//                       (contiguous, in a fixed order: deterministic), then its wall contacts
//                       (the particles near an enabled wall, listed at rebuild; the kernel in
//                       lanes too, compute_wall_contacts), then takes the closing kick
//                       v += dt/2 F/m, w += dt/2 T/I
//   6. gather_bodies    only with clumps: each body sums its components' forces and torques
//                       (r x F + T) in template order, gravity once, takes the closing kick
//                       v += dt/2 F/M, L += dt/2 T, and sets its components' velocities
//                       v + w x r and angular velocities w
// Components are ordinary particles for phases 3-5 (pairs of one body are never listed, and a
// rebuild reorders the bodies with their components), so phases 1 and 5 also move and kick them
// as spheres; phases 1b and 6 overwrite that with the body's motion. Without clumps both do
// nothing and the spheres' bits are those of an engine without clumps.
// (diagnose(): energy, overlap, NaN and escape checks, called by the runner every few steps.)
// Each phase is timed into Profile, which the benchmark prints. No phase writes memory another
// thread writes, and no floating-point sum depends on the thread count, so a run is
// bit-identical for the same scene and seed on any number of threads.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "sim/bodies.hpp"
#include "sim/model.hpp"
#include "sim/neighbor.hpp"
#include "sim/pair_simd.hpp"
#include "sim/particles.hpp"
#include "sim/walls.hpp"

namespace reposetwin::sim {

/// Physics trouble, reported and never silently continued.
enum class Status { kOk, kNan, kOverlap, kEscaped };
const char* status_name(Status s);

/// Seconds spent in each phase of step() since the start (or the last reset).
struct Profile {
  double kick_drift = 0, move_walls = 0, neighbors = 0, pair_forces = 0, gather_walls_kick = 0;
  double bodies = 0;  // kick_drift_bodies and gather_bodies (clumps only)
  std::int64_t steps = 0;
  double total() const {
    return kick_drift + move_walls + neighbors + pair_forces + gather_walls_kick + bodies;
  }
};

/// Whole-system figures, computed by World::diagnose().
struct Diagnostics {
  double kinetic_energy = 0.0;      // translational + rotational [J]
  double max_overlap_ratio = 0.0;   // largest overlap / smaller radius [-]
  double max_speed = 0.0;           // [m/s]
  std::size_t contacts = 0;         // touching pairs + wall contacts
  Status status = Status::kOk;
  std::string detail;               // which particle, what value
};

/// Everything that changes while the run steps.
struct State {
  Particles particles;
  Bodies bodies;                    // clumps; their components are in `particles`
  // (derived) each body's components' particle indices, in template order; rebuilt whenever
  // the particles are reordered or removed
  BodyComponents body_components;
  std::int64_t next_body_id = 0;    // id given to the next inserted body
  NeighborList neighbors;
  std::vector<WallState> walls;     // one per Model::walls entry
  double time = 0.0;                // [s]
  std::int64_t step = 0;
  std::int64_t next_id = 0;         // id given to the next inserted particle
  bool forces_valid = false;        // particles.force holds the forces of the current positions
  // Per-pair results of the last force phase (scratch, sized with the neighbor list). The
  // reactions are stored in the order of the incoming lists (slot neighbors.in_slot[k] for pair
  // k), so gather_forces reads each particle's reactions contiguously.
  HugeVector<Reaction> reaction;  // (pairs, by slot)
  // (pairs) 1 if the pair touched in the last force phase (or may have: set to 1 for every pair
  // when the list is compacted or read from a checkpoint, and for the pairs with springs when it
  // is rebuilt); 0 only if the pair's history and reactions are zero. A live pair goes
  // straight to the kernel, which clears it if it no longer touches; any other costs a distance
  // test, or nothing if it cannot touch yet (NeighborList::clearance2).
  HugeVector<std::uint8_t> pair_live;
  // (particles) squared displacement since the neighbor list was built, measured in each step's
  // kick_drift (scratch for the force phase) [m^2].
  HugeVector<double> moved2;
  // Wall candidates (scratch, rebuilt with the neighbor list, and alone when invalid or when a
  // wall has moved half a skin): the particles within 1.5 skins of an enabled wall, each with its
  // walls in increasing order (CSR). Only these are tested in wall_forces; every other particle
  // stays clear of every wall until the next rebuild (it moves at most one skin, a wall at most
  // half a skin). Which particles are listed never changes a result.
  bool wall_candidates_valid = false;
  std::vector<std::int32_t> wall_cand_particle;   // particle index
  std::vector<std::int32_t> wall_cand_start;      // CSR offsets into wall_cand_wall
  std::vector<std::int32_t> wall_cand_wall;       // wall index
  std::vector<Vec3> wall_offset_at_build;         // each wall's offset when they were built [m]
};

class World {
 public:
  /// Takes a finalised model (Model::finalize has been called).
  explicit World(Model model);

  const Model& model() const { return model_; }
  State& state() { return state_; }
  const State& state() const { return state_; }
  const Profile& profile() const { return profile_; }
  void reset_profile() { profile_ = Profile{}; }

  /// Inserts a particle at rest; returns its index (valid until the next rebuild).
  std::size_t add_particle(const Vec3& x, double radius, int material);

  /// Inserts a clump of template `shape` (Model::clumps) at rest with its centre of mass at x
  /// and orientation q (body to world; normalised here), its components of `material`; returns
  /// the body's index (valid until the next rebuild, which reorders the bodies with the
  /// particles; Bodies::id is stable). Its components are particles with the body's index.
  std::size_t add_clump(int shape, const Vec3& x, const Quat& q, int material);

  /// Sets a body's velocity [m/s] and world-frame angular velocity [rad/s] (and so its angular
  /// momentum and its components' velocities).
  void set_body_velocity(std::size_t body, const Vec3& v, const Vec3& w);

  /// Sets a wall's velocity (for example the funnel lift) [m/s].
  void set_wall_velocity(int wall, const Vec3& velocity);
  void set_wall_enabled(int wall, bool enabled);

  /// The instruction set of the pair kernel (default best_pair_isa(); every choice gives the
  /// same bits). Throws std::invalid_argument if this CPU cannot run it.
  void set_pair_isa(PairIsa isa);
  PairIsa pair_isa() const { return pair_isa_; }

  /// Advances one time step.
  void step();

  /// Computes the forces of the current positions now (normally done inside step()). Note
  /// that this advances the contact springs by one step's relative motion.
  void refresh_forces() { compute_forces(); }

  /// Computes energy, overlap, speed and checks for NaN or escaped particles.
  Diagnostics diagnose() const;

  /// True once a step has moved a particle to a non-finite position (or by a non-finite
  /// distance). Checked every step at the cost of one add per particle, so a runner that calls
  /// diagnose() only every few steps can call it at once; diagnose() names the particle.
  bool nonfinite_seen() const { return nonfinite_; }

  /// Removes particles for which `remove` is true (e.g. fallen off the plate); returns the count.
  /// A clump goes whole: removing any of its components removes the body and all of them.
  std::size_t remove_particles(const std::vector<char>& remove);

 private:
  void kick_drift();
  void move_walls();
  void update_neighbors();
  bool wall_candidates_current() const;
  void build_wall_candidates();
  void pair_forces();
  void gather_wall_forces(bool kick);
  void kick_drift_bodies();
  void order_bodies();  // after the particles' sort: bodies by their first component's index
  void gather_bodies(bool kick);
  // Sets body b's components' positions x + rot b_c, velocities v + w x r and angular
  // velocities w (rot: the body's rotation matrix) and, if moved2 is given, their squared
  // displacements since the list's build; move_components sets the velocities only, from the
  // components' positions.
  void place_components(std::size_t b, const Mat3& rot, double* moved2);
  void move_components(std::size_t b);
  void compute_forces();  // phases 3-6 without the kick (also used once before the first step)

  Model model_;
  State state_;
  Profile profile_;
  PairIsa pair_isa_ = best_pair_isa();
  // Largest squared displacement since the list was built, measured by kick_drift for the
  // update_neighbors that follows it; -1 if unknown (then update_neighbors measures) [m^2].
  double moved2_ = -1.0;
  bool nonfinite_ = false;  // see nonfinite_seen()
  // pair_forces' work estimate for the threads' ranges: each block's contacts computed by the
  // kernel last step, and the cost before each block (scratch; results never depend on them).
  std::vector<std::int32_t> block_queued_;
  std::vector<double> block_cost_;
};

/// A SHA-256-free, portable 64-bit FNV-1a hash of the particle state (positions, velocities,
/// angular velocities, ids) and, if there are clumps, of the bodies' (positions, orientations,
/// velocities, angular momenta, ids), for determinism tests.
std::uint64_t state_hash(const State& s);

}  // namespace reposetwin::sim
