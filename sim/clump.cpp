#include "sim/clump.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

namespace reposetwin::sim {
namespace {

[[noreturn]] void bad_shape(const std::string& name, const std::string& what) {
  throw std::invalid_argument("clump template '" + name + "': " + what);
}

/// The integrals of 1, x and x^2 over [a, b].
struct Chord {
  double a, b;
};

}  // namespace

MassProperties clump_mass_properties(const std::vector<Vec3>& centres,
                                     const std::vector<double>& radii,
                                     const MassPropertySettings& settings) {
  const std::size_t n = radii.size();
  if (n == 0 || centres.size() != n)
    throw std::invalid_argument("clump_mass_properties: need as many centres as radii, >= 1");
  for (std::size_t i = 0; i < n; ++i) {
    if (!(radii[i] > 0.0) || !std::isfinite(radii[i]))
      throw std::invalid_argument("clump_mass_properties: a radius is not positive");
    if (!centres[i].allFinite())
      throw std::invalid_argument("clump_mass_properties: a centre is not finite");
  }
  if (!(settings.cells >= 2))
    throw std::invalid_argument("clump_mass_properties: cells must be at least 2");
  // Relative to the mean centre, so that the moments of the chords lose no digits.
  Vec3 origin = Vec3::Zero();
  for (const Vec3& c : centres) origin += c;
  origin /= static_cast<double>(n);
  std::vector<Vec3> c(n);
  for (std::size_t i = 0; i < n; ++i) c[i] = centres[i] - origin;

  // The spheres' own integrals (closed form): V, V c, V (c c^T + r^2/5 1).
  double vol = 0.0;
  Vec3 first = Vec3::Zero();
  Mat3 second = Mat3::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    const double r = radii[i];
    const double v = 4.0 / 3.0 * std::numbers::pi * r * r * r;
    vol += v;
    first += v * c[i];
    second += v * (c[i] * c[i].transpose() + (r * r / 5.0) * Mat3::Identity());
  }

  // The grid across the pairwise overlaps: the union of the (y, z) boxes both spheres cover.
  double ylo = 1e300, yhi = -1e300, zlo = 1e300, zhi = -1e300;
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = i + 1; j < n; ++j) {
      if ((c[i] - c[j]).norm() >= radii[i] + radii[j]) continue;
      ylo = std::min(ylo, std::max(c[i].y() - radii[i], c[j].y() - radii[j]));
      yhi = std::max(yhi, std::min(c[i].y() + radii[i], c[j].y() + radii[j]));
      zlo = std::min(zlo, std::max(c[i].z() - radii[i], c[j].z() - radii[j]));
      zhi = std::max(zhi, std::min(c[i].z() + radii[i], c[j].z() + radii[j]));
    }
  }
  if (yhi > ylo && zhi > zlo) {
    const int cells = settings.cells;
    const double hy = (yhi - ylo) / cells, hz = (zhi - zlo) / cells;
    // Excess integrals of 1, x, y, z and the products, summed row by row.
    double e0 = 0.0;
    Vec3 e1 = Vec3::Zero();
    Mat3 e2 = Mat3::Zero();
    std::vector<Chord> chords;
    chords.reserve(n);
    for (int iz = 0; iz < cells; ++iz) {
      const double z = zlo + (iz + 0.5) * hz;
      double r0 = 0, r1x = 0, r1y = 0, r1z = 0, rxx = 0, rxy = 0, rxz = 0, ryy = 0, ryz = 0,
             rzz = 0;
      for (int iy = 0; iy < cells; ++iy) {
        const double y = ylo + (iy + 0.5) * hy;
        chords.clear();
        for (std::size_t i = 0; i < n; ++i) {
          const double dy = y - c[i].y(), dz = z - c[i].z();
          const double rho2 = radii[i] * radii[i] - dy * dy - dz * dz;
          if (rho2 <= 0.0) continue;
          const double rho = std::sqrt(rho2);
          chords.push_back({c[i].x() - rho, c[i].x() + rho});
        }
        if (chords.size() < 2) continue;
        std::sort(chords.begin(), chords.end(),
                  [](const Chord& p, const Chord& q) { return p.a < q.a; });
        // Sum over the chords minus the union of the chords.
        double m0 = 0, m1 = 0, m2 = 0;
        auto add = [&](double a, double b, double sign) {
          m0 += sign * (b - a);
          m1 += sign * 0.5 * (b * b - a * a);
          m2 += sign * (b * b * b - a * a * a) / 3.0;
        };
        double ua = chords[0].a, ub = chords[0].b;
        for (std::size_t k = 0; k < chords.size(); ++k) {
          add(chords[k].a, chords[k].b, 1.0);
          if (k == 0) continue;
          if (chords[k].a <= ub) {
            ub = std::max(ub, chords[k].b);
          } else {
            add(ua, ub, -1.0);
            ua = chords[k].a;
            ub = chords[k].b;
          }
        }
        add(ua, ub, -1.0);
        r0 += m0;
        r1x += m1;
        r1y += y * m0;
        r1z += z * m0;
        rxx += m2;
        rxy += y * m1;
        rxz += z * m1;
        ryy += y * y * m0;
        ryz += y * z * m0;
        rzz += z * z * m0;
      }
      e0 += r0;
      e1 += Vec3(r1x, r1y, r1z);
      Mat3 row;
      row << rxx, rxy, rxz, rxy, ryy, ryz, rxz, ryz, rzz;
      e2 += row;
    }
    const double w = hy * hz;
    vol -= w * e0;
    first -= w * e1;
    second -= w * e2;
  }

  MassProperties mp;
  mp.volume = vol;
  const Vec3 centre = first / vol;
  const Mat3 central = second - vol * centre * centre.transpose();
  mp.centre = centre + origin;
  mp.inertia = central.trace() * Mat3::Identity() - central;
  return mp;
}

