#include "sim/world.hpp"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "sim/pair_simd.hpp"

namespace reposetwin::sim {
namespace {

/// Adds the wall-clock time of its scope to a Profile field.
class PhaseTimer {
 public:
  explicit PhaseTimer(double& acc) : acc_(acc), t0_(std::chrono::steady_clock::now()) {}
  ~PhaseTimer() {
    acc_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
  }

 private:
  double& acc_;
  std::chrono::steady_clock::time_point t0_;
};

/// The first of the blocks that thread t of nt takes when the blocks are split into contiguous
/// ranges of about equal cost: `cost` holds the cost before each block (blocks + 1 entries,
/// growing). Thread nt gets `blocks`.
std::size_t first_block(const std::vector<double>& cost, int t, int nt) {
  const std::size_t blocks = cost.size() - 1;
  if (t >= nt) return blocks;
  const double target = cost[blocks] * t / nt;
  return static_cast<std::size_t>(std::lower_bound(cost.begin(), cost.end() - 1, target) -
                                  cost.begin());
}

}  // namespace

const char* status_name(Status s) {
  switch (s) {
    case Status::kOk: return "ok";
    case Status::kNan: return "nan";
    case Status::kOverlap: return "overlap";
    case Status::kEscaped: return "escaped";
  }
  return "?";
}

World::World(Model model) : model_(std::move(model)) {
  if (model_.dt <= 0.0) throw std::logic_error("World: the model has not been finalised");
  if (model_.settings.threads > 0) omp_set_num_threads(model_.settings.threads);
  state_.walls.assign(model_.walls.size(), WallState{});
  state_.neighbors.parallel_min = model_.settings.parallel_min_particles;
  state_.neighbors.skin =
      model_.settings.skin > 0.0 ? model_.settings.skin : 0.25 * 2.0 * model_.r_min;
}

std::size_t World::add_particle(const Vec3& x, double radius, int material) {
  const double density = model_.materials.at(material).density;
  const std::size_t i =
      state_.particles.add(x, radius, density, material, state_.next_id++);
  state_.forces_valid = false;
  state_.wall_candidates_valid = false;
  return i;
}

std::size_t World::add_clump(int shape, const Vec3& x, const Quat& q, int material) {
  const ClumpTemplate& t = model_.clumps.at(static_cast<std::size_t>(shape));
  const double density = model_.materials.at(material).density;
  Bodies& bodies = state_.bodies;
  const std::size_t b = bodies.size();
  bodies.resize(b + 1);
  bodies.x[b] = x;
  bodies.q[b] = q.normalized();
  bodies.v[b].setZero();
  bodies.w[b].setZero();
  bodies.l[b].setZero();
  bodies.force[b].setZero();
  bodies.torque[b].setZero();
  if (t.size() == 1) {  // the sphere's own expressions (Particles::add), for the sphere's bits
    const double r = t.radii[0];
    bodies.mass[b] = sphere_mass(density, r);
    bodies.inertia[b] = Vec3::Constant(0.4 * bodies.mass[b] * r * r);
  } else {
    bodies.mass[b] = density * t.volume;
    bodies.inertia[b] = density * t.inertia;
  }
  bodies.shape[b] = shape;
  bodies.material[b] = material;
  bodies.id[b] = state_.next_body_id++;
  const Mat3 rot = bodies.q[b].toRotationMatrix();
  Particles& p = state_.particles;
  const double m = bodies.mass[b];
  for (std::size_t c = 0; c < t.size(); ++c) {
    const double r = t.radii[c];
    const Vec3 xc = t.size() == 1 ? x : Vec3(x + rot * t.offsets[c]);
    const std::size_t i = p.add(xc, r, density, material, state_.next_id++);
    p.mass[i] = m;
    p.inertia[i] = 0.4 * m * r * r;
    p.body[i] = static_cast<std::int32_t>(b);
    p.component[i] = static_cast<std::int32_t>(c);
  }
  state_.body_components.start.clear();  // indexed again when next needed
  state_.forces_valid = false;
  state_.wall_candidates_valid = false;
  return b;
}

void World::set_body_velocity(std::size_t b, const Vec3& v, const Vec3& w) {
  Bodies& bodies = state_.bodies;
  bodies.v.at(b) = v;
  if (bodies.spherical(b)) {
    bodies.w[b] = w;
    bodies.l[b] = bodies.inertia[b].x() * w;
  } else {
    const Mat3 r = bodies.q[b].toRotationMatrix();
    bodies.l[b] = r * bodies.inertia[b].cwiseProduct(r.transpose() * w);
    bodies.w[b] = body_angular_velocity(bodies.q[b], bodies.l[b], bodies.inertia[b]);
  }
  if (!state_.body_components.indexed_for(bodies.size()))
    index_body_components(state_.particles, bodies.size(), state_.body_components);
  move_components(b);
}

void World::place_components(std::size_t b, const Mat3& rot, double* moved2) {
  const Bodies& bodies = state_.bodies;
  Particles& p = state_.particles;
  const BodyComponents& bc = state_.body_components;
  const Vec3* const x_at_build = state_.neighbors.x_at_build.data();
  const std::int32_t c0 = bc.start[b], c1 = bc.start[b + 1];
  if (c1 - c0 == 1) {  // a one-sphere clump: the body's values themselves
    const std::size_t i = static_cast<std::size_t>(bc.particle[c0]);
    p.x[i] = bodies.x[b];
    p.v[i] = bodies.v[b];
    p.w[i] = bodies.w[b];
    if (moved2) moved2[i] = (p.x[i] - x_at_build[i]).squaredNorm();
    return;
  }
  const Vec3* const offsets =
      model_.clumps[static_cast<std::size_t>(bodies.shape[b])].offsets.data();
  for (std::int32_t k = c0; k < c1; ++k) {
    const std::size_t i = static_cast<std::size_t>(bc.particle[k]);
    const Vec3 r = rot * offsets[k - c0];
    p.x[i] = bodies.x[b] + r;
    p.v[i] = bodies.v[b] + bodies.w[b].cross(r);
    p.w[i] = bodies.w[b];
    if (moved2) moved2[i] = (p.x[i] - x_at_build[i]).squaredNorm();
  }
}

void World::move_components(std::size_t b) {
  const Bodies& bodies = state_.bodies;
  Particles& p = state_.particles;
  const BodyComponents& bc = state_.body_components;
  const std::int32_t c0 = bc.start[b], c1 = bc.start[b + 1];
  if (c1 - c0 == 1) {
    const std::size_t i = static_cast<std::size_t>(bc.particle[c0]);
    p.v[i] = bodies.v[b];
    p.w[i] = bodies.w[b];
    return;
  }
  for (std::int32_t k = c0; k < c1; ++k) {
    const std::size_t i = static_cast<std::size_t>(bc.particle[k]);
    p.v[i] = bodies.v[b] + bodies.w[b].cross(p.x[i] - bodies.x[b]);
    p.w[i] = bodies.w[b];
  }
}

void World::set_wall_velocity(int wall, const Vec3& velocity) {
  state_.walls.at(wall).velocity = velocity;
}

void World::set_pair_isa(PairIsa isa) {
  if (!pair_isa_available(isa))
    throw std::invalid_argument(std::string("pair kernel: this CPU cannot run ") +
                                pair_isa_name(isa));
  pair_isa_ = isa;
}

void World::set_wall_enabled(int wall, bool enabled) {
  state_.walls.at(wall).enabled = enabled;
  state_.wall_candidates_valid = false;
}

void World::step() {
  if (!state_.forces_valid) compute_forces();
  kick_drift();
  kick_drift_bodies();
  move_walls();
  update_neighbors();
  pair_forces();
  gather_wall_forces(/*kick=*/true);
  gather_bodies(/*kick=*/true);
  state_.time += model_.dt;
  ++state_.step;
  ++profile_.steps;
}

void World::compute_forces() {
  moved2_ = -1.0;  // positions may have been set from outside: measure the displacement
  update_neighbors();
  pair_forces();
  gather_wall_forces(/*kick=*/false);
  gather_bodies(/*kick=*/false);
}

void World::kick_drift() {
  PhaseTimer t(profile_.kick_drift);
  Particles& p = state_.particles;
  const double dt = model_.dt, h = 0.5 * model_.dt;
  const std::size_t n = p.size();
  const std::size_t par_min = model_.settings.parallel_min_particles;
  // Each particle's squared displacement since the neighbor list was built, measured here while
  // the positions are at hand: update_neighbors takes the largest for the rebuild test, and
  // pair_forces skips the pairs that cannot touch yet (NeighborList::clearance2).
  const bool listed = state_.neighbors.x_at_build.size() == n;
  const Vec3* const x_at_build = listed ? state_.neighbors.x_at_build.data() : nullptr;
  if (listed) state_.moved2.resize(n);
  double* const moved2 = state_.moved2.data();
  // The sum of the displacements is there for its finiteness alone: std::max drops a NaN, a sum
  // keeps it, so a broken state is seen in the step that makes it, for one add per particle.
  double max2 = 0.0, sum2 = 0.0;
#pragma omp parallel for schedule(static) reduction(max : max2) reduction(+ : sum2) \
    if (n > par_min)
  for (std::size_t i = 0; i < n; ++i) {
    p.v[i] += (h / p.mass[i]) * p.force[i];
    p.w[i] += (h / p.inertia[i]) * p.torque[i];
    p.x[i] += dt * p.v[i];
    if (listed) {
      moved2[i] = (p.x[i] - x_at_build[i]).squaredNorm();
      max2 = std::max(max2, moved2[i]);
      sum2 += moved2[i];
    }
  }
  moved2_ = listed ? max2 : -1.0;
  if (!std::isfinite(sum2)) nonfinite_ = true;
}

void World::order_bodies() {
  Particles& p = state_.particles;
  Bodies& bodies = state_.bodies;
  const std::size_t nb = bodies.size();
  // The bodies in the order of their first component in the (just sorted) particle arrays.
  std::vector<std::int32_t> order;
  order.reserve(nb);
  std::vector<char> seen(nb, 0);
  for (std::size_t i = 0; i < p.size(); ++i) {
    const std::int32_t b = p.body[i];
    if (b >= 0 && !seen[static_cast<std::size_t>(b)]) {
      seen[static_cast<std::size_t>(b)] = 1;
      order.push_back(b);
    }
  }
  bool identity = true;
  for (std::size_t k = 0; k < nb && identity; ++k)
    identity = order[k] == static_cast<std::int32_t>(k);
  if (!identity) {
    bodies.permute(order);
    std::vector<std::int32_t> new_index(nb);
    for (std::size_t k = 0; k < nb; ++k)
      new_index[static_cast<std::size_t>(order[k])] = static_cast<std::int32_t>(k);
    for (std::size_t i = 0; i < p.size(); ++i)
      if (p.body[i] >= 0) p.body[i] = new_index[static_cast<std::size_t>(p.body[i])];
  }
  index_body_components(p, nb, state_.body_components);
}

void World::kick_drift_bodies() {
  Bodies& bodies = state_.bodies;
  const std::size_t nb = bodies.size();
  if (nb == 0) return;
  PhaseTimer t(profile_.bodies);
  if (!state_.body_components.indexed_for(nb))
    index_body_components(state_.particles, nb, state_.body_components);
  const double dt = model_.dt, h = 0.5 * model_.dt;
  const std::size_t par_min = model_.settings.parallel_min_particles;
  // kick_drift measured the components' displacements from their motion as spheres: they are
  // measured again from their places on the bodies (when kick_drift measured at all: else
  // update_neighbors does), and the largest is taken again over every particle.
  const bool measure = moved2_ >= 0.0;
  double* const moved2 = measure ? state_.moved2.data() : nullptr;
#pragma omp parallel for schedule(static) if (nb > par_min)
  for (std::size_t b = 0; b < nb; ++b) {
    bodies.v[b] += (h / bodies.mass[b]) * bodies.force[b];
    bodies.x[b] += dt * bodies.v[b];
    if (bodies.spherical(b)) {  // as a sphere (Bodies::spherical); the orientation turns at w
      const double inertia = bodies.inertia[b].x();
      bodies.w[b] += (h / inertia) * bodies.torque[b];
      bodies.l[b] = inertia * bodies.w[b];
      const double speed = bodies.w[b].norm();
      if (speed > 0.0)
        bodies.q[b] = (Quat(Eigen::AngleAxisd(speed * dt, bodies.w[b] / speed)) * bodies.q[b])
                          .normalized();
    } else {
      bodies.l[b] += h * bodies.torque[b];
      free_rotor_drift(bodies.q[b], bodies.l[b], bodies.inertia[b], dt);
    }
    const Mat3 rot = bodies.q[b].toRotationMatrix();
    if (!bodies.spherical(b))
      bodies.w[b] = rot * (rot.transpose() * bodies.l[b]).cwiseQuotient(bodies.inertia[b]);
    place_components(b, rot, moved2);
  }
  if (!measure) return;
  const std::size_t n = state_.particles.size();
  double max2 = 0.0;
  for (std::size_t i = 0; i < n; ++i) max2 = std::max(max2, moved2[i]);
  moved2_ = max2;
}

void World::gather_bodies(bool kick) {
  Bodies& bodies = state_.bodies;
  const std::size_t nb = bodies.size();
  if (nb == 0) return;
  PhaseTimer t(profile_.bodies);
  if (!state_.body_components.indexed_for(nb))
    index_body_components(state_.particles, nb, state_.body_components);
  const Particles& p = state_.particles;
  const BodyComponents& bc = state_.body_components;
  const Vec3 g = model_.settings.gravity;
  const double h = 0.5 * model_.dt;
  const std::size_t par_min = model_.settings.parallel_min_particles;
  // Each component's force holds gravity with the body's mass (its `mass`, pair_forces): the
  // body keeps it once, from its first component. Sums in template order, on any thread count.
#pragma omp parallel for schedule(static) if (nb > par_min)
  for (std::size_t b = 0; b < nb; ++b) {
    const std::int32_t c0 = bc.start[b], c1 = bc.start[b + 1];
    const std::size_t i0 = static_cast<std::size_t>(bc.particle[c0]);
    Vec3 f = p.force[i0], tq = p.torque[i0];
    if (c1 - c0 > 1) {  // (a one-sphere clump: the sphere's force and torque themselves)
      const Vec3 weight = bodies.mass[b] * g;
      tq += (p.x[i0] - bodies.x[b]).cross(f - weight);
      for (std::int32_t k = c0 + 1; k < c1; ++k) {
        const std::size_t i = static_cast<std::size_t>(bc.particle[k]);
        const Vec3 contact = p.force[i] - weight;
        f += contact;
        tq += p.torque[i] + (p.x[i] - bodies.x[b]).cross(contact);
      }
    }
    bodies.force[b] = f;
    bodies.torque[b] = tq;
    if (!kick) continue;
    bodies.v[b] += (h / bodies.mass[b]) * f;
    if (bodies.spherical(b)) {
      const double inertia = bodies.inertia[b].x();
      bodies.w[b] += (h / inertia) * tq;
      bodies.l[b] = inertia * bodies.w[b];
    } else {
      bodies.l[b] += h * tq;
      bodies.w[b] = body_angular_velocity(bodies.q[b], bodies.l[b], bodies.inertia[b]);
    }
    move_components(b);
  }
}

void World::move_walls() {
  PhaseTimer t(profile_.move_walls);
  for (WallState& w : state_.walls) w.offset += model_.dt * w.velocity;
}

void World::update_neighbors() {
  PhaseTimer t(profile_.neighbors);
  // The wall candidates are rebuilt with the list, and alone when they are invalid (a restored
  // checkpoint, a wall switched) or a wall has moved half a skin. Rebuilding them alone never
  // reorders the particles, so the results do not depend on when it happens (a resumed run stays
  // bit-identical to an uninterrupted one).
  Particles& p = state_.particles;
  NeighborList& nl = state_.neighbors;
  const std::size_t n = p.size();
  const bool built = nl.built_for(n);
  double moved2 = moved2_;
  moved2_ = -1.0;  // used once: the next call measures again unless kick_drift has
  if (built && moved2 < 0.0) {  // not measured by kick_drift: positions may have been set
    state_.moved2.resize(n);
    moved2 = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      state_.moved2[i] = (p.x[i] - nl.x_at_build[i]).squaredNorm();
      moved2 = std::max(moved2, state_.moved2[i]);
    }
  }
  if (built && !nl.needs_rebuild(moved2)) {
    if (!wall_candidates_current()) build_wall_candidates();
    return;
  }
  build_neighbor_list(p, nl, /*sort_particles=*/true);
  if (state_.bodies.size() > 0) order_bodies();  // the components have moved in the arrays
  state_.moved2.assign(n, 0.0);
  // What a pair that did not touch last step must have: no springs or reactions. A pair with
  // springs carried over from the old list is taken as touching (live): the force phase clears
  // it if it does not.
  const std::size_t np = nl.pairs();
  state_.reaction.assign(np, Reaction{});
  state_.pair_live.resize(np);
  for (std::size_t k = 0; k < np; ++k)
    state_.pair_live[k] = nl.history[k].tangential != Vec3::Zero() ||
                          nl.history[k].rolling != Vec3::Zero();
  build_wall_candidates();
}

