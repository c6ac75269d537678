#include "sim/pile_geometry.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <sstream>
#include <stdexcept>

#include "numeric/median.hpp"

namespace reposetwin::sim {
namespace {

using numeric::median;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

[[noreturn]] void fail(const std::string& message) {
  throw std::invalid_argument("pile geometry: " + message);
}

std::string number(double x) {
  std::ostringstream s;
  s.precision(10);
  s << x;
  return s.str();
}

void check_inputs(std::span<const Vec3> x, std::span<const double> r,
                  const PileGeometrySettings& s) {
  if (x.size() != r.size()) {
    fail(std::to_string(x.size()) + " positions but " + std::to_string(r.size()) + " radii");
  }
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (!x[i].allFinite()) {
      fail("position of particle " + std::to_string(i) + " is not finite (" + number(x[i].x()) +
           ", " + number(x[i].y()) + ", " + number(x[i].z()) + ")");
    }
    if (!std::isfinite(r[i]) || r[i] <= 0.0) {
      fail("radius of particle " + std::to_string(i) + " = " + number(r[i]) +
           " m must be positive and finite");
    }
  }
  auto require = [](bool ok, const char* field, double value, const char* rule) {
    if (!ok) fail(std::string("setting ") + field + " = " + number(value) + " " + rule);
  };
  require(std::isfinite(s.plate_z), "plate_z", s.plate_z, "must be finite");
  require(std::isfinite(s.contact_tolerance) && s.contact_tolerance >= 0.0, "contact_tolerance",
          s.contact_tolerance, "must be >= 0");
  require(std::isfinite(s.footprint_tolerance) && s.footprint_tolerance >= 0.0,
          "footprint_tolerance", s.footprint_tolerance, "must be >= 0");
  require(s.sectors >= 4, "sectors", s.sectors, "must be >= 4");
  require(s.centre_iterations >= 0, "centre_iterations", s.centre_iterations, "must be >= 0");
  require(s.slice_azimuths >= 1, "slice_azimuths", s.slice_azimuths, "must be >= 1");
  require(std::isfinite(s.slice_half_width) && s.slice_half_width > 0.0, "slice_half_width",
          s.slice_half_width, "must be > 0");
  require(std::isfinite(s.bin_width) && s.bin_width > 0.0, "bin_width", s.bin_width, "must be > 0");
  require(s.flank_low >= 0.0 && s.flank_low < s.flank_high && s.flank_high <= 1.0, "flank_low",
          s.flank_low, "and flank_high must satisfy 0 <= flank_low < flank_high <= 1");
  require(s.min_flank_points >= 2, "min_flank_points", s.min_flank_points, "must be >= 2");
}

// Union-find with path halving; the root of a set is its smallest index.
struct DisjointSets {
  std::vector<std::size_t> parent;
  explicit DisjointSets(std::size_t n) : parent(n) {
    std::iota(parent.begin(), parent.end(), std::size_t{0});
  }
  std::size_t find(std::size_t i) {
    while (parent[i] != i) {
      parent[i] = parent[parent[i]];
      i = parent[i];
    }
    return i;
  }
  void unite(std::size_t a, std::size_t b) {
    a = find(a);
    b = find(b);
    if (a == b) return;
    if (a < b) std::swap(a, b);
    parent[a] = b;
  }
};

// Labels the clusters of touching spheres: returns each particle's root index. Uses a uniform
// grid (cell = the largest connection distance), sorted by cell, so the work is O(n log n).
std::vector<std::size_t> cluster_roots(std::span<const Vec3> x, std::span<const double> r,
                                       double tolerance) {
  const std::size_t n = x.size();
  DisjointSets sets(n);
  if (n == 0) return {};
  const double r_max = *std::max_element(r.begin(), r.end());
  const double cell = 2.0 * r_max * (1.0 + tolerance);
  using Cell = std::array<std::int64_t, 3>;
  constexpr double kCellLimit = 1e15;  // far strays are clamped; distances are still exact
  auto cell_of = [&](const Vec3& p) {
    Cell c;
    for (int k = 0; k < 3; ++k) {
      c[k] =
          static_cast<std::int64_t>(std::floor(std::clamp(p[k] / cell, -kCellLimit, kCellLimit)));
    }
    return c;
  };
  std::vector<std::pair<Cell, std::size_t>> sorted(n);
  for (std::size_t i = 0; i < n; ++i) sorted[i] = {cell_of(x[i]), i};
  std::sort(sorted.begin(), sorted.end());
  // Occupied cells, each with its range in `sorted`.
  struct Range {
    Cell cell;
    std::size_t begin, end;
  };
  std::vector<Range> cells;
  for (std::size_t k = 0; k < n; ++k) {
    if (cells.empty() || cells.back().cell != sorted[k].first)
      cells.push_back({sorted[k].first, k, k});
    cells.back().end = k + 1;
  }
  auto connect = [&](std::size_t i, std::size_t j) {
    const double reach = (1.0 + tolerance) * (r[i] + r[j]);
    if ((x[i] - x[j]).squaredNorm() <= reach * reach) sets.unite(i, j);
  };
  // Each cell against itself and its 13 neighbours that sort after it: every pair once.
  for (std::size_t c = 0; c < cells.size(); ++c) {
    const Range& a = cells[c];
    for (std::size_t p = a.begin; p < a.end; ++p) {
      for (std::size_t q = p + 1; q < a.end; ++q) connect(sorted[p].second, sorted[q].second);
    }
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dz = -1; dz <= 1; ++dz) {
          const Cell nc{a.cell[0] + dx, a.cell[1] + dy, a.cell[2] + dz};
          if (!(a.cell < nc)) continue;
          const auto it = std::lower_bound(
              cells.begin() + c + 1, cells.end(), nc,
              [](const Range& range, const Cell& key) { return range.cell < key; });
          if (it == cells.end() || it->cell != nc) continue;
          for (std::size_t p = a.begin; p < a.end; ++p) {
            for (std::size_t q = it->begin; q < it->end; ++q) {
              connect(sorted[p].second, sorted[q].second);
            }
          }
        }
      }
    }
  }
  std::vector<std::size_t> root(n);
  for (std::size_t i = 0; i < n; ++i) root[i] = sets.find(i);
  return root;
}

