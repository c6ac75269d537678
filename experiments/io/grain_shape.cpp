#include "experiments/io/grain_shape.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include "experiments/io/format.hpp"
#include "experiments/io/toml_reader.hpp"

namespace reposetwin::experiments {
namespace {

// Lines of the overlap grid for a shape's mass properties: the engine's default, whose stated
// error (sim/clump.hpp: 2e-9 to 3e-7 relative) is far below a sieve class's width.
const sim::MassPropertySettings kMass{};

sim::Vec3 read_point(const toml::node& node, const TableReader& t, const std::string& key,
                     std::size_t i) {
  const toml::array* a = node.as_array();
  const std::string at = key + "[" + std::to_string(i) + "]";
  if (!a || a->size() != 3) t.fail(at, "= " + show_node(node) + " must be [x, y, z]");
  sim::Vec3 p;
  for (int c = 0; c < 3; ++c) {
    const std::optional<double> v = number_of((*a)[static_cast<std::size_t>(c)]);
    if (!v || !std::isfinite(*v)) t.fail(at, "= " + show_node(node) + " must be three numbers");
    p[c] = *v;
  }
  return p;
}

sim::ClumpShape read_template(TableReader& t, const std::string& name) {
  sim::ClumpShape shape;
  shape.name = name;
  shape.radii = t.numbers("radii");
  const toml::array* offsets = t.raw()["offsets"].as_array();
  t.mark_used("offsets");
  if (!offsets) t.fail("offsets", "is required: an array of [x, y, z] component centres");
  for (std::size_t i = 0; i < offsets->size(); ++i)
    shape.offsets.push_back(read_point(*offsets->get(i), t, "offsets", i));
  if (shape.radii.empty()) t.fail("radii", "must list at least one component radius");
  if (shape.offsets.size() != shape.radii.size())
    t.fail("offsets", "has " + std::to_string(shape.offsets.size()) + " points but radii has " +
                          std::to_string(shape.radii.size()) + " values");
  for (std::size_t i = 0; i < shape.radii.size(); ++i)
    if (!(shape.radii[i] > 0) || !std::isfinite(shape.radii[i]))
      t.fail("radii[" + std::to_string(i) + "]",
             "= " + significant(shape.radii[i]) + " must be a positive radius");
  return shape;
}

// The family of the design note, in units of S: rows of spheres along x, thickest radius 1/2.
sim::ClumpShape generate_shape(TableReader& t, GrainShape& g) {
  g.elongation = t.number("elongation", 1.0);
  g.flatness = t.number("flatness", 1.0);
  g.roundness = t.number("roundness", 1.0);
  if (!t.has("spheres")) t.fail("spheres", "is required: the number of component spheres");
  const std::int64_t n = t.integer("spheres", 0);
  for (const char* key : {"elongation", "flatness"}) {
    const double v = std::string(key) == "elongation" ? g.elongation : g.flatness;
    if (!(v >= 1.0) || !std::isfinite(v))
      t.fail(key, "= " + significant(v) +
                      " must be at least 1 (a ratio of the longer extent to the shorter)");
  }
  if (!(g.roundness > 0 && g.roundness <= 1))
    t.fail("roundness", "= " + significant(g.roundness) + " must lie in (0, 1]");
  const int rows = g.flatness > 1.0 ? 2 : 1;
  if (n < rows || n > 64 || n % rows != 0)
    t.fail("spheres", "= " + std::to_string(n) +
                          (rows == 2 ? " must be even (two rows, for flatness > 1), 2 to 64"
                                     : " must be 1 to 64"));
  const int per_row = static_cast<int>(n) / rows;
  if (per_row == 1 && g.elongation > 1.0)
    t.fail("spheres", "= " + std::to_string(n) + " (one per row) cannot make an elongation of " +
                          significant(g.elongation) + "; use at least " + std::to_string(2 * rows));
  // In one row, neighbours stand (L - 2 roundness r) / (n - 1) apart with radii at most r:
  // farther than 2 r, the grain is in pieces, and the elongation is the key to blame.
  if (rows == 1 && per_row > 1 && g.elongation > per_row - 1 + g.roundness) {
    const double needed = std::ceil(g.elongation + 1.0 - g.roundness);
    t.fail("elongation", "= " + significant(g.elongation) + " with spheres = " + std::to_string(n) +
                             " leaves gaps between the spheres (the grain would fall in pieces); "
                             "use an elongation of at most " +
                             significant(per_row - 1 + g.roundness) +
                             (needed <= 64 ? ", or spheres = " + significant(needed)
                                           : " (64 spheres, the most, allow " +
                                                 significant(63 + g.roundness) + ")"));
  }
  g.spheres = static_cast<int>(n);
  const double r = 0.5, length = g.elongation * g.flatness;
  const double row_y = 0.5 * (g.flatness - 1.0);
  const double half = std::max(0.0, 0.5 * length - g.roundness * r);
  sim::ClumpShape shape;
  shape.name = g.name;
  for (int row = 0; row < rows; ++row) {
    for (int j = 0; j < per_row; ++j) {
      const double u = per_row == 1 ? 0.0 : -1.0 + 2.0 * j / (per_row - 1);
      shape.offsets.emplace_back(half * u, rows == 2 ? (row == 0 ? -row_y : row_y) : 0.0, 0.0);
      shape.radii.push_back(r * (1.0 - (1.0 - g.roundness) * std::abs(u)));
    }
  }
  return shape;
}

// The blocky family of the design note, in units of I: a box L x I x S (L = elongation, I = 1,
// S = 1 / flatness) filled by a grid of equal spheres whose outer ones touch its faces, so the
// box's edges and corners are rounded with the spheres' radius r = (1 - angularity) S / 2. Along
// each axis the centres are evenly spaced with neighbours at most 1.8 r apart (they overlap by at
// least a tenth of a diameter: one rigid, connected body with no hole between faces), which is
// the fewest spheres that do it: angularity 0 on a 1.2 x 1 x 0.85 box is 4 spheres, 0.25 is 8.
sim::ClumpShape blocky_shape(TableReader& t, GrainShape& g) {
  g.elongation = t.number("elongation", 1.0);
  g.flatness = t.number("flatness", 1.0);
  g.angularity = t.number("angularity", 0.0);
  for (const char* key : {"elongation", "flatness"}) {
    const double v = std::string(key) == "elongation" ? g.elongation : g.flatness;
    if (!(v >= 1.0) || !std::isfinite(v) || v > 10.0)
      t.fail(key, "= " + significant(v) +
                      " must lie in [1, 10] (a ratio of the longer extent to the "
                      "shorter)");
  }
  if (!(g.angularity >= 0.0 && g.angularity < 1.0))
    t.fail("angularity", "= " + significant(g.angularity) +
                             " must lie in [0, 1) (0: edges rounded with half the shortest "
                             "extent; towards 1: sharper edges, more spheres)");
  const std::array<double, 3> extent = {g.elongation, 1.0, 1.0 / g.flatness};
  const double r = 0.5 * (1.0 - g.angularity) * extent[2];
  std::array<int, 3> count{};
  int total = 1;
  for (std::size_t a = 0; a < 3; ++a) {
    const double span = std::max(0.0, extent[a] - 2.0 * r);
    count[a] = 1 + static_cast<int>(std::ceil(span / (1.8 * r) - 1e-9));
    total *= count[a];
  }
  if (total > 64)
    t.fail("angularity", "= " + significant(g.angularity) + " needs " + std::to_string(total) +
                             " spheres for this box (at most 64): lower it");
  g.spheres = total;
  sim::ClumpShape shape;
  shape.name = g.name;
  auto at = [&](std::size_t a, int i) {
    const double half = 0.5 * extent[a] - r;
    return count[a] == 1 ? 0.0 : -half + 2.0 * half * i / (count[a] - 1);
  };
  for (int i = 0; i < count[0]; ++i)
    for (int j = 0; j < count[1]; ++j)
      for (int k = 0; k < count[2]; ++k) {
        shape.offsets.emplace_back(at(0, i), at(1, j), at(2, k));
        shape.radii.push_back(r);
      }
  return shape;
}

GrainShape read_shape(TableReader t, const std::string& key, std::size_t index, bool single) {
  t.known_keys({"name", "kind", "mass_fraction", "offsets", "radii", "elongation", "flatness",
                "roundness", "spheres", "angularity"});
  GrainShape g;
  g.key = key;
  g.name = t.string("name", "shape " + std::to_string(index));
  g.kind = t.string("kind");
  g.mass_fraction = t.number("mass_fraction", single ? 1.0 : -1.0);
  if (!single && !t.has("mass_fraction"))
    t.fail("mass_fraction", "is required when several shapes are mixed");
  if (!(g.mass_fraction >= 0 && g.mass_fraction <= 1))
    t.fail("mass_fraction", "= " + significant(g.mass_fraction) + " must lie in [0, 1]");
  sim::ClumpShape shape;
  if (g.kind == "template") {
    shape = read_template(t, g.name);
  } else if (g.kind == "generated") {
    shape = generate_shape(t, g);
  } else if (g.kind == "blocky") {
    shape = blocky_shape(t, g);
  } else {
    t.fail("kind", "= \"" + g.kind + "\" must be \"template\", \"generated\" or \"blocky\"");
  }
  t.finish();
  sim::ClumpTemplate raw;
  try {
    raw = sim::make_clump_template(shape, kMass);
  } catch (const std::invalid_argument& e) {
    t.fail(g.kind == "template" ? "offsets" : g.kind == "blocky" ? "angularity" : "spheres",
           std::string("does not make one rigid body: ") + e.what());
  }
  const PrincipalExtents e = principal_extents(raw);
  g.unit = sim::scale_clump_template(raw, 1.0 / e.intermediate);
  g.longest = e.longest / e.intermediate;
  g.intermediate = 1.0;
  g.shortest = e.shortest / e.intermediate;
  g.outlet_diameter = outlet_diameter(g.unit);
  return g;
}

}  // namespace

PrincipalExtents principal_extents(const sim::ClumpTemplate& t) {
  std::array<double, 3> extent{};
  for (int a = 0; a < 3; ++a) {
    double lo = 0.0, hi = 0.0;
    for (std::size_t c = 0; c < t.size(); ++c) {
      const double l = t.offsets[c][a] - t.radii[c], h = t.offsets[c][a] + t.radii[c];
      lo = c == 0 ? l : std::min(lo, l);
      hi = c == 0 ? h : std::max(hi, h);
    }
    extent[static_cast<std::size_t>(a)] = hi - lo;
  }
  PrincipalExtents e;
  e.long_axis = static_cast<int>(std::max_element(extent.begin(), extent.end()) - extent.begin());
  std::array<double, 3> sorted = extent;
  std::sort(sorted.begin(), sorted.end());
  e.longest = sorted[2];
  e.intermediate = sorted[1];
  e.shortest = sorted[0];
  return e;
}

double outlet_diameter(const sim::ClumpTemplate& t) {
  const int axis = principal_extents(t).long_axis;
  double w = 0.0;
  for (std::size_t c = 0; c < t.size(); ++c) {
    sim::Vec3 across = t.offsets[c];
    across[axis] = 0.0;
    w = std::max(w, 2.0 * (across.norm() + t.radii[c]));
  }
  return w;
}

std::vector<GrainShape> read_grain_shapes(TableReader& sample) {
  const bool one = sample.has("shape"), many = sample.has("shapes");
  if (one && many)
    sample.fail("shape", "and sample.shapes are both given: use [sample.shape] for one shape or "
                         "[[sample.shapes]] for a mix, not both");
  std::vector<GrainShape> shapes;
  if (!one && !many) return shapes;
  const std::string key = one ? "shape" : "shapes";
  sample.mark_used(key);
  const toml::node* node = sample.raw().get(key);
  if (one) {
    if (!node->as_table()) sample.fail(key, "must be a table ([sample.shape])");
    shapes.push_back(read_shape(TableReader(*node->as_table(), sample.file(), sample.where(key)),
                                sample.where(key), 0, true));
  } else {
    const toml::array* list = node->as_array();
    if (!list || list->empty() || !list->is_array_of_tables())
      sample.fail(key, "must be an array of tables ([[sample.shapes]]), one per shape");
    for (std::size_t k = 0; k < list->size(); ++k) {
      const std::string at = sample.where(key) + "[" + std::to_string(k) + "]";
      shapes.push_back(read_shape(TableReader(*list->get(k)->as_table(), sample.file(), at), at,
                                  k, list->size() == 1));
    }
  }
  double sum = 0.0;
  std::string each;
  for (const GrainShape& g : shapes) {
    sum += g.mass_fraction;
    each += (each.empty() ? "" : " + ") + significant(g.mass_fraction);
  }
  if (std::abs(sum - 1.0) > 1e-9)
    sample.fail(key, "mass_fraction values " + each + " sum to " + significant(sum) + ", not 1");
  return shapes;
}

void check_shapes_pass_outlet(const std::vector<GrainShape>& shapes, double d_max, double w,
                              const std::string& file) {
  for (const GrainShape& g : shapes) {
    const double across = g.outlet_diameter * d_max;
    if (across >= w)
      throw InputError(file + ": " + g.key + " (\"" + g.name +
                       "\"): a grain of the sieve size d_max = " + significant(1e3 * d_max) +
                       " mm is " + significant(1e3 * across) +
                       " mm across its long axis and does not pass the outlet "
                       "container.bottom_diameter_m = " +
                       significant(w) + " m");
  }
}

}  // namespace reposetwin::experiments