ClumpTemplate make_clump_template(const ClumpShape& shape, const MassPropertySettings& settings) {
  const std::size_t n = shape.radii.size();
  if (n == 0) bad_shape(shape.name, "has no components");
  if (shape.offsets.size() != n) {
    std::ostringstream os;
    os << "has " << shape.offsets.size() << " offsets and " << n << " radii";
    bad_shape(shape.name, os.str());
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!(shape.radii[i] > 0.0) || !std::isfinite(shape.radii[i])) {
      std::ostringstream os;
      os << "component " << i << " radius = " << shape.radii[i] << " m: must be positive";
      bad_shape(shape.name, os.str());
    }
    if (!shape.offsets[i].allFinite()) {
      std::ostringstream os;
      os << "component " << i << " offset (" << shape.offsets[i].transpose()
         << ") m: must be finite";
      bad_shape(shape.name, os.str());
    }
  }
  // One piece: every component reached from the first through touching components.
  std::vector<char> reached(n, 0);
  std::vector<std::size_t> todo{0};
  reached[0] = 1;
  while (!todo.empty()) {
    const std::size_t i = todo.back();
    todo.pop_back();
    for (std::size_t j = 0; j < n; ++j) {
      if (reached[j]) continue;
      if ((shape.offsets[i] - shape.offsets[j]).norm() <= shape.radii[i] + shape.radii[j]) {
        reached[j] = 1;
        todo.push_back(j);
      }
    }
  }
  for (std::size_t j = 0; j < n; ++j) {
    if (!reached[j]) {
      std::ostringstream os;
      os << "component " << j << " at (" << shape.offsets[j].transpose()
         << ") m touches no other component connected to component 0: the body is in pieces";
      bad_shape(shape.name, os.str());
    }
  }

  ClumpTemplate t;
  t.name = shape.name;
  t.radii = shape.radii;
  if (n == 1) {
    // A sphere: the closed form, and the engine then treats it exactly as a sphere (World).
    const double r = shape.radii[0];
    t.volume = 4.0 / 3.0 * std::numbers::pi * r * r * r;
    t.inertia = Vec3::Constant(0.4 * t.volume * r * r);
    t.offsets = {Vec3::Zero()};
    t.centre = shape.offsets[0];
    t.reach = r;
    return t;
  }
  const MassProperties mp = clump_mass_properties(shape.offsets, shape.radii, settings);
  const Eigen::SelfAdjointEigenSolver<Mat3> eig(mp.inertia);
  Mat3 axes = eig.eigenvectors();  // columns: principal axes, moments increasing
  if (axes.determinant() < 0.0) axes.col(2) = -axes.col(2);
  t.volume = mp.volume;
  t.inertia = eig.eigenvalues();
  t.centre = mp.centre;
  t.axes = Quat(axes);
  t.axes.normalize();
  t.offsets.resize(n);
  t.reach = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    t.offsets[i] = axes.transpose() * (shape.offsets[i] - mp.centre);
    t.reach = std::max(t.reach, t.offsets[i].norm() + shape.radii[i]);
  }
  return t;
}

