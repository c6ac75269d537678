// The pair loop's two inner phases, two pairs at a time: the distance test of the listed pairs
// (queue_touching_pairs) and the contact kernel on the touching ones (compute_queued_contacts).
//
// Design note. The scalar kernel (sim/contact.hpp, hertz_mindlin, with the pair's geometry from
// pair_input below) is one long dependency chain per contact: a square root for the distance, a
// division for the normal, two square roots for the stiffnesses and dampings, one square root
// and one division to rotate each spring, the Coulomb and rolling caps. compute_queued_contacts()
// runs the same arithmetic on two contacts at once, one per SSE2 lane (the x86-64 baseline): the
// particles' data are gathered straight into the lanes (no intermediate ContactInput), every
// branch of the kernel is a select (only the rolling dashpot, off or on for a whole material
// pair, is branched around), and the results are scattered back. Each lane performs the scalar
// kernel's IEEE operations (+, -, *, /, sqrt, no fused multiply-add) in its order, Eigen's
// three-term sums included ((a0 + a1) + a2), so a lane gives the bits of the scalar kernel
// exactly; tests/sim/pair_simd_test.cpp checks this contact by contact, and the pinned
// determinism hash checks it for whole runs. A 4-wide AVX copy of the same code (chosen at run
// time) was as fast as SSE2 on the standard heap (bench/README.md).
//
// Scope of the lanes: material pairs with EPSD rolling and neither cohesion nor size-dependent
// rolling (lanes_eligible), which is the standard heap's and the paper's physics; a contact of
// any other material pair (CDT or no rolling, cohesion, size-dependent rolling) goes through the
// scalar kernel at its place in the queue. Each lane reads its own pair's constants, so the two
// lanes may hold different material pairs.
//
// Wall contacts (compute_wall_contacts) take the same kernel with the geometry of a wall
// (wall_input): the caller finds the touching ones and their normals; the lanes do the rest.
//
// The force and torque of each contact on its first member are written per queued contact, not
// summed here: the caller sums them per particle in list order, which keeps the sums, and so the
// results, those of the one-contact-at-a-time loop.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "sim/contact.hpp"
#include "sim/particles.hpp"

namespace reposetwin::sim {

/// The contact input of the touching pair (i, j): the geometry and the bodies' motion at the
/// contact point (the scalar reference the lanes reproduce).
inline ContactInput pair_input(const Particles& p, const ContactConstants& c, std::size_t i,
                               std::size_t j) {
  const Vec3 d = p.x[i] - p.x[j];
  const double ri = p.radius[i], rj = p.radius[j];
  const double mi = p.mass[i], mj = p.mass[j];
  const double cut = ri + rj, msum = mi + mj, rmin = std::min(ri, rj);
  const double dist = std::sqrt(d.squaredNorm());
  // One division for the normal d / |d|, R* = r_i r_j / (r_i + r_j) and m* = m_i m_j / (m_i +
  // m_j): inv = 1 / (|d| (r_i + r_j) (m_i + m_j) r_min). r_min is in the product only for the
  // rounding: taking it out would change the rounding of the other three, and every pinned hash.
  const double a = dist * cut, b = msum * rmin;
  const double inv = 1.0 / (a * b);
  ContactInput in;
  in.n = d * ((cut * b) * inv);
  in.delta = cut - dist;
  in.r_eff = (ri * rj) * ((dist * b) * inv);
  in.m_eff = (mi * mj) * ((a * rmin) * inv);
  // The rolling inertia is read only by the EPSD dashpot.
  in.i_roll = c.rolling == RollingModel::kEpsd && c.eta_r > 0.0
                  ? 1.0 / (1.0 / (p.inertia[i] + p.mass[i] * ri * ri) +
                           1.0 / (p.inertia[j] + p.mass[j] * rj * rj))
                  : 0.0;
  in.a_i = ri - 0.5 * in.delta;
  in.a_j = rj - 0.5 * in.delta;
  in.w_i = p.w[i];
  in.w_j = p.w[j];
  in.v_rel = p.v[i] - p.v[j] - in.a_i * p.w[i].cross(in.n) - in.a_j * p.w[j].cross(in.n);
  in.contact_diameter = 4.0 * in.r_eff;  // = d for equal spheres (size-dependent rolling)
  return in;
}

/// A touching pair queued for the kernel: pair k of the neighbor list, between its first
/// member i and its second member j, with the constants of their material pair.
struct QueuedContact {
  std::int32_t k = 0;
  std::int32_t i = 0;
  std::int32_t j = 0;
  const ContactConstants* c = nullptr;
};

/// Where the results of the queued contacts go, laid out as World::pair_forces keeps them.
struct PairOutputs {
  ContactHistory* history = nullptr;   // (pairs) springs of pair k, updated in place
  const std::int32_t* slot = nullptr;  // (pairs) incoming slot of pair k
  Reaction* reaction = nullptr;        // (pairs, by slot) what the pair leaves its second member
  std::uint8_t* live = nullptr;        // (pairs) set to 0 for a queued pair that does not touch
  Vec3* force_i = nullptr;             // (queued) force of each queued contact on i [N]
  Vec3* torque_i = nullptr;            // (queued) torque of each queued contact on i [N m]
};

/// Wall contacts queued for the kernel, as a struct of arrays: particle i touching wall w
/// (wall_contact found the normal and the overlap).
struct WallContacts {
  std::vector<std::int32_t> particle;                 // i
  std::vector<std::int32_t> wall;                     // w: springs in wall_history[i][w]
  std::vector<Vec3> normal;                           // unit normal, wall to particle
  std::vector<double> overlap;                        // > 0 [m]
  std::vector<Vec3> wall_velocity;                    // [m/s]
  std::vector<const ContactConstants*> c;             // (particle material, wall material)
  std::vector<Vec3> force, torque;                    // results: on the particle [N], [N m]