bool World::wall_candidates_current() const {
  if (!state_.wall_candidates_valid) return false;
  const double half_skin = 0.5 * state_.neighbors.skin;
  for (std::size_t w = 0; w < state_.walls.size(); ++w) {
    if ((state_.walls[w].offset - state_.wall_offset_at_build[w]).squaredNorm() >
        half_skin * half_skin)
      return false;
  }
  return true;
}

void World::build_wall_candidates() {
  Particles& p = state_.particles;
  const std::size_t n = p.size();
  const int nw = static_cast<int>(model_.walls.size());
  // Listed: gap below 1.5 skins. Until the next list rebuild a particle moves at most one skin
  // from here (half a skin on each side of the list's build) and a wall at most half a skin (or
  // the candidates are rebuilt), so every particle left out stays clear of every wall.
  const double reach = 1.5 * state_.neighbors.skin;
  state_.wall_cand_particle.clear();
  state_.wall_cand_start.assign(1, 0);
  state_.wall_cand_wall.clear();
  for (std::size_t i = 0; i < n; ++i) {
    bool any = false;
    for (int w = 0; w < nw; ++w) {
      const WallState& ws = state_.walls[w];
      Vec3 normal;
      double delta;
      if (ws.enabled &&
          wall_contact(model_.walls[w], ws.offset, p.x[i], p.radius[i] + reach, &normal, &delta)) {
        state_.wall_cand_wall.push_back(w);
        any = true;
      } else {
        p.wall_history[i][w] = ContactHistory{};  // farther than a skin: not touching now
      }
    }
    if (any) {
      state_.wall_cand_particle.push_back(static_cast<std::int32_t>(i));
      state_.wall_cand_start.push_back(static_cast<std::int32_t>(state_.wall_cand_wall.size()));
    }
  }
  state_.wall_offset_at_build.resize(nw);
  for (int w = 0; w < nw; ++w) state_.wall_offset_at_build[w] = state_.walls[w].offset;
  state_.wall_candidates_valid = true;
}