ClumpTemplate scale_clump_template(const ClumpTemplate& t, double factor) {
  if (!(factor > 0.0) || !std::isfinite(factor)) {
    std::ostringstream os;
    os << "clump " << t.name << ": scale factor " << factor << " must be positive and finite";
    throw std::invalid_argument(os.str());
  }
  ClumpTemplate s = t;
  for (Vec3& o : s.offsets) o *= factor;
  for (double& r : s.radii) r *= factor;
  const double f2 = factor * factor;
  s.volume = t.volume * (f2 * factor);
  s.inertia = t.inertia * (f2 * f2 * factor);
  s.reach = t.reach * factor;
  s.centre = t.centre * factor;
  return s;
}

namespace {

/// cos x and sin x. For |x| <= 0.05 (a body turning less than 0.1 rad in a step: nearly always)
/// from their Taylor polynomials, to x^8 and x^7 (first omitted terms, x^10/10! and x^9/9!,
/// below 3e-17 of the result: about a rounding), and for |x| <= 2e-3 to x^4 and x^5 (omitted
/// terms below 2e-20); at a fraction of the cost of the library's functions, which the five
/// turns of a step would otherwise call twenty times.
inline void cos_sin(double x, double* c, double* s) {
  const double x2 = x * x;
  if (std::abs(x) <= 2e-3) {
    *c = 1.0 + x2 * (-1.0 / 2 + x2 * (1.0 / 24));
    *s = x * (1.0 + x2 * (-1.0 / 6 + x2 * (1.0 / 120)));
  } else if (std::abs(x) <= 0.05) {
    *c = 1.0 + x2 * (-1.0 / 2 + x2 * (1.0 / 24 + x2 * (-1.0 / 720 + x2 * (1.0 / 40320))));
    *s = x * (1.0 + x2 * (-1.0 / 6 + x2 * (1.0 / 120 + x2 * (-1.0 / 5040))));
  } else {
    *c = std::cos(x);
    *s = std::sin(x);
  }
}

}  // namespace

void free_rotor_drift(Quat& q, const Vec3& l, const Vec3& inertia, double tau) {
  Vec3 pi = q.conjugate() * l;  // body-frame angular momentum
  const Vec3 inv = inertia.cwiseInverse();
  double qw = q.w();
  Vec3 qv = q.vec();
  // The exact flow of pi_k^2 / (2 I_k) for time s: a turn about body axis k by s pi_k / I_k.
  // q <- q (cos theta/2, sin theta/2 e_k), written out for the axis (a, b, k cyclic);
  // pi <- R_k(theta)^T pi (pi_k unchanged).
  auto turn = [&](int k, double s) {
    const double theta = (s * pi[k]) * inv[k];
    double ch, sh;
    cos_sin(0.5 * theta, &ch, &sh);
    const int a = (k + 1) % 3, b = (k + 2) % 3;
    const double w0 = qw, qa = qv[a], qb = qv[b], qk = qv[k];
    qw = w0 * ch - qk * sh;
    qv[k] = qk * ch + w0 * sh;
    qv[a] = qa * ch + qb * sh;
    qv[b] = qb * ch - qa * sh;
    const double ct = (ch - sh) * (ch + sh), st = 2.0 * ch * sh;  // of theta
    const double pa = pi[a], pb = pi[b];
    pi[a] = ct * pa + st * pb;
    pi[b] = ct * pb - st * pa;
  };
  const double half = 0.5 * tau;
  turn(0, half);
  turn(1, half);
  turn(2, tau);
  turn(1, half);
  turn(0, half);
  q = Quat(qw, qv.x(), qv.y(), qv.z());
  q.normalize();
}

}  // namespace reposetwin::sim
