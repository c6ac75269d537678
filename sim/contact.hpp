// Contact laws as small stateless kernels (after LAMMPS GRANULAR's gran_sub_mod_* classes).
//
// Design note. Each kernel takes plain parameters and the geometry of one contact and returns a
// force or torque; contact history (the tangential spring, the rolling spring) is passed in and
// updated explicitly, so a kernel can be tested one contact at a time against closed forms.
// Conventions for one contact between body i and body j (j may be a wall):
//   n        unit normal pointing from j to i,
//   delta    overlap r_i + r_j - |x_i - x_j| > 0 (for a wall, r_i - distance),
//   a_i, a_j lever arms, centre to contact point (r - delta/2 for a pair, r - delta on a wall),
//   v_rel    velocity of i relative to j at the contact point,
//   forces and torques returned act on i; body j receives -force and its own torque.
// The equations cited are those of EDEM's Hertz-Mindlin (no slip) model, as also used by
// LIGGGHTS (normal_model hertz, tangential_model history) and LAMMPS (hertz/material, mindlin).
// Two optional effects, off by default, each switched on per material pair by one parameter:
// simplified-JKR cohesion (sjkr_cohesion) and a rolling coefficient that scales with the contact
// diameter (rolling_size_factor). Both are gated by flags precomputed in ContactConstants, so
// with the defaults the kernel does exactly the arithmetic it did without them.
// Cost: a touching contact takes two square roots for all its stiffnesses and damping
// coefficients (contact_stiffness: sqrt(R* delta), shared by the normal, tangential and rolling
// springs, and sqrt(sqrt(R* delta) m*), from which both damping coefficients follow with
// constant factors), and one square root and one division per spring to keep its length when it
// is rotated. Divisions are few because the divider, not the other arithmetic, bounds the
// kernel's throughput when several contacts are computed at once (sim/pair_simd.hpp): the pair
// geometry takes one for the normal, R*, m* and the overlap ratio (pair_input), a slipping
// contact one for its force and spring (mindlin_tangential), a rolling spring at its cap one.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>  // cross products
#include <cmath>
#include <cstddef>
#include <numbers>
#include <string_view>

