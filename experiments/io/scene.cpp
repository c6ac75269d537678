#include "experiments/io/scene.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <numbers>
#include <optional>
#include <sstream>
#include <utility>

#include "experiments/io/format.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/io/toml_reader.hpp"
#include "experiments/io/toml_tables.hpp"
#include "sim/psd.hpp"

namespace reposetwin::experiments {
namespace {

// Limits beyond which a value is a typo, not an experiment. Each is far outside any laboratory
// pile test, so it refuses only values that would otherwise run for ever, overflow a count or
// quietly stand for something else.
constexpr double kMinGrains = 10.0;       // grains of the largest size in a sample [-]
constexpr double kMaxLiftSpeed = 1.0;     // [m/s]
constexpr double kMaxGravity = 100.0;     // [m/s^2]
constexpr double kMinDensity = 1.0;       // below a gas's: no grain [kg/m^3]
constexpr double kMaxDensity = 1e5;       // osmium is 2.26e4 [kg/m^3]
constexpr double kMaxModulus = 1e13;      // diamond is 1.2e12 [Pa]
constexpr double kMaxFriction = 10.0;     // sliding and rolling coefficients [-]
constexpr double kMaxSettleSpeed = 1.0;   // a grain this fast has not settled [m/s]
constexpr double kMaxLatticeGap = 1.0;    // fill spacing twice d_max [-]
constexpr double kMaxContainerSize = 10.0;  // diameters, height, gap [m]
constexpr double kMaxMaxTime = 1e5;       // simulated seconds (a day is 8.6e4) [s]
constexpr int kMaxThreads = 4096;
constexpr int kMaxSectors = 360;
constexpr int kMaxSliceAzimuths = 3600;
// Derived from several keys: what a run would do, bounded before it starts.
constexpr double kMaxSteps = 1e11;   // max_time / dt: 1e11 steps of one grain are days [-]
constexpr double kMaxFrames = 1e4;   // max_time / frame_interval: .vtp frame sets written [-]
constexpr double kMaxParticles = 1e10;  // no machine holds more; the plan's limit is far lower [-]

sim::Material read_material(TableReader t, const std::string& name) {
  sim::Material m;
  m.name = name;
  m.density = t.number("density_kg_m3", m.density);
  m.youngs_modulus = t.number("youngs_modulus_pa", m.youngs_modulus);
  m.poisson_ratio = t.number("poisson_ratio", m.poisson_ratio);
  if (!(m.density >= kMinDensity && m.density <= kMaxDensity))
    t.fail("density_kg_m3", "= " + significant(m.density) + " must be in [" +
                                significant(kMinDensity) + ", " + significant(kMaxDensity) +
                                "] kg/m^3 (rock is about 2700)");
  if (!(m.youngs_modulus > 0 && m.youngs_modulus <= kMaxModulus))
    t.fail("youngs_modulus_pa", "= " + significant(m.youngs_modulus) + " must be in (0, " +
                                    significant(kMaxModulus) + "] Pa (rock is about 5e10)");
  if (!(m.poisson_ratio > -1 && m.poisson_ratio < 0.5))
    t.fail("poisson_ratio", "= " + significant(m.poisson_ratio) + " must lie in (-1, 0.5)");
  t.finish();
  return m;
}

sim::PairParams read_contact(TableReader t) {
  sim::PairParams p;
  p.restitution = t.number("restitution", p.restitution);
  p.friction = t.number("friction", p.friction);
  p.rolling_friction = t.number("rolling_friction", p.rolling_friction);
  p.rolling_damping = t.number("rolling_damping", p.rolling_damping);
  const std::string model = t.string("rolling_model", "epsd");
  const sim::RollingModelInfo* info = sim::find_rolling_model(model);
  if (!info) {
    std::string known;
    for (const auto& row : sim::kRollingModels) known += " " + std::string(row.keyword);
    t.fail("rolling_model", "= \"" + model + "\" is not a rolling model (known:" + known + ")");
  }
  p.rolling_model = info->model;
  // Optional effects (off by default): simplified-JKR cohesion and size-dependent rolling.
  p.cohesion_energy_density = t.number("cohesion_energy_density", p.cohesion_energy_density);
  p.rolling_size_exponent = t.number("rolling_size_exponent", p.rolling_size_exponent);
  p.rolling_reference_diameter =
      t.number("rolling_reference_diameter_m", p.rolling_reference_diameter);
  if (!(p.cohesion_energy_density >= 0 && std::isfinite(p.cohesion_energy_density)))
    t.fail("cohesion_energy_density", "= " + significant(p.cohesion_energy_density) +
                                          " must be finite and not negative [J/m^3]");
  if (!std::isfinite(p.rolling_size_exponent))
    t.fail("rolling_size_exponent",
           "= " + significant(p.rolling_size_exponent) + " must be finite");
  if (!(p.rolling_reference_diameter >= 0 && std::isfinite(p.rolling_reference_diameter)))
    t.fail("rolling_reference_diameter_m", "= " + significant(p.rolling_reference_diameter) +
                                               " must be finite and not negative [m]");
  if (p.rolling_size_exponent != 0 && !(p.rolling_reference_diameter > 0))
    t.fail("rolling_reference_diameter_m", "= " + significant(p.rolling_reference_diameter) +
                                               " must be positive when " +
                                               t.where("rolling_size_exponent") + " = " +
                                               significant(p.rolling_size_exponent) + " is not 0");
  if (!(p.restitution > 0 && p.restitution <= 1))
    t.fail("restitution", "= " + significant(p.restitution) + " must lie in (0, 1]");
  if (!(p.friction >= 0 && p.friction <= kMaxFriction))
    t.fail("friction",
           "= " + significant(p.friction) + " must be in [0, " + significant(kMaxFriction) + "]");
  if (!(p.rolling_friction >= 0 && p.rolling_friction <= kMaxFriction))
    t.fail("rolling_friction", "= " + significant(p.rolling_friction) + " must be in [0, " +
                                   significant(kMaxFriction) + "]");
  if (!(p.rolling_damping >= 0))
    t.fail("rolling_damping", "= " + significant(p.rolling_damping) + " must not be negative");
  t.finish();
  return p;
}

/// The two materials a [contacts] key "a-b" names. A material's own name may hold a dash
/// ("ro-ck"), so every split is tried: exactly one must name two declared materials.
std::optional<std::pair<std::string, std::string>> contact_materials(
    const std::string& key, const std::vector<sim::Material>& materials) {
  auto declared = [&](const std::string& name) {
    return std::any_of(materials.begin(), materials.end(),
                       [&](const sim::Material& m) { return m.name == name; });
  };
  std::optional<std::pair<std::string, std::string>> found;
  for (std::size_t dash = key.find('-'); dash != std::string::npos;
       dash = key.find('-', dash + 1)) {
    const std::string a = key.substr(0, dash), b = key.substr(dash + 1);
    if (!declared(a) || !declared(b)) continue;
    if (found) return std::nullopt;  // two readings: neither is taken
    found = {a, b};
  }
  return found;
}

/// The scene as read, with the optional contact effects written out in every [contacts.a-b]
/// table (defaults included), so a run folder states whether cohesion or size-dependent rolling
/// was on without knowing the parser's defaults.
// The scene as run: every contact's defaults written out, and a sieve-table file's [psd] table
// copied in as [sample.psd], so the text loads on its own from any folder (a psd_file path is
// relative to the original scene's folder).
std::string resolved_text(const toml::table& doc, const SceneConfig& s,
                          const std::filesystem::path& dir) {
  toml::table out = doc;
  if (toml::table* sample = out["sample"].as_table()) {
    if (const auto file = (*sample)["psd_file"].value<std::string>()) {
      const std::filesystem::path p = dir / *file;
      sample->insert_or_assign("psd", psd_table_of_file(p.string()));
      sample->erase("psd_file");
    }
  }
  if (toml::table* contacts = out["contacts"].as_table()) {
    for (auto& [key, node] : *contacts) {
      toml::table* t = node.as_table();
      const auto pair = contact_materials(std::string(key.str()), s.materials);
      if (!t || !pair) continue;
      const auto it = s.contacts.find(*pair);
      if (it == s.contacts.end()) continue;
      const sim::PairParams& p = it->second;
      t->insert_or_assign("cohesion_energy_density", p.cohesion_energy_density);
      t->insert_or_assign("rolling_size_exponent", p.rolling_size_exponent);
      t->insert_or_assign("rolling_reference_diameter_m", p.rolling_reference_diameter);
    }
  }
  std::ostringstream os;
  os << out;
  return os.str();
}

/// Volume of the container's inside [m^3].
double container_volume(const ContainerConfig& c) {
  const double r0 = 0.5 * c.bottom_diameter, r1 = 0.5 * c.top_diameter;
  return std::numbers::pi / 3.0 * c.height * (r0 * r0 + r0 * r1 + r1 * r1);
}

// [scene]: name, description, seed.
void read_scene_head(TableReader t, SceneConfig& s) {
  s.name = t.string("name");
  s.description = t.string("description", "");
  // The name titles pages and progress lines: a control character (a NUL) would cut or garble it.
  for (const char c : s.name)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
      t.fail("name", "holds a control character (code " +
                         std::to_string(static_cast<int>(static_cast<unsigned char>(c))) +
                         "); a name is printable text");
  const std::int64_t seed = t.integer("seed", 1);
  if (seed < 0) t.fail("seed", "= " + std::to_string(seed) + " must not be negative");
  s.seed = static_cast<std::uint64_t>(seed);
  t.finish();
}

// [materials]: at least one.
void read_materials(TableReader t, SceneConfig& s) {
  for (const std::string& name : t.keys())
    s.materials.push_back(read_material(*t.table(name), name));
  if (s.materials.empty()) t.fail("", "must define at least one material");
  t.finish();
}

// [sample]: mass, material, the PSD (a sieve file or an inline table), size cut-offs and grain
// shapes; a sample of too few grains of the largest size is refused.
void read_sample(TableReader t, SceneConfig& s, const toml::table& doc,
                 const std::filesystem::path& dir, const std::string& file) {
  s.mass = t.number("mass_kg");
  if (!(s.mass > 0)) t.fail("mass_kg", "= " + significant(s.mass) + " must be positive");
  s.sample_material = t.string("material", s.sample_material);
  material_index(s, s.sample_material, t.where("material"));
  const bool has_file = t.has("psd_file"), has_inline = t.has("psd");
  if (has_file == has_inline)
    t.fail("psd_file", "or an inline [sample.psd] table is required (exactly one of them)");
  try {
    if (has_file) {
      const std::string name = t.string("psd_file");
      if (name.empty()) t.fail("psd_file", "is empty: name a sieve-table file (TOML or CSV)");
      if (name.find('\0') != std::string::npos)
        t.fail("psd_file", "holds a NUL character; a file name cannot");
      const std::filesystem::path p = dir / name;
      std::error_code ec;  // a name the system refuses (too long, ...) is a bad value too
      if (!std::filesystem::exists(p, ec))
        t.fail("psd_file", "= \"" + p.string() + "\" does not exist" +
                               (ec ? " (" + ec.message() + ")" : std::string()));
      s.psd = read_psd_file(p.string());
    } else {
      t.mark_used("psd");
      const toml::table* psd = doc["sample"]["psd"].as_table();
      if (!psd) t.fail("psd", "must be a table");
      s.psd = parse_psd_table(*psd, file, t.where("psd"));
    }
  } catch (const InputError&) {
    throw;
  } catch (const std::invalid_argument& e) {  // the PSD reader names the file and key
    throw InputError(e.what(), t.where(has_file ? "psd_file" : "psd"));
  } catch (const std::exception& e) {  // a file that is no sieve table at all
    throw InputError(file + ": " + t.where("psd_file") + ": " + e.what(), t.where("psd_file"));
  }
  for (const char* key : {"d_min_mm", "d_max_mm"}) {
    if (!t.has(key)) continue;
    const double d = t.number(key);
    if (!(d > 0 && std::isfinite(d)))
      t.fail(key, "= " + significant(d) + " must be a positive size");
    (std::string(key) == "d_min_mm" ? s.psd.spec.d_min : s.psd.spec.d_max) = 1e-3 * d;
  }
  s.shapes = read_grain_shapes(t);
  t.finish();
  sim::ResolvedPsd resolved;
  try {
    resolved = sim::resolve_psd(s.psd.spec);
  } catch (const std::invalid_argument& e) {
    // A cut-off outside the table is the cut-off key's fault when the scene set it.
    // (Both, when the message is about the two: "d_min = ... must be below d_max = ...".)
    const std::string what = e.what();
    std::string keys, first;
    for (const char* key : {"d_min_mm", "d_max_mm"}) {
      const std::string name = std::string(key).substr(0, 5);  // "d_min", "d_max"
      if (t.has(key) && what.find(name + " =") != std::string::npos) {
        keys += (keys.empty() ? "" : ", ") + t.where(key) + " = " + significant(t.number(key));
        if (first.empty()) first = t.where(key);
      }
    }
    if (!keys.empty()) throw InputError(file + ": " + keys + ": " + what, first);
    throw InputError(file + ": sample.psd: " + what);
  }
  // A sample of a few grains is no pile, and the sampler could only round it up to one grain
  // many times its mass.
  const double density = s.materials[material_index(s, s.sample_material, "")].density;
  const double grain = density * std::numbers::pi / 6.0 * std::pow(resolved.d_max, 3);
  if (s.mass < kMinGrains * grain)
    t.fail("mass_kg", "= " + significant(s.mass) + " kg is " + significant(s.mass / grain) +
                          " grains of the largest size (" + significant(1e3 * resolved.d_max) +
                          " mm, " + significant(grain) +
                          " kg each, from sample.psd's sieve sizes or " +
                          "sample.d_max_mm); a pile needs at least " + significant(kMinGrains));
}

// [contacts]: one table per pair of declared materials, "a-b" (both orders set).
void read_contacts(TableReader t, SceneConfig& s) {
  for (const std::string& key : t.keys()) {
    const auto pair = contact_materials(key, s.materials);
    if (!pair) {
      std::string names;
      for (const sim::Material& m : s.materials) names += (names.empty() ? "" : ", ") + m.name;
      t.fail(key, "must name two materials of [materials] as \"a-b\", in one way only "
                  "(materials: " + names + ")");
    }
    const auto& [a, b] = *pair;
    const sim::PairParams p = read_contact(*t.table(key));
    s.contacts[{a, b}] = p;
    s.contacts[{b, a}] = p;
    s.contact_pairs.emplace_back(a, b);
  }
  t.finish();
}

// [container]: a funnel or a cylinder the sample passes and fits in.
void read_container(TableReader t, SceneConfig& s, const std::string& file) {
  ContainerConfig& c = s.container;
  c.kind = t.string("kind", c.kind);
  if (c.kind != "funnel" && c.kind != "cylinder")
    t.fail("kind", "= \"" + c.kind + "\" must be \"funnel\" or \"cylinder\"");
  c.material = t.string("material", c.material);
  material_index(s, c.material, t.where("material"));
  c.bottom_diameter = t.number("bottom_diameter_m", c.bottom_diameter);
  c.top_diameter = c.kind == "cylinder" ? c.bottom_diameter : c.top_diameter;
  if (c.kind == "funnel") c.top_diameter = t.number("top_diameter_m", c.top_diameter);
  c.height = t.number("height_m", c.height);
  c.gap = t.number("gap_m", c.gap);
  const std::string most = significant(kMaxContainerSize) + "] m";
  if (!(c.bottom_diameter > 0 && c.bottom_diameter <= kMaxContainerSize))
    t.fail("bottom_diameter_m", "= " + significant(c.bottom_diameter) + " must be in (0, " + most);
  if (!(c.top_diameter >= c.bottom_diameter))
    t.fail("top_diameter_m", "= " + significant(c.top_diameter) + " must not be below the outlet " +
                                 t.where("bottom_diameter_m") + " = " +
                                 significant(c.bottom_diameter));
  if (!(c.top_diameter <= kMaxContainerSize))
    t.fail("top_diameter_m", "= " + significant(c.top_diameter) + " must be at most " + most);
  if (!(c.height > 0 && c.height <= kMaxContainerSize))
    t.fail("height_m", "= " + significant(c.height) + " must be in (0, " + most);
  if (!(c.gap >= 0 && c.gap <= kMaxContainerSize))
    t.fail("gap_m", "= " + significant(c.gap) + " must be in [0, " + most);
  t.finish();
  const sim::ResolvedPsd psd = sim::resolve_psd(s.psd.spec);
  if (psd.d_max >= c.bottom_diameter) {
    throw InputError(file + ": sample d_max = " + significant(psd.d_max * 1e3) +
                     " mm does not pass the outlet container.bottom_diameter_m = " +
                     significant(c.bottom_diameter) + " m");
  }
  check_shapes_pass_outlet(s.shapes, psd.d_max, c.bottom_diameter, file);
  const double density = s.materials[material_index(s, s.sample_material, "sample")].density;
  const double bulk = s.mass / (density * 0.6);  // loose bulk volume (solid fraction 0.6)
  if (bulk > container_volume(c)) {
    throw InputError(file + ": sample.mass_kg = " + significant(s.mass) + " needs about " +
                     significant(bulk * 1e6) + " cm^3 of bulk volume, more than the container's " +
                     significant(container_volume(c) * 1e6) +
                     " cm^3 (container.bottom_diameter_m = " + significant(c.bottom_diameter) +
                     ", container.top_diameter_m = " + significant(c.top_diameter) +
                     ", container.height_m = " + significant(c.height) + ")");
  }
}

// [plate]: its material.
void read_plate(TableReader t, SceneConfig& s) {
  s.plate_material = t.string("material", s.plate_material);
  material_index(s, s.plate_material, t.where("material"));
  t.finish();
}

// Every contact the test uses is declared.
void check_test_contacts(const SceneConfig& s, const std::string& file) {
  for (const auto& [a, b] : {std::pair{s.sample_material, s.sample_material},
                             std::pair{s.sample_material, s.container.material},
                             std::pair{s.sample_material, s.plate_material}}) {
    if (!s.contacts.count({a, b})) {
      throw InputError(file + ": contacts." + a + "-" + b +
                       " is missing: every contact the test uses must be declared");
    }
  }
}

// [procedure]: the fill, lift and settle law.
void read_procedure(TableReader t, ProcedureConfig& p) {
  p.lift_speed = t.number("lift_speed_m_s", p.lift_speed);
  p.settle_speed = t.number("settle_speed_m_s", p.settle_speed);
  p.fill_settle_max = t.number("fill_settle_max_s", p.fill_settle_max);
  p.final_settle_max = t.number("final_settle_max_s", p.final_settle_max);
  p.max_time = t.number("max_time_s", p.max_time);
  p.clog_window = t.number("clog_window_s", p.clog_window);
  p.max_retained_fraction = t.number("max_retained_fraction", p.max_retained_fraction);
  p.lattice_gap = t.number("lattice_gap", p.lattice_gap);
  p.fill_jitter = t.number("fill_jitter", p.fill_jitter);
  p.fill_max_speed = t.number("fill_max_speed_m_s", p.fill_max_speed);
  if (!(p.fill_max_speed > 0))
    t.fail("fill_max_speed_m_s", "= " + significant(p.fill_max_speed) + " must be positive");
  if (!(p.lift_speed > 0 && p.lift_speed <= kMaxLiftSpeed))
    t.fail("lift_speed_m_s", "= " + significant(p.lift_speed) + " m/s must be in (0, " +
                                 significant(kMaxLiftSpeed) + "] (the lab lifts at 0.01)");
  if (!(p.settle_speed > 0 && p.settle_speed <= kMaxSettleSpeed))
    t.fail("settle_speed_m_s", "= " + significant(p.settle_speed) + " m/s must be in (0, " +
                                   significant(kMaxSettleSpeed) + "]");
  if (!(p.fill_settle_max > 0))
    t.fail("fill_settle_max_s", "= " + significant(p.fill_settle_max) + " must be positive");
  if (!(p.final_settle_max > 0))
    t.fail("final_settle_max_s", "= " + significant(p.final_settle_max) + " must be positive");
  if (!(p.max_time > 0 && p.max_time <= kMaxMaxTime))
    t.fail("max_time_s",
           "= " + significant(p.max_time) + " s must be in (0, " + significant(kMaxMaxTime) + "]");
  if (!(p.clog_window > 0))
    t.fail("clog_window_s", "= " + significant(p.clog_window) + " must be positive");
  if (!(p.max_retained_fraction >= 0 && p.max_retained_fraction < 1))
    t.fail("max_retained_fraction",
           "= " + significant(p.max_retained_fraction) + " must be in [0, 1)");
  if (!(p.lattice_gap >= 0 && p.lattice_gap <= kMaxLatticeGap))
    t.fail("lattice_gap", "= " + significant(p.lattice_gap) + " must be in [0, " +
                              significant(kMaxLatticeGap) + "] (fill spacing d_max (1 + this))");
  if (!(p.fill_jitter >= 0 && p.fill_jitter <= 1))
    t.fail("fill_jitter", "= " + significant(p.fill_jitter) +
                              " must be in [0, 1] (the fraction of a grain's free room in its "
                              "lattice cell)");
  t.finish();
}

// [numerics]: the engine's settings, each within what keeps the integration stable.
void read_numerics(TableReader t, sim::Settings& n) {
  n.rayleigh_fraction = t.number("rayleigh_fraction", n.rayleigh_fraction);
  n.time_step = t.number("time_step_s", n.time_step);
  n.softened_youngs_modulus = t.number("softened_youngs_modulus_pa", n.softened_youngs_modulus);
  n.skin = t.number("skin_m", n.skin);
  const std::int64_t threads = t.integer("threads", n.threads);
  if (threads < 0 || threads > kMaxThreads)
    t.fail("threads", "= " + std::to_string(threads) + " must be in [0, " +
                          std::to_string(kMaxThreads) + "]");
  n.threads = static_cast<int>(threads);
  n.gravity.z() = -t.number("gravity_m_s2", -n.gravity.z());
  n.max_overlap_ratio = t.number("max_overlap_ratio", n.max_overlap_ratio);
  n.initial_overlap_tolerance = t.number("initial_overlap_tolerance", n.initial_overlap_tolerance);
  n.escape_distance = t.number("escape_distance_m", n.escape_distance);
  if (n.time_step < 0)
    t.fail("time_step_s", "= " + significant(n.time_step) + " must not be negative");
  // The stability guard (max_rayleigh_fraction) is the engine's, not a scene key.
  if (!(n.rayleigh_fraction > 0 && n.rayleigh_fraction <= n.max_rayleigh_fraction))
    t.fail("rayleigh_fraction", "= " + significant(n.rayleigh_fraction) + " must be in (0, " +
                                    significant(n.max_rayleigh_fraction) +
                                    "]: above it the explicit integration is unstable");
  const double g = -n.gravity.z();
  // A pile forms only under gravity pulling the grains onto the plate: without it (0, or
  // upward) there is no pile physics and no angle to report.
  if (!(std::isfinite(g) && g > 0 && g <= kMaxGravity))
    t.fail("gravity_m_s2", "= " + significant(g) + " must be positive (downward) and at most " +
                               significant(kMaxGravity) + " m/s^2 (the lab's is 9.81)");
  if (!(n.initial_overlap_tolerance >= 0 && std::isfinite(n.initial_overlap_tolerance)))
    t.fail("initial_overlap_tolerance",
           "= " + significant(n.initial_overlap_tolerance) + " must not be negative");
  if (!(n.max_overlap_ratio > 0 && n.max_overlap_ratio <= 1))
    t.fail("max_overlap_ratio", "= " + significant(n.max_overlap_ratio) + " must be in (0, 1]");
  if (!(n.escape_distance > 0 && std::isfinite(n.escape_distance)))
    t.fail("escape_distance_m", "= " + significant(n.escape_distance) + " must be positive");
  if (!(n.skin >= 0 && std::isfinite(n.skin)))
    t.fail("skin_m", "= " + significant(n.skin) + " must not be negative");
  if (!(n.softened_youngs_modulus >= 0 && n.softened_youngs_modulus <= kMaxModulus))
    t.fail("softened_youngs_modulus_pa", "= " + significant(n.softened_youngs_modulus) +
                                             " must be in [0, " + significant(kMaxModulus) +
                                             "] Pa (0: each material's own)");
  t.finish();
}

// [output]: frames, checkpoints, progress.
void read_output(TableReader t, OutputConfig& o) {
  o.frame_interval = t.number("frame_interval_s", o.frame_interval);
  o.checkpoint_interval = t.number("checkpoint_interval_s", o.checkpoint_interval);
  o.progress_interval = t.number("progress_interval_s", o.progress_interval);
  o.contact_forces = t.boolean("contact_forces", o.contact_forces);
  if (o.frame_interval < 0)
    t.fail("frame_interval_s", "= " + significant(o.frame_interval) + " must not be negative");
  if (!(o.checkpoint_interval > 0))
    t.fail("checkpoint_interval_s",
           "= " + significant(o.checkpoint_interval) + " must be positive");
  if (o.progress_interval < 0)
    t.fail("progress_interval_s",
           "= " + significant(o.progress_interval) + " must not be negative");
  t.finish();
}

// [measure]: the particle measurement of the pile.
void read_measure(TableReader t, sim::PileGeometrySettings& m) {
  // Counts are checked as read (64-bit), before they narrow to int.
  auto count = [&t](const char* key, int fallback, int lo, int hi) {
    const std::int64_t v = t.integer(key, fallback);
    if (v < lo || v > hi)
      t.fail(key, "= " + std::to_string(v) + " must be at least " + std::to_string(lo) +
                      " and at most " + std::to_string(hi));
    return static_cast<int>(v);
  };
  m.slice_azimuths = count("slice_azimuths", m.slice_azimuths, 8, kMaxSliceAzimuths);
  m.flank_low = t.number("flank_low", m.flank_low);
  m.flank_high = t.number("flank_high", m.flank_high);
  m.sectors = count("sectors", m.sectors, 4, kMaxSectors);
  if (!(m.flank_low >= 0 && m.flank_low < m.flank_high && m.flank_high <= 1))
    t.fail("flank_low", "= " + significant(m.flank_low) +
                            " / measure.flank_high = " + significant(m.flank_high) +
                            " must satisfy 0 <= flank_low < flank_high <= 1");
  t.finish();
}

// What the scene makes a run do, bounded before it starts: the steps up to the time limit and the
// frames written, each from several keys, so the message names them all.
void check_run_bounds(const SceneConfig& s, double dt) {
  const std::string dt_keys = s.settings.time_step > 0
                                  ? "numerics.time_step_s"
                                  : "numerics.rayleigh_fraction, the stiffness (numerics."
                                    "softened_youngs_modulus_pa or materials' youngs_modulus_pa)"
                                    " and density";
  if (!(dt > 0 && std::isfinite(dt)))
    throw InputError(s.file + ": the time step from " + dt_keys + " is " + significant(dt) +
                         " s; it must be positive and finite",
                     "numerics.time_step_s");
  const double steps = s.procedure.max_time / dt;
  if (!(steps <= kMaxSteps))
    throw InputError(s.file + ": procedure.max_time_s = " + significant(s.procedure.max_time) +
                         " s at a time step of " + significant(dt) + " s (from " + dt_keys +
                         ") is " + significant(steps) + " steps, above the limit of " +
                         significant(kMaxSteps) + "; lower the stiffness or procedure.max_time_s",
                     "procedure.max_time_s");
  const double density = s.materials[material_index(s, s.sample_material, "")].density;
  const double count = sim::expected_particle_count(s.psd.spec, s.mass, density);
  if (!(count <= kMaxParticles))
    throw InputError(
        s.file + ": sample.mass_kg = " + significant(s.mass) + " kg down to the cut-off " +
            "sample.d_min_mm = " + significant(1e3 * sim::resolve_psd(s.psd.spec).d_min) +
            " mm is about " + significant(count) + " particles, above the limit of " +
            significant(kMaxParticles) + "; raise sample.d_min_mm or lower sample.mass_kg",
        "sample.d_min_mm");
  const double every = s.output.frame_interval;
  if (every > 0 && !(s.procedure.max_time / every <= kMaxFrames))
    throw InputError(s.file + ": output.frame_interval_s = " + significant(every) +
                         " s writes up to " +
                         significant(s.procedure.max_time / std::max(every, dt)) +
                         " frames (each two or more .vtp files) in procedure.max_time_s = " +
                         significant(s.procedure.max_time) + " s, above the limit of " +
                         significant(kMaxFrames) + "; raise it to at least " +
                         significant(s.procedure.max_time / kMaxFrames) +
                         " s, lower max_time_s, or set 0 for the final state only",
                     "output.frame_interval_s");
}

// The engine's name of a setting and the scene key a user wrote for it: the engine checks the
// time step against the stability limit, which needs the particle size, so that error is the
// engine's and is told in the scene's words.
constexpr std::pair<const char*, const char*> kEngineKeys[] = {
    {"settings.time_step", "numerics.time_step_s"},
    {"settings.softened_youngs_modulus", "numerics.softened_youngs_modulus_pa"},
    {"settings.rayleigh_fraction", "numerics.rayleigh_fraction"},
    {"settings.skin", "numerics.skin_m"},
};

InputError engine_error(const std::string& file, const std::string& what) {
  for (const auto& [engine, scene] : kEngineKeys) {
    const std::string e(engine);
    if (what.compare(0, e.size(), e) == 0 && what.size() > e.size() && what[e.size()] == ' ')
      return InputError(file + ": " + scene + what.substr(e.size()), scene);
  }
  return InputError(file + ": " + what);
}

}  // namespace

SceneConfig parse_scene_table(const toml::table& doc, const std::string& file) {
  SceneConfig s;
  s.file = file;
  const std::filesystem::path dir = file == "<embedded>"
                                        ? std::filesystem::current_path()
                                        : std::filesystem::absolute(file).parent_path();
  TableReader root(doc, file);
  // The top-level tables first: a misspelt [sampel] is the mistake to name, not the missing
  // [sample] it leaves behind.
  root.known_keys({"scene", "materials", "sample", "contacts", "container", "plate", "procedure",
                   "numerics", "output", "measure"});
  read_scene_head(*root.table("scene"), s);
  read_materials(*root.table("materials"), s);
  read_sample(*root.table("sample"), s, doc, dir, file);
  read_contacts(*root.table("contacts"), s);
  read_container(*root.table("container"), s, file);
  read_plate(*root.table("plate"), s);
  check_test_contacts(s, file);
  if (auto t = root.table("procedure", true)) read_procedure(std::move(*t), s.procedure);
  // Escape limit scaled to the test: the fill lattice may stand well above a tall column.
  s.settings.escape_distance = std::max(1.0, 10.0 * s.container.height);
  if (auto t = root.table("numerics", true)) read_numerics(std::move(*t), s.settings);
  if (auto t = root.table("output", true)) read_output(std::move(*t), s.output);
  if (auto t = root.table("measure", true)) read_measure(std::move(*t), s.pile);
  root.finish();
  {  // Validate the numerics now (time step against the stability limit, pair parameters).
    const sim::ResolvedPsd psd = sim::resolve_psd(s.psd.spec);
    const auto [r_min, r_max] = grain_radius_range(s, psd.d_min, psd.d_max);
    check_run_bounds(s, build_model(s, r_min, r_max).dt);
  }
  s.resolved_toml = resolved_text(doc, s, dir);
  return s;
}

SceneConfig parse_scene_text(const std::string& text, const std::string& file) {
  return parse_scene_table(parse_toml(text, file), file);
}

SceneConfig parse_scene_file(const std::string& path) {
  std::error_code ec;  // a path the system refuses (too long, ...) does not exist either
  if (!std::filesystem::exists(path, ec))
    throw InputError(path + ": scene file does not exist" + (ec ? " (" + ec.message() + ")" : ""));
  return parse_scene_text(read_file(path), path);
}

int material_index(const SceneConfig& scene, const std::string& name, const std::string& key) {
  for (std::size_t i = 0; i < scene.materials.size(); ++i)
    if (scene.materials[i].name == name) return static_cast<int>(i);
  throw InputError(scene.file + ": " + key + " = \"" + name +
                   "\" is not a material in [materials]");
}

std::pair<double, double> grain_radius_range(const SceneConfig& scene, double d_min, double d_max) {
  if (scene.shapes.empty()) return {0.5 * d_min, 0.5 * d_max};
  double lo = std::numeric_limits<double>::infinity(), hi = 0.0;
  for (const GrainShape& g : scene.shapes) {
    for (double r : g.unit.radii) {
      lo = std::min(lo, r);
      hi = std::max(hi, r);
    }
  }
  return {lo * d_min, hi * d_max};
}

double clump_step_ratio(const SceneConfig& scene) {
  if (scene.shapes.empty()) return 1.0;
  double sphere = std::numeric_limits<double>::infinity();
  double step = std::numeric_limits<double>::infinity();
  for (const GrainShape& g : scene.shapes) {
    for (double r : g.unit.radii) sphere = std::min(sphere, r);
    step = std::min(step, std::cbrt(3.0 * g.volume_per_cube() / (4.0 * std::numbers::pi)));
  }
  return std::max(1.0, step / sphere);
}

sim::Model build_model(const SceneConfig& scene, double r_min, double r_max) {
  sim::Model m;
  m.materials = scene.materials;
  m.settings = scene.settings;
  const int n = static_cast<int>(m.materials.size());
  m.pairs.assign(n * n, sim::PairParams{});
  for (const auto& [names, p] : scene.contacts)
    m.set_pair(material_index(scene, names.first, "contacts"),
               material_index(scene, names.second, "contacts"), p);
  sim::WallSpec plate;
  plate.name = "plate";
  plate.kind = sim::WallKind::kPlane;
  plate.material = material_index(scene, scene.plate_material, "plate.material");
  m.walls.push_back(plate);
  sim::WallSpec c;
  c.name = scene.container.kind;
  c.kind = sim::WallKind::kShell;
  c.material = material_index(scene, scene.container.material, "container.material");
  c.z_bottom = scene.container.gap;
  c.z_top = scene.container.gap + scene.container.height;
  c.r_bottom = 0.5 * scene.container.bottom_diameter;
  c.r_top = 0.5 * scene.container.top_diameter;
  m.walls.push_back(c);
  // The time step comes from what is simulated: the grains' material and the walls' (an unused
  // material in [materials] changes nothing).
  m.particle_materials = {material_index(scene, scene.sample_material, "sample.material")};
  try {
    m.finalize(r_min, r_max, r_min * clump_step_ratio(scene));
  } catch (const std::invalid_argument& e) {
    throw engine_error(scene.file, e.what());
  }
  return m;
}

}  // namespace reposetwin::experiments