void World::pair_forces() {
  PhaseTimer t(profile_.pair_forces);
  const Particles& p = state_.particles;
  NeighborList& nl = state_.neighbors;
  const PairTable& table = model_.table;
  const Vec3 g = model_.settings.gravity;
  const double dt = model_.dt;
  const std::size_t n = p.size();
  const std::size_t par_min = model_.settings.parallel_min_particles;
  const std::size_t np = nl.pairs();
  if (state_.pair_live.size() != np || state_.reaction.size() != np ||
      nl.in_slot.size() != np || nl.in_particle.size() != np || nl.first.size() != np ||
      nl.clearance2.size() != np) {
    // A state assembled elsewhere (a restored checkpoint): nothing is known to be zero.
    derive_list_indices(nl);
    compute_clearances(nl, p);
    state_.reaction.assign(np, Reaction{});
    state_.pair_live.assign(np, 1);
  }
  // The particles are taken in blocks of kBlock. For each block: (1) its listed pairs are split
  // without a branch on the outcome: a pair that touched last step (pair_live; about half of
  // them on a heap) is queued for the kernel, which tests it as it computes it and clears it if
  // it separated; a pair that did not is skipped if neither particle has moved half the gap the
  // pair had when the list was built (NeighborList::clearance2: it cannot touch yet), and
  // distance-tested otherwise, the touching ones queued after the live ones (first touches, a
  // few per step). (2) The kernel runs on the queue several contacts at a time
  // (sim/pair_simd.hpp), which stores each pair's springs and reactions and each
  // contact's force and torque on its first member. (3) Each particle sums gravity and the
  // contacts it owns in list order (the two parts of the queue merged by pair index);
  // gather_wall_forces() then adds the reactions of the pairs it is second in (stored in the
  // second member's incoming slot). The sums' order is that of a one-contact-at-a-time loop over
  // the list and the same on any number of threads, so results stay bit-identical.
  // Raw pointers: the stores below (some of them bytes) would otherwise make the compiler reload
  // every vector's data pointer after each of them.
  const double* const mass = p.mass.data();
  const std::int32_t* const material = p.material.data();
  Vec3* const force = state_.particles.force.data();
  Vec3* const torque = state_.particles.torque.data();
  const std::int32_t* const start = nl.start.data();
  const std::int32_t* const first = nl.first.data();
  const std::int32_t* const second = nl.second.data();
  const std::int32_t* const slot = nl.in_slot.data();
  const double* const clearance2 = nl.clearance2.data();
  const double* const moved2 = state_.moved2.data();
  ContactHistory* const history = nl.history.data();
  Reaction* const reaction = state_.reaction.data();
  std::uint8_t* const live = state_.pair_live.data();
  const PairIsa isa = pair_isa_;  // the same bits with any of them
  constexpr std::size_t kBlock = 256;  // particles: about 400 touching pairs on a settled heap
  // The cost of each block, for the threads' ranges (first_block): a listed pair, a particle,
  // and a pair the kernel computed last step (block_queued_), weighed 6 (on the standard heap
  // the kernel takes several times as long per contact as the split per listed pair). Counting the
  // listed pairs alone left one of two threads waiting 3-5% of the loop: the share of listed
  // pairs that touch differs between blocks. The ranges only move work between threads; the
  // results do not depend on them.
  constexpr double kQueuedCost = 6.0;  // [listed pairs]
  const std::size_t blocks = (n + kBlock - 1) / kBlock;
  block_queued_.resize(blocks, 0);
  block_cost_.resize(blocks + 1);
  block_cost_[0] = 0.0;
  for (std::size_t b = 0; b < blocks; ++b) {
    const std::size_t i0 = b * kBlock, i1 = std::min(n, i0 + kBlock);
    block_cost_[b + 1] = block_cost_[b] + static_cast<double>(start[i1] - start[i0]) +
                         static_cast<double>(i1 - i0) + kQueuedCost * block_queued_[b];
  }
  std::int32_t* const block_queued = block_queued_.data();
  // A heap of one material (the usual case) has one set of pair constants: the split below
  // gives it to every live pair, and only the first touches look theirs up (2% of a step). The
  // materials are scanned every step (one vectorised pass, ~0.3% of a step), not cached: a
  // caller may change them through state() between steps.
  std::int32_t material_differs = 0;
  for (std::size_t i = 1; i < n; ++i) material_differs |= material[i] ^ material[0];
  const ContactConstants* const one_pair =
      n > 0 && material_differs == 0 ? &table.c(material[0], material[0]) : nullptr;
#pragma omp parallel if (n > par_min)
  {
    std::vector<QueuedContact> queue;
    std::vector<Vec3> queue_force, queue_torque;
    std::vector<std::int32_t> tested;  // (listed pairs of the block) positions to test
    Vec3 block_force[kBlock], block_torque[kBlock];
    // Each thread takes one contiguous range of blocks, of about equal work (first_block): the
    // particles kick_drift has just moved on the same core (its static halves) are still in that
    // core's cache; dealing blocks out dynamically loses that (13% slower on two threads).
    const int nt = omp_get_num_threads(), t = omp_get_thread_num();
    const std::size_t b_end = first_block(block_cost_, t + 1, nt);
    for (std::size_t b = first_block(block_cost_, t, nt); b < b_end; ++b) {
      const std::size_t i0 = b * kBlock, i1 = std::min(n, i0 + kBlock);
      const std::int32_t k0 = start[i0], k1 = start[i1];
      const std::size_t listed = static_cast<std::size_t>(k1 - k0);
      if (queue.size() < listed) {
        queue.resize(listed);
        queue_force.resize(listed);
        queue_torque.resize(listed);
        tested.resize(listed);
      }
      // The block's pairs in one flat loop (a loop per particle, of varying length, would cost
      // the branch predictor), each with its first member from the list.
      const std::int32_t* const owner = first + k0;
      // (1) Live pairs to the queue; the others to the distance test unless they cannot touch.
      std::size_t live_queued = 0, to_test = 0;
      for (std::size_t m = 0; m < listed; ++m) {
        const std::int32_t k = k0 + static_cast<std::int32_t>(m);
        const std::int32_t i = owner[m], j = second[k];
        const std::size_t was_live = live[k];
        queue[live_queued] = QueuedContact{k, i, j, one_pair};
        live_queued += was_live;
        tested[to_test] = static_cast<std::int32_t>(m);
        const bool clear = std::max(moved2[i], moved2[j]) < clearance2[k];
        to_test += static_cast<std::size_t>((was_live == 0) & !clear);
      }
      const std::size_t first_touches = queue_touching_pairs(
          p, owner, second, k0, tested.data(), to_test, live, queue.data() + live_queued);
      const std::size_t queued = live_queued + first_touches;
      block_queued[b] = static_cast<std::int32_t>(queued);
      // (2) The kernel.
      PairOutputs out;
      out.history = history;
      out.slot = slot;
      out.reaction = reaction;
      out.live = live;
      out.force_i = queue_force.data();
      out.torque_i = queue_torque.data();
      for (std::size_t q = one_pair ? live_queued : 0; q < queued; ++q)
        queue[q].c = &table.c(material[queue[q].i], material[queue[q].j]);
      compute_queued_contacts(isa, p, queue.data(), queued, dt, out);
      // (3) The sums, in list order.
      for (std::size_t i = i0; i < i1; ++i) {
        block_force[i - i0] = mass[i] * g;
        block_torque[i - i0].setZero();
      }
      auto add = [&](std::size_t q) {
        const std::size_t i = static_cast<std::size_t>(queue[q].i) - i0;
        block_force[i] += queue_force[q];
        block_torque[i] += queue_torque[q];
      };
      if (first_touches == 0) {
        for (std::size_t q = 0; q < queued; ++q) add(q);
      } else {
        for (std::size_t a = 0, f = live_queued; a < live_queued || f < queued;) {
          if (f == queued || (a < live_queued && queue[a].k < queue[f].k)) {
            add(a++);
          } else {
            add(f++);
          }
        }
      }
      for (std::size_t i = i0; i < i1; ++i) {
        force[i] = block_force[i - i0];
        torque[i] = block_torque[i - i0];
      }
    }
  }
}

