// Broad phase: a cell grid and a Verlet neighbor list with a skin, rebuilt by displacement.
//
// Design note.
//  - Each pair is listed once (a half list), owned by its "first" particle: the larger one, ties
//    broken by index. The first particle therefore only searches for partners no larger than
//    itself, within 2 r_i + skin; with cells sized for the smallest particles this keeps the cost
//    linear for polydisperse packings (d_max/d_min up to 8 and more) instead of every small
//    particle scanning the reach of the largest.
//  - The list is stored in CSR form: pairs of particle i are [start[i], start[i+1]), partners in
//    increasing index. A second CSR ("incoming") lists, for each particle, the pairs in which it
//    is the second member. The force phase writes one result per pair (no two threads write the
//    same place) and the gather phase sums each particle's pairs in a fixed order, so forces are
//    bit-identical whatever the number of threads.
//  - The components of one clump (Particles::body) are never listed together: they never
//    interact. A component is a particle with a position of its own (set from its body's motion,
//    rotation included), so the displacement criterion below holds for it as for a sphere.
//  - Rebuild when the largest displacement since the last build exceeds half the skin. A rebuild
//    sorts the particles by cell (memory locality) and carries every contact's history over from
//    the old list (found by the particles' indices before the sort), so springs survive rebuilds
//    and reorderings.
#pragma once

#include <cstdint>
#include <vector>

#include "sim/contact.hpp"
#include "sim/huge_pages.hpp"
#include "sim/particles.hpp"

namespace reposetwin::sim {

struct NeighborList {
  double skin = 0.0;                // [m]
  HugeVector<std::int32_t> start;  // (n + 1) CSR offsets of each particle's pairs
  HugeVector<std::int32_t> second; // (pairs) partner index
  HugeVector<ContactHistory> history;  // (pairs)
  HugeVector<std::int32_t> in_start;   // (n + 1) CSR offsets of incoming pairs
  HugeVector<std::int32_t> in_pairs;   // pair indices where the particle is second
  HugeVector<std::int32_t> in_slot;    // (pairs) position of each pair in in_pairs (derived
                                        // from in_pairs, not saved in checkpoints)
  HugeVector<std::int32_t> in_particle; // (pairs) the particle whose incoming list holds slot q,
                                        // the second member of pair in_pairs[q] (derived too)
  HugeVector<std::int32_t> first;       // (pairs) the first member of pair k, the particle whose
                                        // CSR range holds k (derived from start, not saved)
  HugeVector<Vec3> x_at_build;     // (n) positions at the last build [m]
  // (pairs) the square of a little less than half the gap between the pair's surfaces at the
  // last build, 0 if they were touching or nearly [m^2]. While neither particle has moved as far
  // (squared) since the build, the pair cannot touch: with both displacements below half the gap
  // the centres are still farther apart than r_i + r_j. Derived from x_at_build and the radii
  // (compute_clearances), not saved in checkpoints.
  HugeVector<double> clearance2;
  // (scratch) the list before the last build: read by the build to carry the springs over,
  // and kept so that the next build reuses its storage (fresh memory costs page faults).
  HugeVector<std::int32_t> old_start, old_second;
  HugeVector<ContactHistory> old_history;
  std::int64_t builds = 0;          // number of rebuilds so far
  std::size_t parallel_min = 2000;  // fewer particles build on one thread

  std::size_t pairs() const { return second.size(); }
  /// True if the list was built for these n particles (else it must be built).
  bool built_for(std::size_t n) const { return x_at_build.size() == n && start.size() == n + 1; }
  /// The displacement criterion: true once some particle has moved more than half the skin
  /// since the build (max_moved2: the largest squared displacement [m^2]).
  bool needs_rebuild(double max_moved2) const { return 4.0 * max_moved2 > skin * skin; }
};

/// Rebuilds the list; sorts `p` by cell first when `sort_particles` is set. Histories of pairs
/// that persist are kept.
void build_neighbor_list(Particles& p, NeighborList& list, bool sort_particles);

/// Derives the list's index arrays: in_slot (in_slot[in_pairs[q]] = q), in_particle and first,
/// from in_pairs, in_start and start.
void derive_list_indices(NeighborList& list);

/// Derives list.clearance2 from list.x_at_build and the radii of `p`.
void compute_clearances(NeighborList& list, const Particles& p);

/// Drops the particles whose `keep` flag is false from a built list, keeping every surviving
/// pair and its history (indices are renumbered as Particles::keep does).
void compact_neighbor_list(NeighborList& list, const std::vector<char>& keep);

/// The reference oracle: every pair (i < j) with |x_i - x_j| < r_i + r_j + cutoff_extra, except
/// the pairs of components of one clump, by an O(N^2) loop. Used by tests.
std::vector<std::pair<std::int32_t, std::int32_t>> brute_force_pairs(const Particles& p,
                                                                     double cutoff_extra);

}  // namespace reposetwin::sim
