#include "sim/pair_simd.hpp"

#include <immintrin.h>

#include <algorithm>
#include <cmath>

namespace reposetwin::sim {
namespace {

static_assert(sizeof(Vec3) == 3 * sizeof(double), "the lanes read a Vec3 as 3 doubles");
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
  double* reaction_force = nullptr;    // (slots x 3) [N]
  double* reaction_torque = nullptr;   // (slots x 3) [N m]
  double* overlap = nullptr;           // (pairs) [-]
  std::uint8_t* live = nullptr;        // (pairs)
  double* force_i = nullptr;           // (queued x 3) [N]
  double* torque_i = nullptr;          // (queued x 3) [N m]
};

LaneArrays lane_arrays(const Particles& p, const PairOutputs& out) {
  LaneArrays a;
  a.x = p.x.data()->data();
  a.v = p.v.data()->data();
  a.w = p.w.data()->data();
  a.radius = p.radius.data();
  a.mass = p.mass.data();
  a.inertia = p.inertia.data();
  a.history = reinterpret_cast<double*>(out.history);
  a.slot = out.slot;
  a.reaction_force = out.reaction_force->data();
  a.reaction_torque = out.reaction_torque->data();
  a.overlap = out.overlap;
  a.live = out.live;
  a.force_i = out.force_i->data();
  a.torque_i = out.torque_i->data();
  return a;
}

/// Clears the springs, reactions and overlap of pair k, which separated since the last step.
[[gnu::noinline]] void clear_pair(const PairOutputs& out, std::int32_t k) {
  out.history[k] = ContactHistory{};
  out.reaction_force[out.slot[k]].setZero();
  out.reaction_torque[out.slot[k]].setZero();
  out.overlap[k] = 0.0;
  out.live[k] = 0;
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
  out.reaction_force[out.slot[e.k]] = o.force;
  out.reaction_torque[out.slot[e.k]] = o.torque_j;
  out.overlap[e.k] = in.delta / std::min(p.radius[e.i], p.radius[e.j]);
}

// Two contacts per instruction (SSE2, the x86-64 baseline): the lane type V, its mask M and the
// operations the kernel uses. Only IEEE add, subtract, multiply, divide and square root, never
// a fused multiply-add (the baseline has none).

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
/// Stores lane l (l < valid) to b[ix[l]].
inline void store1(double* b, const std::size_t* ix, int valid, V a) {
  _mm_store_sd(b + ix[0], a.v);
  if (valid > 1) _mm_storeh_pd(b + ix[1], a.v);
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

/// What the lanes store for a queued pair k that does not touch (any more): its springs,
/// reactions (at 3 times slot s3) and overlap cleared, zero force and torque for queue position
/// q3 / 3, live flag 0.
[[gnu::noinline]] void separate_lane(const LaneArrays& a, std::size_t k, std::size_t s3,
                                     std::size_t q3) {
  std::fill_n(a.history + 6 * k, 6, 0.0);
  std::fill_n(a.reaction_force + s3, 3, 0.0);
  std::fill_n(a.reaction_torque + s3, 3, 0.0);
  std::fill_n(a.force_i + q3, 3, 0.0);
  std::fill_n(a.torque_i + q3, 3, 0.0);
  a.overlap[k] = 0.0;
  a.live[k] = 0;
}

// The kernel. Each line is the operation of the scalar kernel (pair_input, hertz_mindlin and the
// functions it calls, sim/contact.hpp) in the same order; a three-term sum is written
// (a0 + a1) + a2 because Eigen sums a Vector3d in that order.

/// (a0 b0 + a1 b1) + a2 b2, as Eigen's dot product and squared norm of a Vector3d.
[[gnu::always_inline]] inline V dot3(V a0, V a1, V a2, V b0, V b1, V b2) {
  return (a0 * b0 + a1 * b1) + a2 * b2;
}

/// rotate_spring: the spring s rotated into the plane normal to n, keeping its length.
[[gnu::always_inline]] inline void rotate_spring_lanes(V n0, V n1, V n2, V& s0, V& s1, V& s2) {
  const V zero = bcast(0.0);
  const V len2 = dot3(s0, s1, s2, s0, s1, s2);
  const V sn = dot3(s0, s1, s2, n0, n1, n2);
  const V p0 = s0 - sn * n0, p1 = s1 - sn * n1, p2 = s2 - sn * n2;
  const V proj2 = dot3(p0, p1, p2, p0, p1, p2);
  const V fac = select(proj2 > zero, vsqrt(len2 / proj2), zero);
  const M nonzero = len2 > zero;
  s0 = select(nonzero, p0 * fac, s0);
  s1 = select(nonzero, p1 * fac, s1);
  s2 = select(nonzero, p2 * fac, s2);
}

/// The contacts queued at positions q[0..kLanes) (the first `valid` of them real, the rest
/// copies of the last real one, whose results are not stored).
[[gnu::always_inline]] inline void contact_group(const LaneArrays& a, const QueuedContact* contacts,
                                                 double dt_s, const std::int32_t* q, int valid) {
  // Each lane's indices: particles i and j (and 3 i, 3 j into the Vec3 arrays), pair k (and
  // 6 k into the histories), 3 times its reaction slot and 3 times its queue position.
  std::size_t i1[kLanes], j1[kLanes], i3[kLanes], j3[kLanes], k1[kLanes], k6[kLanes], s3[kLanes],
      q3[kLanes];
  for (int l = 0; l < kLanes; ++l) {
    const QueuedContact& e = contacts[q[l]];
    i1[l] = static_cast<std::size_t>(e.i);
    j1[l] = static_cast<std::size_t>(e.j);
    i3[l] = 3 * i1[l];
    j3[l] = 3 * j1[l];
    k1[l] = static_cast<std::size_t>(e.k);
    k6[l] = 6 * k1[l];
    s3[l] = 3 * static_cast<std::size_t>(a.slot[k1[l]]);
    q3[l] = 3 * static_cast<std::size_t>(q[l]);
  }
  // The pair constants: broadcast if every lane has the same material pair (a heap of one
  // material), gathered lane by lane otherwise.
  V hertz, nd, td, g_star, mu_s, mu_r, eta;
  bool one_pair = true;
  for (int l = 1; l < kLanes; ++l) one_pair &= contacts[q[l]].c == contacts[q[0]].c;
  if (one_pair) {
    const ContactConstants& c = *contacts[q[0]].c;
    hertz = bcast(c.hertz_factor);
    nd = bcast(c.normal_damping);
    td = bcast(c.tangential_damping);
    g_star = bcast(c.g_star);
    mu_s = bcast(c.mu_s);
    mu_r = bcast(c.mu_r);
    eta = bcast(c.eta_r);
  } else {
    const double* f[kLanes];
    auto gather = [&](double ContactConstants::*field) {
      for (int l = 0; l < kLanes; ++l) f[l] = &(contacts[q[l]].c->*field);
      return load1p(f);
    };
    hertz = gather(&ContactConstants::hertz_factor);
    nd = gather(&ContactConstants::normal_damping);
    td = gather(&ContactConstants::tangential_damping);
    g_star = gather(&ContactConstants::g_star);
    mu_s = gather(&ContactConstants::mu_s);
    mu_r = gather(&ContactConstants::mu_r);
    eta = gather(&ContactConstants::eta_r);
  }
  const V zero = bcast(0.0);
  const V half = bcast(0.5);
  const V dt = bcast(dt_s);

  // pair_input: geometry and relative velocity at the contact point.
  V xi0, xi1, xi2, xj0, xj1, xj2;
  load3(a.x, i3, xi0, xi1, xi2);
  load3(a.x, j3, xj0, xj1, xj2);
  const V ri = load1(a.radius, i1), rj = load1(a.radius, j1);
  const V d0 = xi0 - xj0, d1 = xi1 - xj1, d2 = xi2 - xj2;
  const V cut = ri + rj;
  const V dist2 = dot3(d0, d1, d2, d0, d1, d2);
  // The distance test of queue_touching_pairs: a live pair may have separated since last step.
  const int touch = mask_bits(not_ge(dist2, cut * cut));
  const V dist = vsqrt(dist2);
  const V n0 = d0 / dist, n1 = d1 / dist, n2 = d2 / dist;
  const V delta = cut - dist;
  const V r_eff = ri * rj / cut;
  const V mi = load1(a.mass, i1), mj = load1(a.mass, j1);
  const V m_eff = mi * mj / (mi + mj);
  const V a_i = ri - half * delta;
  const V a_j = rj - half * delta;
  V wi0, wi1, wi2, wj0, wj1, wj2, vi0, vi1, vi2, vj0, vj1, vj2;
  load3(a.w, i3, wi0, wi1, wi2);
  load3(a.w, j3, wj0, wj1, wj2);
  load3(a.v, i3, vi0, vi1, vi2);
  load3(a.v, j3, vj0, vj1, vj2);
  // w x n, component by component as Eigen's cross product.
  const V ci0 = wi1 * n2 - wi2 * n1, ci1 = wi2 * n0 - wi0 * n2, ci2 = wi0 * n1 - wi1 * n0;
  const V cj0 = wj1 * n2 - wj2 * n1, cj1 = wj2 * n0 - wj0 * n2, cj2 = wj0 * n1 - wj1 * n0;
  const V vr0 = ((vi0 - vj0) - a_i * ci0) - a_j * cj0;
  const V vr1 = ((vi1 - vj1) - a_i * ci1) - a_j * cj1;
  const V vr2 = ((vi2 - vj2) - a_i * ci2) - a_j * cj2;

  // contact_stiffness.
  const V g8 = bcast(8.0) * g_star;
  const V sqrt_rd = vsqrt(r_eff * delta);
  const V root = vsqrt(sqrt_rd * m_eff);
  const V s_t = g8 * sqrt_rd;
  const V gamma_n = nd * root;
  const V gamma_t = td * root;

  // hertz_normal.
  const V v_n = dot3(vr0, vr1, vr2, n0, n1, n2);
  const V f_n = hertz * sqrt_rd * delta - gamma_n * v_n;
  const V vt0 = vr0 - v_n * n0, vt1 = vr1 - v_n * n1, vt2 = vr2 - v_n * n2;
  const V f_n_pos = max0(f_n);  // std::max(f_n, 0.0)

  // mindlin_tangential.
  V s0, s1, s2;
  load3(a.history, k6, s0, s1, s2);
  rotate_spring_lanes(n0, n1, n2, s0, s1, s2);
  s0 = s0 + vt0 * dt;
  s1 = s1 + vt1 * dt;
  s2 = s2 + vt2 * dt;
  const V neg_st = -s_t;
  V f0 = neg_st * s0 - gamma_t * vt0;
  V f1 = neg_st * s1 - gamma_t * vt1;
  V f2 = neg_st * s2 - gamma_t * vt2;
  const V cap = mu_s * f_n_pos;
  const V fs2 = dot3(f0, f1, f2, f0, f1, f2);
  const M slip = fs2 > cap * cap;
  // The slip and the rolling cap are computed for every pair of lanes and selected, not
  // branched on: in a heap either occurs in a fraction of the contacts that no predictor
  // follows, and a mispredicted branch costs more than the square root and divisions it skips
  // (bench/README.md, session 8).
  {
    const V fmag = vsqrt(fs2);
    const V scale = select(fmag > zero, cap / fmag, zero);
    const V g0 = f0 * scale, g1 = f1 * scale, g2 = f2 * scale;
    const M st_pos = s_t > zero;
    s0 = select(slip, select(st_pos, -g0 / s_t, zero), s0);
    s1 = select(slip, select(st_pos, -g1 / s_t, zero), s1);
    s2 = select(slip, select(st_pos, -g2 / s_t, zero), s2);
    f0 = select(slip, g0, f0);
    f1 = select(slip, g1, f1);
    f2 = select(slip, g2, f2);
  }
  store3(a.history, k6, valid, s0, s1, s2);

  // hertz_mindlin: force on i, torques of the tangential force.
  const V force0 = f_n * n0 + f0, force1 = f_n * n1 + f1, force2 = f_n * n2 + f2;
  const V nf0 = n1 * f2 - n2 * f1, nf1 = n2 * f0 - n0 * f2, nf2 = n0 * f1 - n1 * f0;
  const V neg_ai = -a_i, neg_aj = -a_j;
  V ti0 = neg_ai * nf0, ti1 = neg_ai * nf1, ti2 = neg_ai * nf2;
  V tj0 = neg_aj * nf0, tj1 = neg_aj * nf1, tj2 = neg_aj * nf2;

  // rolling_epsd.
  V wr0 = wi0 - wj0, wr1 = wi1 - wj1, wr2 = wi2 - wj2;
  const V wn = dot3(wr0, wr1, wr2, n0, n1, n2);
  wr0 = wr0 - wn * n0;
  wr1 = wr1 - wn * n1;
  wr2 = wr2 - wn * n2;
  V m0, m1, m2;
  load3(a.history + 3, k6, m0, m1, m2);
  rotate_spring_lanes(n0, n1, n2, m0, m1, m2);
  const V k_r = s_t * r_eff * r_eff;
  const V k_r_dt = k_r * dt;
  m0 = m0 - k_r_dt * wr0;
  m1 = m1 - k_r_dt * wr1;
  m2 = m2 - k_r_dt * wr2;
  const V rcap = mu_r * f_n_pos * r_eff;
  const V ms2 = dot3(m0, m1, m2, m0, m1, m2);
  const M at_cap = ms2 >= rcap * rcap;
  {
    const V mag = vsqrt(ms2);
    const V scale = select(mag > zero, rcap / mag, zero);
    m0 = select(at_cap, m0 * scale, m0);
    m1 = select(at_cap, m1 * scale, m1);
    m2 = select(at_cap, m2 * scale, m2);
  }
  V r0 = m0, r1 = m1, r2 = m2;  // the torque on i
  store3(a.history + 3, k6, valid, m0, m1, m2);
  const M damped = eta != zero;  // rolling_epsd: no dashpot if eta_r == 0
  if (any(damped)) {
    // pair_input's rolling inertia (0 unless eta_r > 0), then the dashpot below the cap.
    const V one = bcast(1.0);
    const V i_roll = select(eta > zero,
                            one / (one / (load1(a.inertia, i1) + mi * ri * ri) +
                                   one / (load1(a.inertia, j1) + mj * rj * rj)),
                            zero);
    const V damp = bcast(2.0) * eta * vsqrt(i_roll * k_r);
    r0 = select(at_cap, m0, select(damped, m0 - damp * wr0, m0));
    r1 = select(at_cap, m1, select(damped, m1 - damp * wr1, m1));
    r2 = select(at_cap, m2, select(damped, m2 - damp * wr2, m2));
  }
  ti0 = ti0 + r0;
  ti1 = ti1 + r1;
  ti2 = ti2 + r2;
  tj0 = tj0 - r0;
  tj1 = tj1 - r1;
  tj2 = tj2 - r2;

  // The stores of pair_forces.
  store3(a.force_i, q3, valid, force0, force1, force2);
  store3(a.torque_i, q3, valid, ti0, ti1, ti2);
  store3(a.reaction_force, s3, valid, force0, force1, force2);
  store3(a.reaction_torque, s3, valid, tj0, tj1, tj2);
  store1(a.overlap, k1, valid, delta / vmin(rj, ri));  // std::min(ri, rj)
  const int stored = (1 << valid) - 1;  // the lanes whose results are stored
  if ((touch & stored) != stored) {      // one of them separated (rare)
    for (int l = 0; l < valid; ++l)
      if (((touch >> l) & 1) == 0) separate_lane(a, k1[l], s3[l], q3[l]);
  }
}

/// compute_queued_contacts on the lanes.
void run_queue(const LaneArrays& a, const Particles& p, const QueuedContact* contacts,
               std::size_t count, double dt, const PairOutputs& out) {
  std::int32_t group[kLanes];
  int g = 0;
  for (std::size_t q = 0; q < count; ++q) {
    if (!lanes_eligible(*contacts[q].c)) {
      scalar_contact(p, contacts, q, dt, out);
      continue;
    }
    group[g++] = static_cast<std::int32_t>(q);
    if (g == kLanes) {
      contact_group(a, contacts, dt, group, kLanes);
      g = 0;
    }
  }
  if (g > 0) {
    for (int l = g; l < kLanes; ++l) group[l] = group[g - 1];
    contact_group(a, contacts, dt, group, g);
  }
}

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

}  // namespace

std::size_t queue_touching_pairs(const Particles& p, const std::int32_t* owner,
                                 const std::int32_t* second, std::int32_t k0,
                                 const std::int32_t* tested, std::size_t count,
                                 std::uint8_t* live, QueuedContact* queue) {
  if (count == 0) return 0;
  LaneArrays a;
  a.x = p.x.data()->data();
  a.radius = p.radius.data();
  return scan_pairs(a, owner, second, k0, tested, count, live, queue);
}

void compute_queued_contacts(PairIsa isa, const Particles& p, const QueuedContact* contacts,
                             std::size_t count, double dt, const PairOutputs& out) {
  if (count == 0) return;
  if (isa == PairIsa::kScalar) {
    for (std::size_t q = 0; q < count; ++q) scalar_contact(p, contacts, q, dt, out);
    return;
  }
  run_queue(lane_arrays(p, out), p, contacts, count, dt, out);
}

}  // namespace reposetwin::sim