void World::gather_wall_forces(bool kick) {
  PhaseTimer t(profile_.gather_walls_kick);
  Particles& p = state_.particles;
  const NeighborList& nl = state_.neighbors;
  const PairTable& table = model_.table;
  const double dt = model_.dt, h = 0.5 * model_.dt;
  const std::size_t n = p.size();
  const std::size_t par_min = model_.settings.parallel_min_particles;
  const std::vector<std::int32_t>& cand = state_.wall_cand_particle;
  const std::int32_t* const in_start = nl.in_start.data();
  const std::int32_t* const in_particle = nl.in_particle.data();
  const Reaction* const reaction = state_.reaction.data();
  // Blocks of particles. In each, the reactions of the pairs the block's particles are second
  // in (stored contiguously by incoming slot) are added in one flat loop over the slots (a loop
  // per particle, of 0 to 8 slots, would cost a mispredicted branch per particle); then the
  // wall contacts of the block's particles near an enabled wall are found, computed several at a
  // time (sim/pair_simd.hpp) and added in particle and wall order; then each particle takes the
  // closing kick. Every particle's sum has the order of a loop over its own slots and walls,
  // whichever thread takes its block. The blocks are dealt out a few at a time, not in halves:
  // the wall contacts gather in some of them (the plate's, all in the lowest layer).
  constexpr std::size_t kBlock = 256;
  const std::size_t blocks = (n + kBlock - 1) / kBlock;
#pragma omp parallel if (n > par_min)
  {
    WallContacts wc;
#pragma omp for schedule(dynamic, 4)
    for (std::size_t b = 0; b < blocks; ++b) {
      const std::size_t i0 = b * kBlock, i1 = std::min(n, i0 + kBlock);
      Vec3 f[kBlock], tq[kBlock];
      for (std::size_t i = i0; i < i1; ++i) {
        f[i - i0] = p.force[i];
        tq[i - i0] = p.torque[i];
      }
      for (std::int32_t q = in_start[i0]; q < in_start[i1]; ++q) {
        const std::size_t i = static_cast<std::size_t>(in_particle[q]) - i0;
        f[i] -= reaction[q].force;
        tq[i] += reaction[q].torque;
      }
      // Wall contacts (candidates in particle order): a wall a candidate does not touch has its
      // springs cleared.
      wc.clear();
      for (std::size_t c = static_cast<std::size_t>(
               std::lower_bound(cand.begin(), cand.end(), static_cast<std::int32_t>(i0)) -
               cand.begin());
           c < cand.size() && static_cast<std::size_t>(cand[c]) < i1; ++c) {
        const std::size_t i = static_cast<std::size_t>(cand[c]);
        for (std::int32_t q = state_.wall_cand_start[c]; q < state_.wall_cand_start[c + 1]; ++q) {
          const int w = state_.wall_cand_wall[q];
          const WallSpec& spec = model_.walls[w];
          const WallState& ws = state_.walls[w];
          Vec3 normal;
          double delta;
          if (!wall_contact(spec, ws.offset, p.x[i], p.radius[i], &normal, &delta)) {
            p.wall_history[i][w] = ContactHistory{};
            continue;
          }
          wc.add(static_cast<std::int32_t>(i), w, normal, delta, ws.velocity,
                 &table.c(p.material[i], spec.material));
        }
      }
      compute_wall_contacts(pair_isa_, p, wc, dt);
      for (std::size_t e = 0; e < wc.size(); ++e) {
        const std::size_t i = static_cast<std::size_t>(wc.particle[e]) - i0;
        f[i] += wc.force[e];
        tq[i] += wc.torque[e];
      }
      for (std::size_t i = i0; i < i1; ++i) {
        p.force[i] = f[i - i0];
        p.torque[i] = tq[i - i0];
        if (kick) {
          p.v[i] += (h / p.mass[i]) * f[i - i0];
          p.w[i] += (h / p.inertia[i]) * tq[i - i0];
        }
      }
    }
  }
  state_.forces_valid = true;
}

