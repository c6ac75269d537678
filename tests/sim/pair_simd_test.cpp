// The SIMD lanes of sim/pair_simd.hpp against the scalar kernel, contact by contact: random
// polydisperse contacts of several material pairs (EPSD with and without the rolling dashpot,
// CDT, no rolling, cohesion, size-dependent rolling), with springs that are zero (first touch),
// small (sticking), large (sliding at the Coulomb cap, rolling at its cap), along the normal
// (rotated to nothing), and separating contacts whose normal force is negative. Every output of
// the SSE2 lanes (and of the scalar path) must equal, bit for bit, what pair_input +
// hertz_mindlin give; a queued pair that no longer touches is cleared. The lanes' distance
// test must queue what the distance definition says.
#include "sim/pair_simd.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <vector>

#include "sim/model.hpp"
#include "sim/random.hpp"

namespace reposetwin::sim {
namespace {

constexpr double kDt = 4e-6;  // [s]

/// Four materials and a pair table covering every branch of hertz_mindlin.
Model mixed_model() {
  Model m;
  const double youngs[4] = {46.8e6, 70e6, 30e6, 46.8e6};
  const double poisson[4] = {0.19, 0.25, 0.3, 0.19};
  const double density[4] = {2760, 2500, 2900, 2760};
  const char* const names[4] = {"m0", "m1", "m2", "m3"};
  for (int k = 0; k < 4; ++k) {
    Material mat;
    mat.name = names[k];
    mat.youngs_modulus = youngs[k];
    mat.poisson_ratio = poisson[k];
    mat.density = density[k];
    m.materials.push_back(mat);
  }
  PairParams epsd;  // the standard heap's pair: EPSD without dashpot
  epsd.rolling_damping = 0.0;
  PairParams damped;  // EPSD with dashpot, other friction
  damped.rolling_damping = 0.3;
  damped.friction = 0.9;
  damped.rolling_friction = 0.4;
  damped.restitution = 0.5;
  PairParams cdt;
  cdt.rolling_model = RollingModel::kCdt;
  PairParams none;
  none.rolling_model = RollingModel::kNone;
  PairParams cohesive;
  cohesive.cohesion_energy_density = 2e5;
  PairParams sized;
  sized.rolling_size_exponent = -0.5;
  sized.rolling_reference_diameter = 1.5e-3;
  const PairParams table[4][4] = {{epsd, damped, cdt, epsd},
                                  {damped, damped, cohesive, none},
                                  {cdt, cohesive, sized, epsd},
                                  {epsd, none, epsd, damped}};
  for (int a = 0; a < 4; ++a)
    for (int b = a; b < 4; ++b) m.set_pair(a, b, table[a][b]);
  m.finalize(0.5e-3, 1e-3);
  return m;
}

/// Random contacts: particles 2q and 2q+1 touch in contact q.
struct Scene {
  Particles p;
  std::vector<QueuedContact> contacts;
  std::vector<ContactHistory> history;  // (pairs)
  std::vector<std::int32_t> slot;       // (pairs)
};

Vec3 random_unit(Rng& rng) {
  for (;;) {
    const Vec3 u(rng.normal(), rng.normal(), rng.normal());
    if (u.norm() > 1e-3) return u.normalized();
  }
}

/// A magnitude log-uniform in [lo, hi].
double log_uniform(Rng& rng, double lo, double hi) { return lo * std::pow(hi / lo, rng.uniform()); }

Scene random_scene(const Model& m, int count, std::uint64_t seed) {
  Rng rng(seed);
  Scene s;
  const int nm = static_cast<int>(m.materials.size());
  for (int q = 0; q < count; ++q) {
    const int mi = static_cast<int>(rng.below(nm)), mj = static_cast<int>(rng.below(nm));
    const double ri = rng.uniform(0.5e-3, 1e-3), rj = rng.uniform(0.5e-3, 1e-3);
    // Axis-aligned normals now and then: a spring along them rotates to exactly zero.
    const bool axis = rng.uniform() < 0.05;
    const Vec3 n = axis ? Vec3(1, 0, 0) : random_unit(rng);
    const double delta = std::min(ri, rj) * log_uniform(rng, 1e-7, 2e-2);
    const Vec3 xi(rng.uniform(-0.01, 0.01), rng.uniform(-0.01, 0.01), rng.uniform(0, 0.01));
    const Vec3 xj = xi - (ri + rj - delta) * n;
    const std::size_t i = s.p.add(xi, ri, m.materials[mi].density, mi, 2 * q);
    const std::size_t j = s.p.add(xj, rj, m.materials[mj].density, mj, 2 * q + 1);
    for (std::size_t b : {i, j}) {
      s.p.v[b] = Vec3(rng.normal(0, 0.05), rng.normal(0, 0.05), rng.normal(0, 0.05));
      s.p.w[b] = Vec3(rng.normal(0, 50), rng.normal(0, 50), rng.normal(0, 50));
    }
    if (rng.uniform() < 0.1) s.p.v[i] += 0.5 * n;  // separating fast: negative normal force
    ContactHistory h;
    const double kind = rng.uniform();
    if (axis) {
      h.tangential = Vec3(1e-6, 0, 0);  // along n: rotated to zero
    } else if (kind < 0.2) {
      // zero springs: first touch
    } else if (kind < 0.5) {
      // Springs in the last step's tangent plane, the normal having turned through a small angle
      // since (1e-9 to 1e-2 rad): the rescale by its series and, beyond 1e-3 rad, exactly.
      const Vec3 r = random_unit(rng);
      const Vec3 t = (r - r.dot(n) * n).normalized();
      auto turned = [&](double length) -> Vec3 {
        const double angle = log_uniform(rng, 1e-9, 1e-2);
        const Vec3 u = (n - n.dot(t) * t).normalized();
        return length * (std::cos(angle) * t + std::sin(angle) * u);
      };
      h.tangential = turned(log_uniform(rng, 1e-10, 1e-4));
      h.rolling = turned(log_uniform(rng, 1e-11, 1e-4));
    } else if (kind < 0.52) {
      // Springs so small that their squared lengths multiply to below 1e-290: rescaled exactly.
      h.tangential = log_uniform(rng, 1e-160, 1e-150) * random_unit(rng);
      h.rolling = log_uniform(rng, 1e-160, 1e-150) * random_unit(rng);
    } else {
      h.tangential = log_uniform(rng, 1e-10, 1e-4) * random_unit(rng);
      h.rolling = log_uniform(rng, 1e-11, 1e-4) * random_unit(rng);
    }
    s.history.push_back(h);
    s.contacts.push_back(QueuedContact{q, static_cast<std::int32_t>(i),
                                       static_cast<std::int32_t>(j), &m.table.c(mi, mj)});
  }
  // Pair indices, slots and queue order shuffled: no output position equals another's.
  std::vector<std::int32_t> perm(count), slot_perm(count);
  for (int q = 0; q < count; ++q) perm[q] = slot_perm[q] = q;
  for (int q = count - 1; q > 0; --q) {
    std::swap(perm[q], perm[rng.below(q + 1)]);
    std::swap(slot_perm[q], slot_perm[rng.below(q + 1)]);
  }
  std::vector<ContactHistory> history(count);
  for (int q = 0; q < count; ++q) {
    history[perm[q]] = s.history[q];
    s.contacts[q].k = perm[q];
  }
  s.history = history;
  s.slot = slot_perm;
  return s;
}

/// Everything a run writes, prefilled with a sentinel so that a stray write shows.
struct Results {
  std::vector<ContactHistory> history;
  std::vector<Reaction> reaction;
  std::vector<Vec3> force_i, torque_i;
  std::vector<std::uint8_t> live;  // (pairs) all 1: every queued pair touched last step