// Furthest reach of the footprint per azimuth sector around `centre`, and the outer points.
struct SectorReach {
  std::vector<double> reach;           // NaN for an empty sector [m]
  std::vector<Eigen::Vector2d> outer;  // outermost point of the reaching particle [m]
};

SectorReach sector_reach(std::span<const Vec3> x, std::span<const double> r,
                         const std::vector<std::size_t>& footprint, const Eigen::Vector2d& centre,
                         int sectors) {
  SectorReach s;
  s.reach.assign(sectors, kNaN);
  s.outer.assign(sectors, Eigen::Vector2d::Zero());
  for (std::size_t i : footprint) {
    const Eigen::Vector2d d = x[i].head<2>() - centre;
    const double rho = d.norm();
    double phi = std::atan2(d.y(), d.x());
    if (phi < 0.0) phi += 2.0 * std::numbers::pi;
    const int k = std::min(sectors - 1, static_cast<int>(phi / (2.0 * std::numbers::pi) * sectors));
    const double reach = rho + r[i];
    if (std::isnan(s.reach[k]) || reach > s.reach[k]) {
      s.reach[k] = reach;
      const Eigen::Vector2d u =
          rho > 0.0 ? Eigen::Vector2d(d / rho)
                    : Eigen::Vector2d(std::cos((k + 0.5) * 2.0 * std::numbers::pi / sectors),
                                      std::sin((k + 0.5) * 2.0 * std::numbers::pi / sectors));
      s.outer[k] = centre + reach * u;
    }
  }
  return s;
}

// Algebraic (Kasa) circle fit: minimises sum (x^2 + y^2 + a x + b y + c)^2. Returns false if the
// points do not determine a circle.
bool fit_circle(const std::vector<Eigen::Vector2d>& p, Eigen::Vector2d& centre) {
  if (p.size() < 3) return false;
  Eigen::MatrixXd a(p.size(), 3);
  Eigen::VectorXd b(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) {
    a(i, 0) = p[i].x();
    a(i, 1) = p[i].y();
    a(i, 2) = 1.0;
    b(i) = -p[i].squaredNorm();
  }
  const Eigen::Vector3d sol = a.colPivHouseholderQr().solve(b);
  if (!sol.allFinite()) return false;
  centre = Eigen::Vector2d(-0.5 * sol(0), -0.5 * sol(1));
  return true;
}