Diagnostics World::diagnose() const {
  Diagnostics d;
  const Particles& p = state_.particles;
  const double limit = model_.settings.escape_distance;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (!p.x[i].allFinite() || !p.v[i].allFinite() || !p.w[i].allFinite()) {
      if (d.status == Status::kOk) {
        d.status = Status::kNan;
        d.detail = "particle id " + std::to_string(p.id[i]) + " has a non-finite state";
      }
      continue;
    }
    if (p.body[i] < 0)  // (a clump's energy is its body's, below)
      d.kinetic_energy += 0.5 * p.mass[i] * p.v[i].squaredNorm() +
                          0.5 * p.inertia[i] * p.w[i].squaredNorm();
    d.max_speed = std::max(d.max_speed, p.v[i].norm());
    if (p.x[i].norm() > limit && d.status == Status::kOk) {
      d.status = Status::kEscaped;
      std::ostringstream os;
      os << "particle id " << p.id[i] << " at (" << p.x[i].transpose() << ") m is farther than "
         << limit << " m from the origin";
      d.detail = os.str();
    }
    for (std::size_t w = 0; w < model_.walls.size(); ++w) {
      Vec3 n;
      double delta;
      if (state_.walls[w].enabled &&
          wall_contact(model_.walls[w], state_.walls[w].offset, p.x[i], p.radius[i], &n, &delta)) {
        d.max_overlap_ratio = std::max(d.max_overlap_ratio, delta / p.radius[i]);
        ++d.contacts;
      }
    }
  }
  const Bodies& bodies = state_.bodies;
  for (std::size_t b = 0; b < bodies.size(); ++b)
    d.kinetic_energy += 0.5 * bodies.mass[b] * bodies.v[b].squaredNorm() +
                        0.5 * bodies.w[b].dot(bodies.l[b]);
  // The pairs' overlaps from the positions (the force phase keeps none: a step stores only what
  // the next one needs), by the kernel's touch test (|d|^2 < (r_i + r_j)^2).
  const NeighborList& nl = state_.neighbors;
  if (nl.built_for(p.size())) {
    for (std::size_t i = 0; i < p.size(); ++i) {
      for (std::int32_t k = nl.start[i]; k < nl.start[i + 1]; ++k) {
        const std::size_t j = static_cast<std::size_t>(nl.second[k]);
        const double cut = p.radius[i] + p.radius[j];
        const double dist2 = (p.x[i] - p.x[j]).squaredNorm();
        if (!(dist2 < cut * cut)) continue;
        const double ratio = (cut - std::sqrt(dist2)) / std::min(p.radius[i], p.radius[j]);
        d.max_overlap_ratio = std::max(d.max_overlap_ratio, ratio);
        ++d.contacts;
      }
    }
  }
  if (d.status == Status::kOk && d.max_overlap_ratio > model_.settings.max_overlap_ratio) {
    d.status = Status::kOverlap;
    std::ostringstream os;
    os << "largest overlap " << d.max_overlap_ratio << " of the smaller radius exceeds "
       << model_.settings.max_overlap_ratio;
    d.detail = os.str();
  }
  return d;
}