  explicit Results(const Scene& s) : history(s.history) {
    const std::size_t n = s.contacts.size();
    const Vec3 sentinel = Vec3::Constant(-12345.0);
    reaction.assign(n, Reaction{sentinel, sentinel});
    force_i.assign(n, sentinel);
    torque_i.assign(n, sentinel);
    live.assign(n, 1);
  }
  PairOutputs outputs(const Scene& s) {
    PairOutputs o;
    o.history = history.data();
    o.slot = s.slot.data();
    o.reaction = reaction.data();
    o.live = live.data();
    o.force_i = force_i.data();
    o.torque_i = torque_i.data();
    return o;
  }
};

template <class T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

/// The reference, the scalar kernel, on queued contact q, carrying its springs in `r`.
void scalar_contact_reference(const Scene& s, std::size_t q, Results& r) {
  const QueuedContact& e = s.contacts[q];
  const ContactInput in = pair_input(s.p, *e.c, e.i, e.j);
  const ContactOutput out = hertz_mindlin(*e.c, in, kDt, r.history[e.k]);
  r.force_i[q] = out.force;
  r.torque_i[q] = out.torque_i;
  r.reaction[s.slot[e.k]] = Reaction{out.force, out.torque_j};
}

/// One step of the reference, one contact after the other, on the first `count` contacts.
void scalar_step(const Scene& s, std::size_t count, Results& r) {
  for (std::size_t q = 0; q < count; ++q) scalar_contact_reference(s, q, r);
}

/// The reference from fresh springs.
Results scalar_reference(const Scene& s, std::size_t count) {
  Results r(s);
  scalar_step(s, count, r);
  return r;
}

void expect_same(const Results& a, const Results& b, const std::string& what) {
  EXPECT_TRUE(same_bits(a.history, b.history)) << what << ": springs differ";
  EXPECT_TRUE(same_bits(a.reaction, b.reaction)) << what << ": reactions";
  EXPECT_TRUE(same_bits(a.force_i, b.force_i)) << what << ": forces on i";
  EXPECT_TRUE(same_bits(a.torque_i, b.torque_i)) << what << ": torques on i";
  EXPECT_TRUE(same_bits(a.live, b.live)) << what << ": live flags";
}

std::vector<PairIsa> available_isas() {
  std::vector<PairIsa> isas{PairIsa::kScalar, PairIsa::kSse2};
  if (pair_isa_available(PairIsa::kAvx)) isas.push_back(PairIsa::kAvx);
  if (pair_isa_available(PairIsa::kAvx512Vl)) isas.push_back(PairIsa::kAvx512Vl);
  return isas;
}

const char* isa_name(PairIsa isa) { return pair_isa_name(isa); }

/// Runs every ISA on all of s's contacts from fresh results and compares with `ref`.
void expect_every_isa_gives(const Scene& s, const Results& ref) {
  for (PairIsa isa : available_isas()) {
    Results r(s);
    compute_queued_contacts(isa, s.p, s.contacts.data(), s.contacts.size(), kDt, r.outputs(s));
    expect_same(ref, r, isa_name(isa));
  }
}

TEST(PairSimd, LanesGiveTheScalarKernelsBits) {
  const Model m = mixed_model();
  const Scene s = random_scene(m, 4003, 20261122);
  const Results ref = scalar_reference(s, s.contacts.size());

  // The sample covers every case the lanes select between (counted on the reference).
  int first_touch = 0, sliding = 0, rolling_cap = 0, pulling = 0, lanes = 0, scalar = 0;
  int series = 0, exact = 0, tiny = 0;  // rescales of the rotated springs (rotate_springs)
  for (std::size_t q = 0; q < s.contacts.size(); ++q) {
    const QueuedContact& e = s.contacts[q];
    const ContactConstants& c = *e.c;
    (lanes_eligible(c) ? lanes : scalar)++;
    if (s.history[e.k].tangential.squaredNorm() == 0.0) ++first_touch;
    const ContactInput in = pair_input(s.p, c, e.i, e.j);
    for (const Vec3& spring : {s.history[e.k].tangential, s.history[e.k].rolling}) {
      const double len2 = spring.squaredNorm(), sn = spring.dot(in.n);
      if (len2 == 0.0) continue;
      if (len2 < 1e-200) ++tiny;
      (sn * sn <= kRotateSeriesMax * len2 ? series : exact)++;
    }
    ContactHistory h = s.history[e.k];
    const ContactOutput out = hertz_mindlin(c, in, kDt, h);
    if (out.normal < 0.0) ++pulling;
    if (out.normal <= 0.0 || c.cohesive) continue;
    const double f_t = (out.force - out.normal * in.n).norm();
    if (std::abs(f_t - c.mu_s * out.normal) <= 1e-9 * f_t) ++sliding;
    if (c.rolling == RollingModel::kEpsd && !c.size_dependent_rolling &&
        std::abs(h.rolling.norm() - c.mu_r * out.normal * in.r_eff) <= 1e-9 * h.rolling.norm())
      ++rolling_cap;
  }
  std::printf(
      "contacts: %d first touch, %d sliding, %d at the rolling cap, %d pulling, %d in "
      "lanes, %d scalar; springs rescaled by the series %d, exactly %d, tiny %d\n",
      first_touch, sliding, rolling_cap, pulling, lanes, scalar, series, exact, tiny);
  EXPECT_GT(first_touch, 100);
  EXPECT_GT(sliding, 100);
  EXPECT_GT(rolling_cap, 100);
  EXPECT_GT(pulling, 100);
  EXPECT_GT(lanes, 1000);
  EXPECT_GT(scalar, 1000);
  EXPECT_GT(series, 1000);
  EXPECT_GT(exact, 1000);
  EXPECT_GT(tiny, 50);

  expect_every_isa_gives(s, ref);
}

TEST(PairSimd, ShortQueuesFillPartOfTheLanesAndWriteNothingElse) {
  // 1 to 9 contacts: partly filled lane groups; the outputs of the contacts not queued keep the
  // sentinel (a padding lane stores nothing).
  const Model m = mixed_model();
  const Scene s = random_scene(m, 9, 7);
  for (std::size_t count = 1; count <= s.contacts.size(); ++count) {
    const Results ref = scalar_reference(s, count);
    for (PairIsa isa : available_isas()) {
      Results r(s);
      compute_queued_contacts(isa, s.p, s.contacts.data(), count, kDt, r.outputs(s));
      expect_same(ref, r, std::string(isa_name(isa)) + " count " + std::to_string(count));
    }
  }
}

TEST(PairSimd, AllEligibleHeapLikeContactsOverManySteps) {
  // One material pair (the standard heap's, EPSD without dashpot), the springs carried from
  // step to step as in a run (the bodies held in place: the springs grow from sticking to
  // sliding): the lanes and the scalar kernel stay bit-identical.
  Model m = mixed_model();
  Scene s = random_scene(m, 403, 99);
  for (QueuedContact& e : s.contacts) e.c = &m.table.c(0, 0);
  const std::vector<PairIsa> isas = available_isas();
  std::vector<Results> runs(isas.size(), Results(s));
  Results ref(s);
  for (int step = 0; step < 50; ++step) {
    scalar_step(s, s.contacts.size(), ref);
    for (std::size_t r = 0; r < isas.size(); ++r) {
      compute_queued_contacts(isas[r], s.p, s.contacts.data(), s.contacts.size(), kDt,
                              runs[r].outputs(s));
      expect_same(ref, runs[r], std::string(isa_name(isas[r])) + " step " + std::to_string(step));
    }
  }
}

TEST(PairSimd, WallContactsGiveTheScalarKernelsBits) {
  // Random contacts of spheres with walls (several walls per sphere, every material pair of the
  // mixed model, moving walls, springs from zero to sliding and at the rolling cap): every ISA
  // must give the forces, torques and wall springs of wall_input + hertz_mindlin, bit for bit.
  const Model m = mixed_model();
  Rng rng(77);
  Particles p;
  WallContacts wc;
  for (int b = 0; b < 1500; ++b) {
    const int mi = static_cast<int>(rng.below(4));
    const double r = rng.uniform(0.5e-3, 1e-3);
    const std::size_t i = p.add(Vec3(rng.uniform(0, 0.01), rng.uniform(0, 0.01), r), r,
                                m.materials[mi].density, mi, b);
    p.v[i] = Vec3(rng.normal(0, 0.05), rng.normal(0, 0.05), rng.normal(0, 0.05));
    p.w[i] = Vec3(rng.normal(0, 50), rng.normal(0, 50), rng.normal(0, 50));
    for (int w = 0; w < kMaxWalls; ++w) {
      if (rng.uniform() > 0.3) continue;
      ContactHistory& h = p.wall_history[i][w];
      if (rng.uniform() > 0.2) {  // else zero springs: first touch
        h.tangential = log_uniform(rng, 1e-10, 1e-4) * random_unit(rng);
        h.rolling = log_uniform(rng, 1e-11, 1e-4) * random_unit(rng);
      }
      const Vec3 velocity =
          rng.uniform() < 0.5 ? Vec3::Zero()
                              : Vec3(rng.normal(0, 0.01), rng.normal(0, 0.01), rng.normal(0, 0.01));
      wc.add(static_cast<std::int32_t>(i), w, random_unit(rng), r * log_uniform(rng, 1e-7, 2e-2),
             velocity, &m.table.c(mi, static_cast<int>(rng.below(4))));
    }
  }
  ASSERT_GT(wc.size(), 2000u);
  Particles ref = p;
  WallContacts ref_wc = wc;
  ref_wc.force.resize(wc.size());
  ref_wc.torque.resize(wc.size());
  int lanes = 0;
  for (std::size_t e = 0; e < wc.size(); ++e) {
    const ContactOutput out =
        hertz_mindlin(*wc.c[e], wall_input(ref, wc, e), kDt,
                      ref.wall_history[static_cast<std::size_t>(wc.particle[e])][wc.wall[e]]);
    ref_wc.force[e] = out.force;
    ref_wc.torque[e] = out.torque_i;
    lanes += lanes_eligible(*wc.c[e]) ? 1 : 0;
  }
  EXPECT_GT(lanes, 500);
  EXPECT_LT(lanes, static_cast<int>(wc.size()) - 500);
  for (PairIsa isa : available_isas()) {
    Particles q = p;
    WallContacts r = wc;
    compute_wall_contacts(isa, q, r, kDt);
    EXPECT_TRUE(same_bits(r.force, ref_wc.force)) << isa_name(isa) << ": forces";
    EXPECT_TRUE(same_bits(r.torque, ref_wc.torque)) << isa_name(isa) << ": torques";
    EXPECT_EQ(std::memcmp(q.wall_history.data(), ref.wall_history.data(),
                          p.size() * sizeof(WallHistory)),
              0)
        << isa_name(isa) << ": wall springs";
  }
}

TEST(PairSimd, QueuedPairsThatNoLongerTouchAreCleared) {
  // Live pairs go to the kernel untested: the ones that separated since the last step (here a
  // third, among them pairs at contact distance to within a rounding, decided as the distance
  // definition does) must get their springs and reactions cleared, zero force and torque on i,
  // and live flag 0; every other output must be the scalar kernel's, bit for bit.
  const Model m = mixed_model();
  Scene s = random_scene(m, 1001, 5);
  Rng rng(6);
  for (std::size_t q = 0; q < s.contacts.size(); ++q) {
    const QueuedContact& e = s.contacts[q];
    if (rng.uniform() > 1.0 / 3.0) continue;
    const double cut = s.p.radius[e.i] + s.p.radius[e.j];
    if (q % 7 == 0) {  // at contact distance up to one rounding
      s.p.radius[e.i] = 0.75e-3;
      s.p.radius[e.j] = 0.5e-3;
      s.p.x[e.j] = s.p.x[e.i] - Vec3(1.25e-3, 0, 0);
    } else {
      s.p.x[e.j] = s.p.x[e.i] + cut * rng.uniform(1.0001, 1.1) * random_unit(rng);
    }
  }
  int separated = 0;
  Results ref(s);
  for (std::size_t q = 0; q < s.contacts.size(); ++q) {
    const QueuedContact& e = s.contacts[q];
    const double cut = s.p.radius[e.i] + s.p.radius[e.j];
    if ((s.p.x[e.i] - s.p.x[e.j]).squaredNorm() >= cut * cut) {
      ++separated;
      ref.history[e.k] = ContactHistory{};
      ref.reaction[s.slot[e.k]] = Reaction{};
      ref.force_i[q].setZero();
      ref.torque_i[q].setZero();
      ref.live[e.k] = 0;
      continue;
    }
    scalar_contact_reference(s, q, ref);
  }
  EXPECT_GT(separated, 250);
  EXPECT_LT(separated, 450);
  expect_every_isa_gives(s, ref);
}

TEST(PairSimd, DistanceTestQueuesTheTouchingPairsInListOrder) {
  // A "list" of pairs at random near contact distance (about half of them touching, some at
  // contact distance to within a rounding), none live; a random subset of them tested. The
  // lanes must queue exactly the tested pairs with |x_i - x_j|^2 < (r_i + r_j)^2, in list order,
  // and set their live flags, leaving every other flag at 0.
  Rng rng(31);
  Particles p;
  const int listed = 1001;
  const int owners = listed / 3;
  for (int b = 0; b < owners + listed; ++b)
    p.add(Vec3(rng.uniform(0, 0.1), rng.uniform(0, 0.1), rng.uniform(0, 0.1)),
          rng.uniform(0.5e-3, 1e-3), 2760.0, 0, b);
  const std::int32_t k0 = 17;  // the block's first pair
  std::vector<std::int32_t> owner(listed), second(k0 + listed), tested;
  for (int m = 0; m < listed; ++m) {
    owner[m] = static_cast<std::int32_t>(m * owners / listed);  // increasing, as in a CSR list
    second[k0 + m] = owners + m;
    const std::size_t i = owner[m], j = second[k0 + m];
    if (m % 50 == 7) {  // at contact distance up to one rounding: decided as the definition does
      p.radius[j] = 0.5e-3;
      p.radius[i] = 0.75e-3;
      p.x[j] = p.x[i] - Vec3(1.25e-3, 0, 0);
    } else {  // a partner near contact distance
      p.x[j] = p.x[i] + (p.radius[i] + p.radius[j]) * rng.uniform(0.9, 1.1) * random_unit(rng);
    }
    if (m % 50 == 7 || rng.uniform() < 0.7) tested.push_back(m);
  }
  if (tested.size() % 2 == 0) tested.pop_back();  // an odd count: a scalar tail
  // The expected outcome, from the definition.
  std::vector<std::int32_t> expected;
  for (std::int32_t m : tested) {
    const std::size_t i = owner[m], j = second[k0 + m];
    const double cut = p.radius[i] + p.radius[j];
    if ((p.x[i] - p.x[j]).squaredNorm() < cut * cut) expected.push_back(k0 + m);
  }
  ASSERT_GT(expected.size(), 150u);
  ASSERT_LT(expected.size(), 600u);
  std::vector<std::uint8_t> live(k0 + listed, 0);
  std::vector<QueuedContact> queue(tested.size());
  const std::size_t queued = queue_touching_pairs(p, owner.data(), second.data(), k0,
                                                  tested.data(), tested.size(), live.data(),
                                                  queue.data());
  ASSERT_EQ(queued, expected.size());
  for (std::size_t q = 0; q < queued; ++q) {
    EXPECT_EQ(queue[q].k, expected[q]);
    EXPECT_EQ(queue[q].i, owner[expected[q] - k0]);
    EXPECT_EQ(queue[q].j, second[expected[q]]);
  }
  std::size_t e = 0;
  for (int k = 0; k < k0 + listed; ++k) {
    const bool touch = e < expected.size() && expected[e] == k;
    e += touch ? 1 : 0;
    EXPECT_EQ(live[k], touch ? 1 : 0) << "pair " << k;
  }
}

}  // namespace
}  // namespace reposetwin::sim