// Refines the footprint centre: fit a circle to the sectors' outer points, excluding sectors
// whose reach is further from the median than three robust deviations (1.4826 MAD) or one
// particle diameter, whichever is larger, and repeat.
Eigen::Vector2d find_centre(std::span<const Vec3> x, std::span<const double> r,
                            const std::vector<std::size_t>& footprint, int sectors, int iterations,
                            double diameter) {
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  for (std::size_t i : footprint) centre += x[i].head<2>();
  centre /= static_cast<double>(footprint.size());
  for (int it = 0; it < iterations; ++it) {
    const SectorReach s = sector_reach(x, r, footprint, centre, sectors);
    std::vector<double> reaches;
    for (double v : s.reach)
      if (!std::isnan(v)) reaches.push_back(v);
    const double m = median(reaches);
    std::vector<double> deviations;
    for (double v : reaches) deviations.push_back(std::abs(v - m));
    const double spread = std::max(3.0 * 1.4826 * median(deviations), diameter);
    std::vector<Eigen::Vector2d> points;
    for (int k = 0; k < sectors; ++k) {
      if (!std::isnan(s.reach[k]) && std::abs(s.reach[k] - m) <= spread) {
        points.push_back(s.outer[k]);
      }
    }
    Eigen::Vector2d next;
    if (!fit_circle(points, next)) break;
    // A fit far outside the footprint means the points were degenerate (a line): keep the mean.
    if ((next - centre).norm() > m) break;
    const double step = (next - centre).norm();
    centre = next;
    if (step <= 1e-12 * std::max(m, 1e-300)) break;
  }
  return centre;
}

// Least-squares line z = a + b rho through the points; angle atan(-b).
FlankFit fit_flank(const std::vector<Eigen::Vector2d>& pts, int min_points) {
  FlankFit f;
  f.points = static_cast<int>(pts.size());
  if (f.points < min_points) return f;
  double mr = 0.0, mz = 0.0;
  for (const auto& p : pts) {
    mr += p.x();
    mz += p.y();
  }
  mr /= pts.size();
  mz /= pts.size();
  double srr = 0.0, srz = 0.0;
  for (const auto& p : pts) {
    srr += (p.x() - mr) * (p.x() - mr);
    srz += (p.x() - mr) * (p.y() - mz);
  }
  if (!(srr > 0.0)) return f;  // all points at one radius: no slope
  const double slope = srz / srr;
  double ss = 0.0;
  for (const auto& p : pts) {
    const double e = p.y() - (mz + slope * (p.x() - mr));
    ss += e * e;
  }
  f.valid = true;
  f.angle = std::atan(-slope);
  f.rms = std::sqrt(ss / pts.size());
  return f;
}

// Mean and sample standard deviation.
std::pair<double, double> mean_sd(const std::vector<double>& v) {
  if (v.empty()) return {0.0, 0.0};
  const double m = std::accumulate(v.begin(), v.end(), 0.0) / v.size();
  if (v.size() < 2) return {m, 0.0};
  double ss = 0.0;
  for (double x : v) ss += (x - m) * (x - m);
  return {m, std::sqrt(ss / (v.size() - 1))};
}

PileSlice measure_slice(std::span<const Vec3> x, std::span<const double> r,
                        const std::vector<std::size_t>& pile, const PileGeometry& g, double azimuth,
                        const PileGeometrySettings& s) {
  PileSlice slice;
  slice.azimuth = azimuth;
  const Eigen::Vector2d u(std::cos(azimuth), std::sin(azimuth));
  const Eigen::Vector2d v(-u.y(), u.x());
  const double half_width = s.slice_half_width * g.median_diameter;
  const double bin = s.bin_width * g.median_diameter;
  // Highest top per (side, radial bin), with the radial position of that particle.
  struct Best {
    double top = -std::numeric_limits<double>::infinity();
    double rho = 0.0;
  };
  std::array<std::vector<Best>, 2> profile;
  for (std::size_t i : pile) {
    const Eigen::Vector2d d = x[i].head<2>() - g.centre;
    const double t = d.dot(v);
    if (std::abs(t) > half_width) continue;
    const double along = d.dot(u);
    const double rho = d.norm();
    const int side = along >= 0.0 ? 0 : 1;
    const std::size_t k = static_cast<std::size_t>(rho / bin);
    auto& p = profile[side];
    if (p.size() <= k) p.resize(k + 1);
    const double top = x[i].z() + r[i];
    if (top > p[k].top) p[k] = {top, rho};
  }
  const double low = s.flank_low * g.height;
  const double high = s.flank_high * g.height;
  for (int side = 0; side < 2; ++side) {
    std::vector<Eigen::Vector2d> pts;
    for (const Best& b : profile[side]) {
      if (!std::isfinite(b.top)) continue;
      slice.area += b.top * bin;
      if (b.top >= low && b.top <= high) pts.emplace_back(b.rho, b.top);
    }
    (side == 0 ? slice.positive : slice.negative) = fit_flank(pts, s.min_flank_points);
  }
  int n = 0;
  if (slice.positive.valid) {
    slice.angle += slice.positive.angle;
    ++n;
  }
  if (slice.negative.valid) {
    slice.angle += slice.negative.angle;
    ++n;
  }
  slice.valid = n > 0;
  if (n > 0) slice.angle /= n;
  if (g.base_diameter > 0.0) {
    slice.equal_area_angle = std::atan(4.0 * slice.area / (g.base_diameter * g.base_diameter));
  }
  return slice;
}

}  // namespace