namespace reposetwin::sim {

using Vec3 = Eigen::Vector3d;

/// Rolling resistance laws (Ai, Chen, Rotter, Ooi 2011, Powder Technol. 206:269).
enum class RollingModel {
  kNone,  // no rolling resistance
  kCdt,   // type A: constant directional torque (EDEM "standard", LIGGGHTS cdt)
  kEpsd,  // type C: elastic-plastic spring-dashpot (EDEM type C, LIGGGHTS epsd2)
};

/// One row per rolling model: the scene file's keyword and, because mu_r values do not port
/// between codes otherwise, exactly which radius and which angular velocity the law uses.
struct RollingModelInfo {
  std::string_view keyword;
  RollingModel model;
  std::string_view torque;
  std::string_view radius;
  std::string_view angular_velocity;
};

inline constexpr RollingModelInfo kRollingModels[] = {
    {"none", RollingModel::kNone, "none", "-", "-"},
    {"cdt", RollingModel::kCdt,
     "M_i = -mu_r |F_n| a_i w_i/|w_i| on each body separately (EDEM Standard, type A); "
     "mu_r -> mu_r (d_c/d_ref)^alpha if rolling_size_exponent alpha != 0 (d_c = 4 R*, 2 R_i on "
     "a wall)",
     "a_i: the body's own centre-to-contact distance (about R_i, as EDEM)",
     "w_i: the body's own angular velocity (as EDEM; LIGGGHTS cdt uses w_i - w_j and R*)"},
    {"epsd", RollingModel::kEpsd,
     "incremental spring k_r = k_t R_r^2 on the relative rolling rotation, capped at "
     "mu_r |F_n| R_r; viscous damping 2 eta_r sqrt(I_r k_r) below the cap (type C, LIGGGHTS "
     "epsd2); mu_r -> mu_r (d_c/d_ref)^alpha if rolling_size_exponent alpha != 0 (d_c = 4 R*, "
     "2 R_i on a wall)",
     "R_r = R* = R_i R_j / (R_i + R_j) (R_i on a wall), as LIGGGHTS and LAMMPS",
     "w_r = (w_i - w_j) minus its twist component along n"},
};

/// Looks a rolling model up by keyword; returns nullptr if unknown.
inline const RollingModelInfo* find_rolling_model(std::string_view keyword) {
  for (const auto& row : kRollingModels)
    if (row.keyword == keyword) return &row;
  return nullptr;
}

inline std::string_view rolling_model_keyword(RollingModel m) {
  for (const auto& row : kRollingModels)
    if (row.model == m) return row.keyword;
  return "?";
}

/// Constants of a material pair, derived once per run (Model::finalize).
struct ContactConstants {
  double e_star = 0.0;   // 1/E* = (1-nu_i^2)/E_i + (1-nu_j^2)/E_j [Pa]
  double g_star = 0.0;   // 1/G* = 2(2-nu_i)(1+nu_i)/E_i + 2(2-nu_j)(1+nu_j)/E_j [Pa]
  double beta = 0.0;     // ln e / sqrt(ln^2 e + pi^2) [-] (0 for e = 1)
  double mu_s = 0.0;     // Coulomb friction [-]
  double mu_r = 0.0;     // rolling resistance coefficient [-]
  double eta_r = 0.0;    // EPSD rolling damping ratio [-]
  RollingModel rolling = RollingModel::kNone;
  double cohesion_energy_density = 0.0;  // k_c of the simplified-JKR cohesion [J/m^3 = Pa]
  bool cohesive = false;                 // k_c > 0: the kernel adds the cohesive force
  double rolling_size_exponent = 0.0;    // alpha in mu_r (d_c / d_ref)^alpha [-]
  double rolling_reference_diameter = 0.0;  // d_ref [m]
  bool size_dependent_rolling = false;   // alpha != 0: the kernel scales mu_r with d_c
  // Derived from the above by derive_contact_constants() (Model::finalize calls it), so that
  // a contact takes two square roots, sqrt(R* delta) and sqrt(sqrt(R* delta) m*), for all its
  // stiffnesses and damping coefficients:
  double hertz_factor = 0.0;    // 4/3 E*: F_el = hertz_factor sqrt(R* delta) delta [Pa]
  double normal_damping = 0.0;  // -2 sqrt(5/6) beta sqrt(2 E*) [Pa^0.5] (>= 0)
  double tangential_damping = 0.0;  // -2 sqrt(5/6) beta sqrt(8 G*) [Pa^0.5] (>= 0)
};

/// Damping factor beta from the coefficient of restitution e (EDEM, LIGGGHTS, LAMMPS):
/// beta = ln e / sqrt(ln^2 e + pi^2). With the Hertz spring and the damping below, the
/// rebound/approach speed ratio of a head-on collision equals e exactly.
inline double damping_beta(double restitution) {
  if (restitution >= 1.0) return 0.0;
  const double l = std::log(restitution);
  return l / std::sqrt(l * l + std::numbers::pi * std::numbers::pi);
}

/// Fills the derived fields of `c` (hertz_factor, normal_damping, tangential_damping) from
/// e_star, g_star and beta. The damping coefficients of EDEM's Hertz-Mindlin,
/// -2 sqrt(5/6) beta sqrt(S m*) with S_n = 2 E* sqrt(R* delta) and S_t = 8 G* sqrt(R* delta),
/// are these constants times sqrt(sqrt(R* delta) m*): one square root serves both.
inline void derive_contact_constants(ContactConstants& c) {
  constexpr double kTwoSqrtFiveSixths = 2.0 * 0.91287092917527685576;  // 2 sqrt(5/6)
  c.hertz_factor = (4.0 / 3.0) * c.e_star;
  c.normal_damping = -kTwoSqrtFiveSixths * c.beta * std::sqrt(2.0 * c.e_star);
  c.tangential_damping = -kTwoSqrtFiveSixths * c.beta * std::sqrt(8.0 * c.g_star);
}

/// Everything a kernel needs about one contact.
struct ContactInput {
  Vec3 n;            // unit normal, from j to i
  double delta;      // overlap [m], > 0
  double r_eff;      // R* [m]
  double m_eff;      // m* [kg]
  double i_roll;     // I_r, effective rolling inertia [kg m^2] (EPSD damping)
  double a_i, a_j;   // lever arms [m] (a_j = 0 for a wall)
  Vec3 v_rel;        // velocity of i relative to j at the contact point [m/s]
  Vec3 w_i, w_j;     // angular velocities [rad/s] (w_j = 0 for a wall)
  double contact_diameter = 0.0;  // d_c: 4 R* for a pair, 2 R_i on a wall [m]; read only by
                                  // size-dependent rolling (ContactConstants::size_dependent_rolling)
};

/// History carried by a contact from step to step.
struct ContactHistory {
  Vec3 tangential = Vec3::Zero();  // tangential spring displacement of i relative to j [m]
  Vec3 rolling = Vec3::Zero();     // EPSD spring torque acting on i [N m]
};

/// What a pair leaves for its second member, in that member's incoming slot (one record, so
/// that storing it touches one or two cache lines, not up to four).
struct Reaction {
  Vec3 force = Vec3::Zero();   // the pair's force on its first member (minus it on the second) [N]
  Vec3 torque = Vec3::Zero();  // the pair's torque on its second member [N m]
};

struct ContactOutput {
  Vec3 force;     // on i [N]
  Vec3 torque_i;  // on i [N m]
  Vec3 torque_j;  // on j [N m]
  double normal;  // signed normal force magnitude (elastic + damping, without cohesion) [N]
};

/// Stiffnesses and damping coefficients of one contact, from two square roots shared by the
/// normal, tangential and rolling laws (EDEM Hertz-Mindlin):
///   S_n = 2 E* sqrt(R* delta),  S_t = 8 G* sqrt(R* delta),
///   gamma_n = -2 sqrt(5/6) beta sqrt(S_n m*),  gamma_t = -2 sqrt(5/6) beta sqrt(S_t m*).
struct ContactStiffness {
  double sqrt_rd = 0.0;  // sqrt(R* delta) [m]
  double s_t = 0.0;      // tangential stiffness S_t [N/m]
  double gamma_n = 0.0;  // normal damping coefficient (>= 0) [kg/s]
  double gamma_t = 0.0;  // tangential damping coefficient (>= 0) [kg/s]
};

/// Computes the stiffnesses and damping coefficients of a contact of overlap delta [m].
inline ContactStiffness contact_stiffness(const ContactConstants& c, double delta, double r_eff,
                                          double m_eff) {
  ContactStiffness k;
  k.sqrt_rd = std::sqrt(r_eff * delta);
  const double root = std::sqrt(k.sqrt_rd * m_eff);  // sqrt(S m*) / sqrt(2 E*) or / sqrt(8 G*)
  k.s_t = 8.0 * c.g_star * k.sqrt_rd;
  k.gamma_n = c.normal_damping * root;
  k.gamma_t = c.tangential_damping * root;
  return k;
}

/// Hertz normal force with restitution damping (EDEM Hertz-Mindlin):
///   F_n = 4/3 E* sqrt(R*) delta^1.5 - gamma_n v_n,   v_n = v_rel . n (negative while
/// approaching). Returns the signed magnitude along n (the damping may make it slightly
/// attractive at the end of the contact; this is what makes the restitution exact).
inline double hertz_normal(const ContactConstants& c, const ContactStiffness& k, double delta,
                           double v_n) {
  return c.hertz_factor * k.sqrt_rd * delta - k.gamma_n * v_n;  // v_n < 0 on approach: repels
}

/// Largest x = (s.n)^2 / |s|^2 for which rotate_springs takes the series of the rescale factor.
inline constexpr double kRotateSeriesMax = 1e-6;

/// One spring of rotate_springs: s <- (s - sn n) f, with f = |s| / |s - sn n| taken from its
/// series in x while x <= kRotateSeriesMax and `series_ok`, exactly otherwise.
inline void rotate_spring(const Vec3& n, double sn, double len2, double x, bool series_ok,
                          Vec3& spring) {
  if (len2 > 0.0) {
    spring -= sn * n;
    double f;
    if (x <= kRotateSeriesMax && series_ok) {
      f = (0.375 * x + 0.5) * x + 1.0;
    } else {
      const double proj2 = spring.squaredNorm();
      f = proj2 > 0.0 ? std::sqrt(len2 / proj2) : 0.0;
    }
    spring *= f;
  }
}

/// Rotates both incremental springs of a contact (tangential s and rolling M) into the tangent
/// plane of the current normal n, keeping their lengths (as LAMMPS' granular "rotate and
/// rescale"): s <- (s - (s.n) n) f, f = |s| / |s - (s.n) n| = 1 / sqrt(1 - x), where
/// x = (s.n)^2 / |s|^2 is the squared sine of the angle the normal turned through since the last
/// step. For x <= kRotateSeriesMax (a normal turning less than 1e-3 rad in a step: nearly every
/// contact) f = 1 + x/2 + 3x^2/8, whose truncation (5x^3/16 < 4e-19) is below a rounding, so both
/// rescales cost one division and no square root; f is exact otherwise, and when the springs'
/// squared lengths multiply to less than 1e-290 (the shared division would lose digits).
inline void rotate_springs(const Vec3& n, ContactHistory& h) {
  const double ls = h.tangential.squaredNorm(), lr = h.rolling.squaredNorm();
  const double sn = h.tangential.dot(n), rn = h.rolling.dot(n);
  const double gs = ls > 0.0 ? ls : 1.0, gr = lr > 0.0 ? lr : 1.0;
  const double both = gs * gr;
  const double inv = 1.0 / both;
  const bool series_ok = both >= 1e-290;
  rotate_spring(n, sn, ls, (sn * sn) * (gr * inv), series_ok, h.tangential);
  rotate_spring(n, rn, lr, (rn * rn) * (gs * inv), series_ok, h.rolling);
}

/// Mindlin no-slip tangential force on an incremental spring with Coulomb cap (EDEM):
///   F_t = -S_t s - gamma_t v_t with |F_t| <= mu_s F_n. The spring s has been rotated into the
/// current tangent plane keeping its length (rotate_springs); when the cap is reached it is
/// truncated to -F_t / S_t (no damping in slip).
inline Vec3 mindlin_tangential(const ContactConstants& c, const ContactStiffness& k,
                               const Vec3& v_t, double f_n, double dt, Vec3& spring) {
  spring += v_t * dt;
  Vec3 f = -k.s_t * spring - k.gamma_t * v_t;
  const double cap = c.mu_s * std::max(f_n, 0.0);
  // Compared squared: the square root is taken only when the contact slips.
  if (f.squaredNorm() > cap * cap) {
    // One division for both cap / |F_t| and 1 / S_t: inv = 1 / (|F_t| S_t). (|F_t| = 0 or
    // S_t = 0 only without overlap or motion, when F_t = 0: then F_t and the spring are zero.)
    const double fmag = f.norm();
    const double denom = fmag * k.s_t;
    const double inv = denom > 0.0 ? 1.0 / denom : 0.0;
    f *= (cap * k.s_t) * inv;
    spring = f * -(fmag * inv);
  }
  return f;
}

/// Type A, constant directional torque on one body: M = -mu_r |F_n| a w/|w|.
inline Vec3 rolling_cdt(double mu_r, double f_n, double lever, const Vec3& w) {
  const double wn = w.norm();
  if (wn <= 0.0) return Vec3::Zero();
  return (-mu_r * std::max(f_n, 0.0) * lever / wn) * w;
}

/// Type C, elastic-plastic spring-dashpot (Ai et al. 2011, eqs. 13-19; LIGGGHTS epsd2):
///   k_r = S_t R_r^2, M_k <- M_k - k_r w_r dt, |M_k| <= mu_r F_n R_r,
///   M_d = -2 eta_r sqrt(I_r k_r) w_r while |M_k| is below the cap (zero at the cap).
/// Returns the torque on i; j receives its negative. `spring` is the torque M_k on i, rotated
/// into the current tangent plane (rotate_springs).
/// `mu_r` is the rolling coefficient in force (c.mu_r, or c.mu_r scaled by size).
inline Vec3 rolling_epsd(const ContactConstants& c, const ContactStiffness& k, double mu_r,
                         const Vec3& n, double r_eff, double i_roll, const Vec3& w_i,
                         const Vec3& w_j, double f_n, double dt, Vec3& spring) {
  Vec3 w_r = w_i - w_j;
  w_r -= w_r.dot(n) * n;  // rolling only: remove the twist about n
  const double k_r = k.s_t * r_eff * r_eff;
  spring -= k_r * dt * w_r;
  const double cap = mu_r * std::max(f_n, 0.0) * r_eff;
  if (spring.squaredNorm() >= cap * cap) {  // squared: the root only at the cap
    const double m = spring.norm();
    spring *= m > 0.0 ? cap / m : 0.0;
    return spring;
  }
  if (c.eta_r == 0.0) return spring;  // no dashpot (LIGGGHTS epsd2)
  return spring - (2.0 * c.eta_r * std::sqrt(i_roll * k_r)) * w_r;
}

/// Simplified-JKR cohesion (the physical law of LIGGGHTS "cohesion sjkr"; Johnson, Kendall,
/// Roberts 1971 reduced to a force proportional to the contact area):
///   F_c = k_c A,   A = pi a^2,   a^2 = R* delta (the Hertz contact radius),
/// so F_c = pi k_c R* delta, attractive (it acts on i along -n), only while delta > 0; it vanishes
/// continuously at first touch and at separation. k_c is a cohesion energy density [J/m^3].
/// Note on porting k_c: LIGGGHTS sjkr takes A as the area of the geometric sphere-sphere
/// intersection, pi/4 (d-R_i-R_j)(d+R_i-R_j)(d-R_i+R_j)(d+R_i+R_j)/d^2 ~ 2 pi R* delta for
/// small delta (twice the Hertz area), so a LIGGGHTS value k corresponds to k_c = 2 k here.
/// Returns the magnitude F_c >= 0 [N].
inline double sjkr_cohesion(double k_c, double r_eff, double delta) {
  return std::numbers::pi * k_c * r_eff * delta;
}

/// Size factor of the rolling coefficient, (d_c / d_ref)^alpha [-]: with alpha < 0 small
/// particles resist rolling more (the fines), with alpha > 0 large ones do. d_c = 4 R* for a
/// pair (the diameter for equal spheres), 2 R_i on a wall; d_ref > 0 (Model::finalize checks).
inline double rolling_size_factor(const ContactConstants& c, double contact_diameter) {
  return std::pow(contact_diameter / c.rolling_reference_diameter, c.rolling_size_exponent);
}

/// The full Hertz-Mindlin contact with rolling resistance: normal, tangential, rolling, and the
/// optional cohesion and size-dependent rolling coefficient.
///
/// Which normal force caps friction under cohesion: the Coulomb limit mu_s F_n of
/// mindlin_tangential and the rolling caps use the repulsive Hertz force F_n (elastic + damping,
/// hertz_normal), not the net force F_n - F_c; this is LIGGGHTS' "tangential_reduce on" choice
/// for its cohesion models. Reasons: (1) in JKR-type adhesion the friction a contact can carry
/// grows with its real area, i.e. with the compressive (Hertz) load the adhesion adds, whereas
/// the net force would let cohesion remove friction: a grain held to a wall by cohesion alone
/// (net normal force 0) would slide freely, and one pulled on would get a negative cap; (2) the
/// cap and the rolling torque then stay continuous and non-negative through every contact, as
/// without cohesion; (3) with k_c = 0 the cap is unchanged by construction. Only the force on
/// the bodies carries -F_c n.
[[gnu::always_inline]] inline ContactOutput hertz_mindlin(const ContactConstants& c,
                                                         const ContactInput& in, double dt,
                                                         ContactHistory& h) {
  ContactOutput out;
  const ContactStiffness k = contact_stiffness(c, in.delta, in.r_eff, in.m_eff);
  const double v_n = in.v_rel.dot(in.n);
  const double f_n = hertz_normal(c, k, in.delta, v_n);
  const Vec3 v_t = in.v_rel - v_n * in.n;
  rotate_springs(in.n, h);
  const Vec3 f_t = mindlin_tangential(c, k, v_t, f_n, dt, h.tangential);
  out.normal = f_n;
  if (c.cohesive) {
    out.force = (f_n - sjkr_cohesion(c.cohesion_energy_density, in.r_eff, in.delta)) * in.n + f_t;
  } else {
    out.force = f_n * in.n + f_t;
  }
  // Lever from i's centre to the contact point is -a_i n; from j's centre it is +a_j n.
  const Vec3 nxf = in.n.cross(f_t);
  out.torque_i = -in.a_i * nxf;
  out.torque_j = -in.a_j * nxf;
  const double mu_r =
      c.size_dependent_rolling ? c.mu_r * rolling_size_factor(c, in.contact_diameter) : c.mu_r;
  switch (c.rolling) {
    case RollingModel::kNone:
      break;
    case RollingModel::kCdt:
      out.torque_i += rolling_cdt(mu_r, f_n, in.a_i, in.w_i);
      out.torque_j += rolling_cdt(mu_r, f_n, in.a_j, in.w_j);
      break;
    case RollingModel::kEpsd: {
      const Vec3 m =
          rolling_epsd(c, k, mu_r, in.n, in.r_eff, in.i_roll, in.w_i, in.w_j, f_n, dt, h.rolling);
      out.torque_i += m;
      out.torque_j -= m;
      break;
    }
  }
  return out;
}

}  // namespace reposetwin::sim