  std::size_t size() const { return particle.size(); }
  void clear() {
    particle.clear();
    wall.clear();
    normal.clear();
    overlap.clear();
    wall_velocity.clear();
    c.clear();
  }
  void add(std::int32_t i, std::int32_t w, const Vec3& n, double delta, const Vec3& velocity,
           const ContactConstants* constants) {
    particle.push_back(i);
    wall.push_back(w);
    normal.push_back(n);
    overlap.push_back(delta);
    wall_velocity.push_back(velocity);
    c.push_back(constants);
  }
};

/// The contact input of wall contact e (the scalar reference the lanes reproduce): the wall is
/// body j, neither turning nor with a lever arm; R* = r_i, m* = m_i.
inline ContactInput wall_input(const Particles& p, const WallContacts& wc, std::size_t e) {
  const std::size_t i = static_cast<std::size_t>(wc.particle[e]);
  const double ri = p.radius[i];
  ContactInput in;
  in.n = wc.normal[e];
  in.delta = wc.overlap[e];
  in.r_eff = ri;
  in.m_eff = p.mass[i];
  in.i_roll = p.inertia[i] + p.mass[i] * ri * ri;
  in.a_i = ri - in.delta;
  in.a_j = 0.0;
  in.w_i = p.w[i];
  in.w_j = Vec3::Zero();
  in.v_rel = p.v[i] - in.a_i * p.w[i].cross(in.n) - wc.wall_velocity[e];
  in.contact_diameter = 2.0 * ri;  // the particle's diameter (size-dependent rolling)
  return in;
}

/// How compute_queued_contacts() runs the kernel.
enum class PairIsa {
  kScalar,  // one contact at a time (pair_input + hertz_mindlin): the reference
  kSse2,    // 2 contacts per instruction (SSE2, the x86-64 baseline)
  kAvx,     // 4 contacts per instruction (only where the CPU has AVX)
  kAvx512Vl,  // the same 4 lanes with 32 vector registers and mask registers (only where the
              // CPU has AVX-512VL)
};

/// Runs the kernel on the wall contacts `wc` with time step dt [s]: updates each contact's
/// springs in p.wall_history and writes the force and torque on its particle to wc.force[e] and
/// wc.torque[e]. Every isa gives the bits of wall_input + hertz_mindlin.
void compute_wall_contacts(PairIsa isa, Particles& p, WallContacts& wc, double dt);

/// Whether this CPU can run `isa`.
bool pair_isa_available(PairIsa isa);

/// The fastest instruction set this CPU can run (kAvx512Vl, kAvx or kSse2): what the engine
/// uses unless told otherwise (World::set_pair_isa). All give the same bits.
PairIsa best_pair_isa();

/// "scalar", "sse2", "avx", "avx512vl".
const char* pair_isa_name(PairIsa isa);

/// Whether contacts of the material pair with constants `c` run in the lanes (EPSD rolling, no
/// cohesion, no size-dependent rolling); the others take the scalar kernel.
inline bool lanes_eligible(const ContactConstants& c) {
  return c.rolling == RollingModel::kEpsd && !c.cohesive && !c.size_dependent_rolling;
}

/// Tests the listed pairs tested[0..count) of a block, none of them live (position m in the
/// block: pair k0 + m, between its first member owner[m] and second[k0 + m]), for contact
/// (|x_i - x_j|^2 < (r_i + r_j)^2), two at a time, and appends the touching ones in that order to
/// `queue` (room for `count` entries; QueuedContact::c is left for the caller to set), setting
/// their live flag to 1. Returns the number queued.
std::size_t queue_touching_pairs(const Particles& p, const std::int32_t* owner,
                                 const std::int32_t* second, std::int32_t k0,
                                 const std::int32_t* tested, std::size_t count,
                                 std::uint8_t* live, QueuedContact* queue);

/// Runs the contact kernel on the `count` queued pairs `contacts` (distinct pair indices k) of
/// the particles `p` with time step dt [s]: for a pair that touches (the distance test of
/// queue_touching_pairs), updates its springs, stores its reactions, and writes the force and
/// torque on its first member to out.force_i[q] and out.torque_i[q] for queued contact q; a pair
/// that does not touch (a live pair that separated) gets its springs and reactions cleared, zero
/// force and torque, and live flag 0. kScalar and kSse2 give
/// the same bits.
void compute_queued_contacts(PairIsa isa, const Particles& p, const QueuedContact* contacts,
                             std::size_t count, double dt, const PairOutputs& out);

}  // namespace reposetwin::sim