std::size_t World::remove_particles(const std::vector<char>& remove) {
  std::vector<char> keep(remove.size());
  std::size_t removed = 0;
  for (std::size_t i = 0; i < remove.size(); ++i) {
    keep[i] = !remove[i];
    removed += remove[i] ? 1 : 0;
  }
  if (removed == 0) return 0;
  Bodies& bodies = state_.bodies;
  Particles& p = state_.particles;
  if (bodies.size() > 0) {
    // Whole clumps: a body with any component removed goes with all of them.
    if (!state_.body_components.indexed_for(bodies.size()))
      index_body_components(p, bodies.size(), state_.body_components);
    const BodyComponents& bc = state_.body_components;
    std::vector<char> keep_body(bodies.size(), 1);
    for (std::size_t i = 0; i < keep.size(); ++i)
      if (!keep[i] && p.body[i] >= 0) keep_body[static_cast<std::size_t>(p.body[i])] = 0;
    std::vector<std::int32_t> new_index(bodies.size(), -1);
    std::int32_t kept = 0;
    for (std::size_t b = 0; b < bodies.size(); ++b) {
      if (keep_body[b]) {
        new_index[b] = kept++;
        continue;
      }
      for (std::int32_t k = bc.start[b]; k < bc.start[b + 1]; ++k) {
        removed += keep[static_cast<std::size_t>(bc.particle[k])] ? 1 : 0;
        keep[static_cast<std::size_t>(bc.particle[k])] = 0;
      }
    }
    for (std::size_t i = 0; i < p.size(); ++i)
      if (p.body[i] >= 0) p.body[i] = new_index[static_cast<std::size_t>(p.body[i])];
    bodies.keep(keep_body);
  }
  p.keep(keep);
  if (bodies.size() > 0) index_body_components(p, bodies.size(), state_.body_components);
  compact_neighbor_list(state_.neighbors, keep);
  const std::size_t np = state_.neighbors.pairs();
  state_.reaction.assign(np, Reaction{});
  state_.pair_live.assign(np, 1);  // unknown: the next force phase clears what does not touch
  state_.moved2.clear();           // measured again by the next force phase
  state_.forces_valid = false;
  state_.wall_candidates_valid = false;
  return removed;
}

