#include "sim/model.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "sim/particles.hpp"

namespace reposetwin::sim {
namespace {

[[noreturn]] void bad(const std::string& field, double value, const std::string& rule) {
  std::ostringstream os;
  os << field << " = " << value << ": " << rule;
  throw std::invalid_argument(os.str());
}

}  // namespace

double rayleigh_time(double radius, double density, double youngs_modulus, double poisson) {
  const double g = youngs_modulus / (2.0 * (1.0 + poisson));
  return std::numbers::pi * radius * std::sqrt(density / g) / (0.1631 * poisson + 0.8766);
}

double hertz_contact_time(double m_eff, double r_eff, double e_eff, double speed) {
  return 2.87 * std::pow(m_eff * m_eff / (r_eff * e_eff * e_eff * speed), 0.2);
}

void Model::set_pair(int a, int b, const PairParams& p) {
  const int n = static_cast<int>(materials.size());
  if (static_cast<int>(pairs.size()) != n * n) pairs.assign(n * n, PairParams{});
  pairs[a * n + b] = p;
  pairs[b * n + a] = p;
}

int Model::add_clump_template(const ClumpShape& shape, const MassPropertySettings& settings) {
  clumps.push_back(make_clump_template(shape, settings));
  return static_cast<int>(clumps.size()) - 1;
}

double Model::youngs_modulus_used(int m) const {
  return settings.softened_youngs_modulus > 0.0 ? settings.softened_youngs_modulus
                                                : materials[m].youngs_modulus;
}

void Model::finalize(double rmin, double rmax, double r_step) {
  const int n = static_cast<int>(materials.size());
  if (n == 0) throw std::invalid_argument("materials: at least one material is required");
  if (static_cast<int>(pairs.size()) != n * n) pairs.resize(n * n, PairParams{});
  for (int m = 0; m < n; ++m) {
    const Material& mat = materials[m];
    const std::string f = "materials." + mat.name + ".";
    if (!(mat.density > 0.0)) bad(f + "density", mat.density, "must be positive [kg/m^3]");
    if (!(mat.youngs_modulus > 0.0))
      bad(f + "youngs_modulus", mat.youngs_modulus, "must be positive [Pa]");
    if (!(mat.poisson_ratio > -1.0 && mat.poisson_ratio < 0.5))
      bad(f + "poisson_ratio", mat.poisson_ratio, "must lie in (-1, 0.5)");
  }
  if (settings.softened_youngs_modulus < 0.0)
    bad("settings.softened_youngs_modulus", settings.softened_youngs_modulus,
        "must be positive, or 0 for the real modulus [Pa]");
  table.n = n;
  table.params = pairs;
  table.consts.assign(n * n, ContactConstants{});
  for (int a = 0; a < n; ++a) {
    for (int b = 0; b < n; ++b) {
      const PairParams& p = pairs[a * n + b];
      const std::string f = "pairs." + materials[a].name + "-" + materials[b].name + ".";
      if (!(p.restitution > 0.0 && p.restitution <= 1.0))
        bad(f + "restitution", p.restitution, "must lie in (0, 1]");
      if (!(p.friction >= 0.0)) bad(f + "friction", p.friction, "must not be negative");
      if (!(p.rolling_friction >= 0.0))
        bad(f + "rolling_friction", p.rolling_friction, "must not be negative");
      if (!(p.rolling_damping >= 0.0))
        bad(f + "rolling_damping", p.rolling_damping, "must not be negative");
      if (!(p.cohesion_energy_density >= 0.0 && std::isfinite(p.cohesion_energy_density)))
        bad(f + "cohesion_energy_density", p.cohesion_energy_density,
            "must be finite and not negative [J/m^3]");
      if (!std::isfinite(p.rolling_size_exponent))
        bad(f + "rolling_size_exponent", p.rolling_size_exponent, "must be finite");
      if (!(p.rolling_reference_diameter >= 0.0 && std::isfinite(p.rolling_reference_diameter)))
        bad(f + "rolling_reference_diameter", p.rolling_reference_diameter,
            "must be finite and not negative [m]");
      if (p.rolling_size_exponent != 0.0 && !(p.rolling_reference_diameter > 0.0))
        bad(f + "rolling_reference_diameter", p.rolling_reference_diameter,
            "must be positive when rolling_size_exponent is not 0 [m]");
      const double ea = youngs_modulus_used(a), eb = youngs_modulus_used(b);
      const double na = materials[a].poisson_ratio, nb = materials[b].poisson_ratio;
      ContactConstants& c = table.consts[a * n + b];
      c.e_star = 1.0 / ((1.0 - na * na) / ea + (1.0 - nb * nb) / eb);
      c.g_star = 1.0 / (2.0 * (2.0 - na) * (1.0 + na) / ea + 2.0 * (2.0 - nb) * (1.0 + nb) / eb);
      c.beta = damping_beta(p.restitution);
      c.mu_s = p.friction;
      c.mu_r = p.rolling_friction;
      c.eta_r = p.rolling_damping;
      c.rolling = p.rolling_model;
      c.cohesion_energy_density = p.cohesion_energy_density;
      c.cohesive = p.cohesion_energy_density > 0.0;
      c.rolling_size_exponent = p.rolling_size_exponent;
      c.rolling_reference_diameter = p.rolling_reference_diameter;
      c.size_dependent_rolling = p.rolling_size_exponent != 0.0;
      derive_contact_constants(c);
    }
  }
  if (static_cast<int>(walls.size()) > kMaxWalls)
    bad("walls (count)", static_cast<double>(walls.size()),
        "more walls than supported (" + std::to_string(kMaxWalls) + ")");
  for (std::size_t w = 0; w < walls.size(); ++w) {
    WallSpec& ws = walls[w];
    const std::string f = "walls." + ws.name + ".";
    if (ws.material < 0 || ws.material >= n)
      bad(f + "material", ws.material, "is not a material index");
    if (ws.kind == WallKind::kPlane) {
      if (!(ws.normal.norm() > 0.0)) bad(f + "normal (length)", ws.normal.norm(), "must be non-zero");
      ws.normal.normalize();
    } else {
      if (!(ws.z_top > ws.z_bottom)) bad(f + "z_top", ws.z_top, "must exceed z_bottom");
      if (!(ws.r_bottom >= 0.0)) bad(f + "r_bottom", ws.r_bottom, "must not be negative");
      if (!(ws.r_top >= 0.0)) bad(f + "r_top", ws.r_top, "must not be negative");
    }
  }
  if (!(rmin > 0.0)) bad("particle radius (smallest)", rmin, "must be positive [m]");
  if (!(rmax >= rmin)) bad("particle radius (largest)", rmax, "must not be below the smallest");
  r_min = rmin;
  r_max = rmax;
  if (!(r_step >= 0.0 && std::isfinite(r_step)))
    bad("time-step radius", r_step, "must be finite and not negative [m]");
  step_radius = std::max(r_step, rmin);
  // The stiffest, lightest material in use (a particle's or a wall's) sets the Rayleigh time of
  // the smallest particle.
  std::vector<char> in_use(static_cast<std::size_t>(n), particle_materials.empty() ? 1 : 0);
  for (const int m : particle_materials) {
    if (m < 0 || m >= n) bad("particle_materials", m, "is not a material index");
    in_use[static_cast<std::size_t>(m)] = 1;
  }
  for (const WallSpec& ws : walls) in_use[static_cast<std::size_t>(ws.material)] = 1;
  rayleigh_time = 0.0;
  bool first = true;
  for (int m = 0; m < n; ++m) {
    if (!in_use[static_cast<std::size_t>(m)]) continue;
    const double t = sim::rayleigh_time(rmin, materials[m].density, youngs_modulus_used(m),
                                        materials[m].poisson_ratio);
    if (first || t < rayleigh_time) rayleigh_time = t;
    first = false;
  }
  if (!(settings.max_rayleigh_fraction > 0.0))
    bad("settings.max_rayleigh_fraction", settings.max_rayleigh_fraction, "must be positive");
  if (settings.time_step > 0.0) {
    if (settings.time_step > settings.max_rayleigh_fraction * rayleigh_time) {
      std::ostringstream os;
      os << "exceeds the stability limit " << settings.max_rayleigh_fraction
         << " x Rayleigh time = " << settings.max_rayleigh_fraction * rayleigh_time
         << " s of the smallest particle (radius " << rmin << " m)";
      bad("settings.time_step", settings.time_step, os.str());
    }
    dt = settings.time_step;
  } else {
    if (settings.time_step < 0.0) bad("settings.time_step", settings.time_step, "must not be negative");
    if (!(settings.rayleigh_fraction > 0.0 &&
          settings.rayleigh_fraction <= settings.max_rayleigh_fraction))
      bad("settings.rayleigh_fraction", settings.rayleigh_fraction,
          "must lie in (0, max_rayleigh_fraction]");
    // T_R is linear in the radius.
    dt = std::min(settings.rayleigh_fraction * rayleigh_time * (step_radius / rmin),
                  settings.max_rayleigh_fraction * rayleigh_time);
  }
  if (settings.skin < 0.0) bad("settings.skin", settings.skin, "must not be negative [m]");
}

}  // namespace reposetwin::sim