std::string to_string(PileStatus status) {
  switch (status) {
    case PileStatus::kOk:
      return "ok";
    case PileStatus::kNoPile:
      return "no pile";
    case PileStatus::kNoFlanks:
      return "no flanks";
  }
  return "unknown";
}

PileGeometry measure_pile(std::span<const Vec3> positions, std::span<const double> radii,
                          const PileGeometrySettings& settings) {
  check_inputs(positions, radii, settings);
  // Heights are measured from the plate: work on a shifted copy if it is not at z = 0.
  std::vector<Vec3> shifted;
  if (settings.plate_z != 0.0) {
    shifted.assign(positions.begin(), positions.end());
    for (Vec3& p : shifted) p.z() -= settings.plate_z;
  }
  const std::span<const Vec3> x =
      settings.plate_z != 0.0 ? std::span<const Vec3>(shifted) : positions;
  const auto& r = radii;
  PileGeometry g;
  g.particle_count = x.size();
  g.stray_count = x.size();
  if (x.empty()) return g;

  auto on_plate = [&](std::size_t i) {
    return x[i].z() - r[i] <= settings.footprint_tolerance * r[i];
  };

  // 1. The pile: the cluster touching the plate with the largest solid volume.
  const std::vector<std::size_t> root = cluster_roots(x, r, settings.contact_tolerance);
  std::vector<double> volume(x.size(), 0.0);
  std::vector<char> touches(x.size(), 0);
  for (std::size_t i = 0; i < x.size(); ++i) {
    volume[root[i]] += r[i] * r[i] * r[i];
    if (on_plate(i)) touches[root[i]] = 1;
  }
  std::size_t best = x.size();
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (root[i] == i && touches[i] && (best == x.size() || volume[i] > volume[best])) best = i;
  }
  if (best == x.size()) return g;  // nothing on the plate: no pile

  std::vector<std::size_t> pile, footprint;
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (root[i] != best) continue;
    pile.push_back(i);
    if (on_plate(i)) footprint.push_back(i);
  }
  g.pile_count = pile.size();
  g.footprint_count = footprint.size();
  g.stray_count = x.size() - pile.size();

  // 2. H, the median diameter and the centre of mass.
  std::vector<double> diameters;
  double weight = 0.0, moment = 0.0;
  for (std::size_t i : pile) {
    g.height = std::max(g.height, x[i].z() + r[i]);
    diameters.push_back(2.0 * r[i]);
    const double w = r[i] * r[i] * r[i];
    weight += w;
    moment += w * x[i].z();
  }
  g.median_diameter = median(diameters);
  g.centre_of_mass_height = moment / weight;

  // 3. The centre and D from the footprint.
  std::vector<double> footprint_diameters;
  for (std::size_t i : footprint) footprint_diameters.push_back(2.0 * r[i]);
  g.centre = find_centre(x, r, footprint, settings.sectors, settings.centre_iterations,
                         median(footprint_diameters));
  g.sector_reach = sector_reach(x, r, footprint, g.centre, settings.sectors).reach;
  std::vector<double> reaches;
  for (double v : g.sector_reach)
    if (!std::isnan(v)) reaches.push_back(v);
  g.base_diameter = 2.0 * median(reaches);
  g.theta_hd = std::atan(2.0 * g.height / g.base_diameter);
  g.centre_of_mass_angle = std::atan(8.0 * g.centre_of_mass_height / g.base_diameter);

  // 4. Protractor slices.
  std::vector<double> slice_angles, flank_angles, equal_area;
  for (int k = 0; k < settings.slice_azimuths; ++k) {
    const double azimuth = std::numbers::pi * k / settings.slice_azimuths;
    PileSlice slice = measure_slice(x, r, pile, g, azimuth, settings);
    if (slice.valid) slice_angles.push_back(slice.angle);
    if (slice.positive.valid) flank_angles.push_back(slice.positive.angle);
    if (slice.negative.valid) flank_angles.push_back(slice.negative.angle);
    equal_area.push_back(slice.equal_area_angle);
    g.slices.push_back(slice);
  }
  g.valid_slices = static_cast<int>(slice_angles.size());
  std::tie(g.slice_angle_mean, g.slice_angle_sd) = mean_sd(slice_angles);
  g.flank_angle_sd = mean_sd(flank_angles).second;
  g.equal_area_angle = mean_sd(equal_area).first;
  g.status = slice_angles.empty() ? PileStatus::kNoFlanks : PileStatus::kOk;
  return g;
}

}  // namespace reposetwin::sim