std::uint64_t state_hash(const State& s) {
  std::uint64_t h = 1469598103934665603ull;
  auto mix = [&h](const void* data, std::size_t bytes) {
    const unsigned char* c = static_cast<const unsigned char*>(data);
    for (std::size_t k = 0; k < bytes; ++k) {
      h ^= c[k];
      h *= 1099511628211ull;
    }
  };
  const Particles& p = s.particles;
  for (std::size_t i = 0; i < p.size(); ++i) {
    mix(p.x[i].data(), 3 * sizeof(double));
    mix(p.v[i].data(), 3 * sizeof(double));
    mix(p.w[i].data(), 3 * sizeof(double));
    mix(&p.id[i], sizeof(std::int64_t));
  }
  const Bodies& b = s.bodies;  // (nothing without clumps: the spheres' hashes stay as they were)
  for (std::size_t k = 0; k < b.size(); ++k) {
    mix(b.x[k].data(), 3 * sizeof(double));
    mix(b.q[k].coeffs().data(), 4 * sizeof(double));
    mix(b.v[k].data(), 3 * sizeof(double));
    mix(b.l[k].data(), 3 * sizeof(double));
    mix(&b.id[k], sizeof(std::int64_t));
  }
  return h;
}

}  // namespace reposetwin::sim
