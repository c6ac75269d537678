#include "sim/pair_simd.hpp"

#include <immintrin.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace reposetwin::sim {
namespace {

static_assert(sizeof(Vec3) == 3 * sizeof(double), "the lanes read a Vec3 as 3 doubles");
static_assert(sizeof(Reaction) == 6 * sizeof(double),
              "the lanes write a Reaction as force then torque, 3 doubles each");
static_assert(sizeof(ContactHistory) == 6 * sizeof(double),
              "the lanes read a ContactHistory as tangential then rolling, 3 doubles each");

/// The arrays the lanes read and write, as raw pointers (3 doubles per Vec3, 6 per history).
struct LaneArrays {
  const double* x = nullptr;           // (particles x 3) [m]
  const double* v = nullptr;           // (particles x 3) [m/s]
  const double* w = nullptr;           // (particles x 3) [rad/s]
  const double* radius = nullptr;      // (particles) [m]
  const double* mass = nullptr;        // (particles) [kg]
  const double* inertia = nullptr;     // (particles) [kg m^2]
  double* history = nullptr;           // (pairs x 6) tangential [m], rolling [N m]
  const std::int32_t* slot = nullptr;  // (pairs)
  double* reaction = nullptr;          // (slots x 6) force [N], then torque [N m]
  std::uint8_t* live = nullptr;        // (pairs)
  double* force_i = nullptr;           // (queued x 3) [N]
  double* torque_i = nullptr;          // (queued x 3) [N m]
};

/// The particle arrays only (the pair outputs left null).
LaneArrays lane_arrays(const Particles& p) {
  LaneArrays a;
  a.x = p.x.data()->data();
  a.v = p.v.data()->data();
  a.w = p.w.data()->data();
  a.radius = p.radius.data();
  a.mass = p.mass.data();
  a.inertia = p.inertia.data();
  return a;
}

LaneArrays lane_arrays(const Particles& p, const PairOutputs& out) {
  LaneArrays a = lane_arrays(p);
  a.history = reinterpret_cast<double*>(out.history);
  a.slot = out.slot;
  a.reaction = reinterpret_cast<double*>(out.reaction);
  a.live = out.live;
  a.force_i = out.force_i->data();
  a.torque_i = out.torque_i->data();
  return a;
}

/// Clears the springs and reactions of pair k, which separated since the last step.
[[gnu::noinline]] void clear_pair(const PairOutputs& out, std::int32_t k) {
  out.history[k] = ContactHistory{};
  out.reaction[out.slot[k]] = Reaction{};
  out.live[k] = 0;
}

/// The wall springs and contact results the lanes read and write (3 doubles per Vec3, 6 per
/// ContactHistory; the history of particle i and wall w at 6 (i kMaxWalls + w)).
struct WallLaneArrays {
  const std::int32_t* particle = nullptr;
  const std::int32_t* wall = nullptr;
  const double* normal = nullptr;
  const double* overlap = nullptr;
  const double* wall_velocity = nullptr;
  const ContactConstants* const* c = nullptr;
  double* history = nullptr;
  double* force = nullptr;
  double* torque = nullptr;
};

static_assert(sizeof(WallHistory) == kMaxWalls * sizeof(ContactHistory),
              "the lanes address the wall springs as one array of ContactHistory");

WallLaneArrays wall_lane_arrays(Particles& p, WallContacts& wc) {
  WallLaneArrays w;
  w.particle = wc.particle.data();
  w.wall = wc.wall.data();
  w.normal = wc.normal.data()->data();
  w.overlap = wc.overlap.data();
  w.wall_velocity = wc.wall_velocity.data()->data();
  w.c = wc.c.data();
  w.history = reinterpret_cast<double*>(p.wall_history.data());
  w.force = wc.force.data()->data();
  w.torque = wc.torque.data()->data();
  return w;
}

/// The scalar kernel on wall contact e.
[[gnu::noinline]] void scalar_wall_contact(Particles& p, WallContacts& wc, std::size_t e,
                                           double dt) {
  const std::size_t i = static_cast<std::size_t>(wc.particle[e]);
  const ContactOutput o = hertz_mindlin(*wc.c[e], wall_input(p, wc, e), dt,
                                        p.wall_history[i][static_cast<std::size_t>(wc.wall[e])]);
  wc.force[e] = o.force;
  wc.torque[e] = o.torque_i;
}

/// The scalar kernel on queued contact q, with the stores of the pair loop.
[[gnu::noinline]] void scalar_contact(const Particles& p, const QueuedContact* contacts,
                                      std::size_t q, double dt, const PairOutputs& out) {
  const QueuedContact& e = contacts[q];
  {  // the distance test of queue_touching_pairs
    const Vec3& xi = p.x[e.i];
    const Vec3& xj = p.x[e.j];
    const double d0 = xi[0] - xj[0], d1 = xi[1] - xj[1], d2 = xi[2] - xj[2];
    const double cut = p.radius[e.i] + p.radius[e.j];
    if ((d0 * d0 + d1 * d1) + d2 * d2 >= cut * cut) {
      clear_pair(out, e.k);
      out.force_i[q].setZero();
      out.torque_i[q].setZero();
      return;
    }
  }
  const ContactInput in = pair_input(p, *e.c, e.i, e.j);
  const ContactOutput o = hertz_mindlin(*e.c, in, dt, out.history[e.k]);
  out.force_i[q] = o.force;
  out.torque_i[q] = o.torque_i;
  out.reaction[out.slot[e.k]] = Reaction{o.force, o.torque_j};
}

/// What the lanes store for a queued pair k that does not touch (any more): its springs,
/// reaction (at 6 times slot s6) cleared, zero force and torque for queue position
/// q3 / 3, live flag 0.
[[gnu::noinline]] void separate_lane(const LaneArrays& a, std::size_t k, std::size_t s6,
                                     std::size_t q3) {
  std::fill_n(a.history + 6 * k, 6, 0.0);
  std::fill_n(a.reaction + s6, 6, 0.0);
  std::fill_n(a.force_i + q3, 3, 0.0);
  std::fill_n(a.torque_i + q3, 3, 0.0);
  a.live[k] = 0;
}

// The lanes, one namespace per instruction set: the lane type V, its mask M and the operations
// the kernel uses. Only IEEE add, subtract, multiply, divide and square root, never a fused
// multiply-add (neither target enables FMA), so every width gives the scalar kernel's bits.

// Two contacts per instruction (SSE2, the x86-64 baseline).
namespace sse2 {

constexpr int kLanes = 2;
struct V {
  __m128d v;
};
struct M {
  __m128d v;
};
inline V operator+(V a, V b) { return {_mm_add_pd(a.v, b.v)}; }
inline V operator-(V a, V b) { return {_mm_sub_pd(a.v, b.v)}; }
inline V operator*(V a, V b) { return {_mm_mul_pd(a.v, b.v)}; }
inline V operator/(V a, V b) { return {_mm_div_pd(a.v, b.v)}; }
inline V operator-(V a) { return {_mm_xor_pd(a.v, _mm_set1_pd(-0.0))}; }  // as scalar negation
inline V vsqrt(V a) { return {_mm_sqrt_pd(a.v)}; }
inline V bcast(double s) { return {_mm_set1_pd(s)}; }
inline M operator>(V a, V b) { return {_mm_cmpgt_pd(a.v, b.v)}; }
inline M operator>=(V a, V b) { return {_mm_cmpge_pd(a.v, b.v)}; }
inline M operator!=(V a, V b) { return {_mm_cmpneq_pd(a.v, b.v)}; }  // true if unordered
/// !(a >= b): true if unordered.
inline M not_ge(V a, V b) { return {_mm_cmpnge_pd(a.v, b.v)}; }
/// Bit l set if lane l of the mask is.
inline int mask_bits(M m) { return _mm_movemask_pd(m.v); }
/// m ? a : b, lane by lane.
inline V select(M m, V a, V b) {
  return {_mm_or_pd(_mm_and_pd(m.v, a.v), _mm_andnot_pd(m.v, b.v))};
}
inline bool any(M m) { return _mm_movemask_pd(m.v) != 0; }
/// std::max(f, 0.0) = (f < 0) ? 0 : f; maxpd(a, b) = (a > b) ? a : b.
inline V max0(V f) { return {_mm_max_pd(_mm_setzero_pd(), f.v)}; }
/// (a < b) ? a : b.
inline V vmin(V a, V b) { return {_mm_min_pd(a.v, b.v)}; }
/// Lane l takes p[l][0].
inline V load1p(const double* const* p) { return {_mm_loadh_pd(_mm_load_sd(p[0]), p[1])}; }
/// Lane l takes b[ix[l]].
inline V load1(const double* b, const std::size_t* ix) {
  return {_mm_loadh_pd(_mm_load_sd(b + ix[0]), b + ix[1])};
}
/// Lane l takes the 3 doubles at b + ix[l].
inline void load3(const double* b, const std::size_t* ix, V& x, V& y, V& z) {
  const double* p0 = b + ix[0];
  const double* p1 = b + ix[1];
  const __m128d u = _mm_loadu_pd(p0), w = _mm_loadu_pd(p1);
  x.v = _mm_unpacklo_pd(u, w);
  y.v = _mm_unpackhi_pd(u, w);
  z.v = _mm_loadh_pd(_mm_load_sd(p0 + 2), p1 + 2);
}
/// Stores lane l (l < valid) to the 3 doubles at b + ix[l].
inline void store3(double* b, const std::size_t* ix, int valid, V x, V y, V z) {
  _mm_storeu_pd(b + ix[0], _mm_unpacklo_pd(x.v, y.v));
  _mm_store_sd(b + ix[0] + 2, z.v);
  if (valid > 1) {
    _mm_storeu_pd(b + ix[1], _mm_unpackhi_pd(x.v, y.v));
    _mm_storeh_pd(b + ix[1] + 2, z.v);
  }
}

#include "sim/pair_lanes.inc"

/// queue_touching_pairs: the distance test of kLanes listed pairs at once, the touching ones
/// appended to the queue without a branch on the outcome.
std::size_t scan_pairs(const LaneArrays& a, const std::int32_t* owner, const std::int32_t* second,
                       std::int32_t k0, const std::int32_t* tested, std::size_t count,
                       std::uint8_t* live, QueuedContact* queue) {
  std::size_t queued = 0, t = 0;
  for (; t + kLanes <= count; t += kLanes) {
    std::size_t i1[kLanes], j1[kLanes], i3[kLanes], j3[kLanes];
    std::int32_t k[kLanes];
    for (int l = 0; l < kLanes; ++l) {
      const std::int32_t m = tested[t + l];
      k[l] = k0 + m;
      i1[l] = static_cast<std::size_t>(owner[m]);
      j1[l] = static_cast<std::size_t>(second[k[l]]);
      i3[l] = 3 * i1[l];
      j3[l] = 3 * j1[l];
    }
    V xi0, xi1, xi2, xj0, xj1, xj2;
    load3(a.x, i3, xi0, xi1, xi2);
    load3(a.x, j3, xj0, xj1, xj2);
    const V d0 = xi0 - xj0, d1 = xi1 - xj1, d2 = xi2 - xj2;
    const V cut = load1(a.radius, i1) + load1(a.radius, j1);
    // The pair loop's test: not touching if |d|^2 >= cut^2.
    const int touch = mask_bits(not_ge(dot3(d0, d1, d2, d0, d1, d2), cut * cut));
    for (int l = 0; l < kLanes; ++l) {
      QueuedContact& e = queue[queued];
      e.k = k[l];
      e.i = static_cast<std::int32_t>(i1[l]);
      e.j = static_cast<std::int32_t>(j1[l]);
      const int bit = (touch >> l) & 1;
      queued += static_cast<std::size_t>(bit);
      live[k[l]] = static_cast<std::uint8_t>(bit);
    }
  }
  for (; t < count; ++t) {
    const std::int32_t m = tested[t];
    const std::int32_t k = k0 + m;
    const std::size_t i = static_cast<std::size_t>(owner[m]);
    const std::size_t j = static_cast<std::size_t>(second[k]);
    const double* xi = a.x + 3 * i;
    const double* xj = a.x + 3 * j;
    const double d0 = xi[0] - xj[0], d1 = xi[1] - xj[1], d2 = xi[2] - xj[2];
    const double cut = a.radius[i] + a.radius[j];
    if ((d0 * d0 + d1 * d1) + d2 * d2 >= cut * cut) continue;
    live[k] = 1;
    queue[queued++] =
        QueuedContact{k, static_cast<std::int32_t>(i), static_cast<std::int32_t>(j), nullptr};
  }
  return queued;
}

}  // namespace sse2

// Four contacts per instruction (AVX, chosen at run time where the CPU has it). GCC takes the
// target for a region from its pragma; clang (the fuzz build) from an attribute on every
// function of the region.
#if defined(__clang__)
#pragma clang attribute push(__attribute__((target("avx"))), apply_to = function)
#else
#pragma GCC push_options
#pragma GCC target("avx")
#endif

namespace avx {

#include "sim/pair_lanes_avx.inc"
#include "sim/pair_lanes.inc"

}  // namespace avx

#if defined(__clang__)
#pragma clang attribute pop
#else
#pragma GCC pop_options
#endif

// The same four lanes where the CPU has AVX-512VL: the same arithmetic on 256 bits, with 32
// vector registers instead of 16, and the lane masks in mask registers
// (REPOSETWIN_LANES_KMASK): a compare writes one, a select is one vblendmpd where AVX's
// vblendvpd takes several micro-ops (3-5% fewer seconds per step on the standard heap).
#if defined(__clang__)
#pragma clang attribute push(__attribute__((target("avx2,avx512f,avx512vl"))), \
                             apply_to = function)
#else
#pragma GCC push_options
#pragma GCC target("avx2,avx512f,avx512vl")
#endif

namespace avx512vl {

#define REPOSETWIN_LANES_KMASK
#include "sim/pair_lanes_avx.inc"
#undef REPOSETWIN_LANES_KMASK
#include "sim/pair_lanes.inc"

}  // namespace avx512vl

#if defined(__clang__)
#pragma clang attribute pop
#else
#pragma GCC pop_options
#endif

bool cpu_has_avx() {
  static const bool has = __builtin_cpu_supports("avx");
  return has;
}


bool cpu_has_avx512vl() {
  static const bool has =
      __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl");
  return has;
}

}  // namespace

std::size_t queue_touching_pairs(const Particles& p, const std::int32_t* owner,
                                 const std::int32_t* second, std::int32_t k0,
                                 const std::int32_t* tested, std::size_t count,
                                 std::uint8_t* live, QueuedContact* queue) {
  if (count == 0) return 0;
  LaneArrays a;
  a.x = p.x.data()->data();
  a.radius = p.radius.data();
  return sse2::scan_pairs(a, owner, second, k0, tested, count, live, queue);
}

void compute_queued_contacts(PairIsa isa, const Particles& p, const QueuedContact* contacts,
                             std::size_t count, double dt, const PairOutputs& out) {
  if (count == 0) return;
  switch (isa) {
    case PairIsa::kScalar:
      for (std::size_t q = 0; q < count; ++q) scalar_contact(p, contacts, q, dt, out);
      return;
    case PairIsa::kSse2:
      sse2::run_queue(lane_arrays(p, out), p, contacts, count, dt, out);
      return;
    case PairIsa::kAvx:
      if (!cpu_has_avx())
        throw std::invalid_argument("compute_queued_contacts: isa kAvx, but this CPU has no AVX");
      avx::run_queue(lane_arrays(p, out), p, contacts, count, dt, out);
      return;
    case PairIsa::kAvx512Vl:
      if (!cpu_has_avx512vl())
        throw std::invalid_argument(
            "compute_queued_contacts: isa kAvx512Vl, but this CPU has no AVX-512VL");
      avx512vl::run_queue(lane_arrays(p, out), p, contacts, count, dt, out);
      return;
  }
}

void compute_wall_contacts(PairIsa isa, Particles& p, WallContacts& wc, double dt) {
  const std::size_t count = wc.size();
  wc.force.resize(count);
  wc.torque.resize(count);
  if (count == 0) return;
  switch (isa) {
    case PairIsa::kScalar:
      for (std::size_t e = 0; e < count; ++e) scalar_wall_contact(p, wc, e, dt);
      return;
    case PairIsa::kSse2:
      sse2::run_wall_queue(lane_arrays(p), wall_lane_arrays(p, wc), p, wc, count, dt);
      return;
    case PairIsa::kAvx:
      if (!cpu_has_avx())
        throw std::invalid_argument("compute_wall_contacts: isa kAvx, but this CPU has no AVX");
      avx::run_wall_queue(lane_arrays(p), wall_lane_arrays(p, wc), p, wc, count, dt);
      return;
    case PairIsa::kAvx512Vl:
      if (!cpu_has_avx512vl())
        throw std::invalid_argument(
            "compute_wall_contacts: isa kAvx512Vl, but this CPU has no AVX-512VL");
      avx512vl::run_wall_queue(lane_arrays(p), wall_lane_arrays(p, wc), p, wc, count, dt);
      return;
  }
}

bool pair_isa_available(PairIsa isa) {
  switch (isa) {
    case PairIsa::kScalar:
    case PairIsa::kSse2:
      return true;
    case PairIsa::kAvx:
      return cpu_has_avx();
    case PairIsa::kAvx512Vl:
      return cpu_has_avx512vl();
  }
  return false;
}

PairIsa best_pair_isa() {
  if (cpu_has_avx512vl()) return PairIsa::kAvx512Vl;
  return cpu_has_avx() ? PairIsa::kAvx : PairIsa::kSse2;
}

const char* pair_isa_name(PairIsa isa) {
  switch (isa) {
    case PairIsa::kScalar:
      return "scalar";
    case PairIsa::kSse2:
      return "sse2";
    case PairIsa::kAvx:
      return "avx";
    case PairIsa::kAvx512Vl:
      return "avx512vl";
  }
  return "?";
}

}  // namespace reposetwin::sim
