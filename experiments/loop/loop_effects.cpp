#include "experiments/loop/loop_effects.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

#include "experiments/io/format.hpp"
#include "experiments/io/overrides.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/io/scene_overrides.hpp"
#include "sim/psd.hpp"

namespace reposetwin::experiments {
using nlohmann::json;

namespace {

std::vector<std::string> sets_of(const LabTest& t) {
  std::vector<std::string> s;
  for (const auto& [k, v] : t.overrides) s.push_back(k + "=" + v);
  return s;
}

std::vector<Override> overrides_of(const LabTest& t) {
  std::vector<Override> o;
  for (const auto& [k, v] : t.overrides) o.push_back({k, v});
  return o;
}

// The test's scene with its overrides applied, for values read by key path.
SceneDoc resolved_doc(const LabTest& t) {
  return SceneDoc(t.scene_path, overrides_of(t), t.scene_path);
}

// "contacts.{sample}-{plate}.friction" -> "contacts.rock-plate.friction" (or plate-rock, whichever
// the scene file names).
std::string resolve_key(const LabTest& t, const std::string& key) {
  if (key.find('{') == std::string::npos) return key;
  const SceneConfig scene = load_scene(t.scene_path, sets_of(t));
  auto sub = [](std::string s, const std::string& from, const std::string& to) {
    for (auto p = s.find(from); p != std::string::npos; p = s.find(from, p + to.size()))
      s.replace(p, from.size(), to);
    return s;
  };
  std::string k = sub(sub(key, "{sample}", scene.sample_material), "{plate}", scene.plate_material);
  if (k.rfind("contacts.", 0) == 0) {
    const auto dot = k.find('.', 9);
    const std::string pair = k.substr(9, dot - 9);
    const auto dash = pair.find('-');
    const std::string swapped = pair.substr(dash + 1) + "-" + pair.substr(0, dash);
    const SceneDoc doc = resolved_doc(t);
    if (!doc.has("contacts." + pair) && doc.has("contacts." + swapped))
      k = "contacts." + swapped + k.substr(dot);
  }
  return k;
}

}  // namespace

namespace {

// The rows of the physics the pile test may lack: its contacts, its procedure and its sample's
// sizes.
std::vector<CandidateEffect> pile_rows() {
  using enum EffectApply;
  return {
      {.name = "plate_friction", .apply = kSetScene, .key = "contacts.{sample}-{plate}.friction",
       .off = 0.0, .off_from_scene = true, .probe = 0.15, .lo = 0.0, .hi = 1.5, .units = "-",
       .description =
           "Sliding friction of the sample on the base plate differs from the declared value "
           "(smooth or dusted board); shows most on small piles and as a step between plates."},
      {.name = "cohesion", .apply = kSetScene,
       .key = "contacts.{sample}-{sample}.cohesion_energy_density", .off = 0.0, .probe = 10000.0,
       .lo = 0.0, .hi = 1e6, .units = "J/m^3",
       .description =
           "Cohesion between particles (simplified JKR, moisture or clay coating); steepens the "
           "piles beyond what rolling friction reaches (on the loop's 3-5 layer test piles the "
           "heavier ones most) and, strong enough, makes grains hang in the funnel."},
      {.name = "rolling_size", .apply = kSetScene,
       .key = "contacts.{sample}-{sample}.rolling_size_exponent", .off = 0.0, .probe = 1.0,
       .lo = -3.0, .hi = 3.0, .units = "-",
       .description =
           "Rolling resistance that varies with particle size, mu_r (d / d_ref)^alpha with d_ref "
           "the calibration tests' typical grain (shape differs between fine and coarse grains); "
           "shows between samples of different size bands (d_min, d_max).",
       .companions = {{"contacts.{sample}-{sample}.rolling_reference_diameter_m", "{d_ref}"}},
       .needs_size_contrast = true},
      {.name = "restitution", .apply = kSetScene, .key = "contacts.{sample}-{sample}.restitution",
       .off = 0.0, .off_from_scene = true, .probe = 0.4, .lo = 0.05, .hi = 0.95, .units = "-",
       .description =
           "The grains lose more energy per collision than the declared pair restitution: a "
           "sphere standing in for an angular rock lacks the rocking and corner impacts by which "
           "the rock dissipates in a flowing pile, so its effective restitution lies below the "
           "value of a drop test; a lower one lets the collapsing column stop sooner, with a "
           "higher, more pointed pile (issue 37's study: 0.79 to 0.3 raised sample 4's "
           "atan(2H/D) by 3.8 deg at mu_r 0.4; the plate's restitution moved it by none).",
       .opt_in = true},
      {.name = "lift_speed", .apply = kFactorScene, .key = "procedure.lift_speed_m_s", .off = 1.0,
       .probe = 4.0, .lo = 0.1, .hi = 20.0, .units = "x declared",
       .description = "The container was lifted faster (or slower) than declared; above a "
                      "quasi-static speed the angle drops."},
      {.name = "fines", .apply = kFactorScene, .key = "sample.d_min_mm", .off = 1.0, .probe = 0.7,
       .lo = 0.2, .hi = 1.0, .units = "x declared d_min",
       .description = "Fines below the simulated cut-off d_min take part (d_min lowered by this "
                      "factor)."},
  };
}

// The rows of how the lab's photographs may have been taken other than declared.
std::vector<CandidateEffect> photo_rows() {
  using enum EffectApply;
  const EffectKind kind = EffectKind::kMeasurement;
  return {
      {.name = "camera_height", .kind = kind, .apply = kImageHeight,
       .key = "image.camera_height_m", .off = 0.0, .probe = 0.005, .lo = 0.0, .hi = 1.0,
       .units = "m",
       .description = "The photographs were taken from above plate level while measured as if "
                      "level (perspective grows with height over distance)."},
      {.name = "camera_pose", .kind = kind, .apply = kImagePose,
       .key = "image.camera_pose_height_m", .off = 0.0, .probe = 0.01, .lo = 0.0, .hi = 1.0,
       .units = "m",
       .description =
           "The photographs were taken from above the plate with the camera pitched down at the "
           "pile's foot, as a person holds a camera, while measured as if level (pitch "
           "atan(h / distance)).",
       .opt_in = true},
      {.name = "lens_k1", .kind = kind, .apply = kImageK1, .key = "image.k1", .off = 0.0,
       .probe = -0.1, .lo = -0.25, .hi = 0.25, .units = "-",
       .description = "Radial lens distortion of the lab camera, measured as if undistorted."},
  };
}

// The row of the grains' shape, which spheres lack.
CandidateEffect shape_row() {
  return {.name = "grain_shape", .apply = EffectApply::kShape, .key = "sample.shape.elongation",
          .off = 1.0, .probe = 1.5, .lo = 1.0, .hi = 3.0, .units = "L/I",
          .description =
              "The grains are elongated, not round: every grain a rod of four spheres with this "
              "elongation L/I (sieve size its intermediate extent); the paper names grain shape "
              "for the gap between sphere piles and its rock.",
          .opt_in = true};
}

}  // namespace

const std::vector<CandidateEffect>& candidate_effects() {
  static const std::vector<CandidateEffect> k = [] {
    std::vector<CandidateEffect> rows = pile_rows();
    for (CandidateEffect& e : photo_rows()) rows.push_back(std::move(e));
    rows.push_back(shape_row());
    return rows;
  }();
  return k;
}

const CandidateEffect& find_effect(const std::string& name) {
  std::string known;
  for (const auto& e : candidate_effects()) {
    if (e.name == name) return e;
    known += " " + e.name;
  }
  throw std::invalid_argument("unknown candidate effect \"" + name + "\" (known:" + known + ")");
}

double median_grain_diameter(const LabTest& t) {
  const SceneConfig s = load_scene(t.scene_path, sets_of(t));
  const sim::ResolvedPsd psd = sim::resolve_psd(s.psd.spec);
  const sim::SieveTable& table = s.psd.spec.table;
  // Percent passing at the cut sizes; the simulated mass is what lies between them.
  const double lo = sim::percent_passing(table, psd.d_min);
  const double hi = sim::percent_passing(table, psd.d_max);
  const double half = 0.5 * (lo + hi);
  std::vector<double> size = {psd.d_min}, pass = {lo};
  for (std::size_t k = 0; k < table.size.size(); ++k)
    if (table.size[k] > psd.d_min && table.size[k] < psd.d_max) {
      size.push_back(table.size[k]);
      pass.push_back(table.passing[k]);
    }
  size.push_back(psd.d_max);
  pass.push_back(hi);
  for (std::size_t k = 0; k + 1 < size.size(); ++k)
    if (pass[k + 1] >= half && pass[k + 1] > pass[k])
      return size[k] + (half - pass[k]) / (pass[k + 1] - pass[k]) * (size[k + 1] - size[k]);
  return psd.d_max;
}

double reference_grain_diameter(const std::vector<LabTest>& tests) {
  if (tests.empty()) throw std::invalid_argument("reference_grain_diameter: no tests");
  double log_sum = 0.0;
  int n = 0;
  for (const LabTest& t : tests)
    if (t.role == Role::kCalibrate) log_sum += std::log(median_grain_diameter(t)), ++n;
  if (n == 0)
    for (const LabTest& t : tests) log_sum += std::log(median_grain_diameter(t)), ++n;
  return std::exp(log_sum / n);
}

double scene_value(const LabTest& t, const std::string& key_pattern) {
  const std::string key = resolve_key(t, key_pattern);
  if (key == "sample.d_min_mm" || key == "procedure.lift_speed_m_s") {
    const SceneConfig s = load_scene(t.scene_path, sets_of(t));
    return key == "sample.d_min_mm" ? 1e3 * s.psd.spec.d_min : s.procedure.lift_speed;
  }
  if (auto v = resolved_doc(t).number(key)) return *v;
  throw InputError(t.scene_path + " (test " + t.id + "): scene key " + key +
                   " has no numeric value");
}

std::vector<std::string> split_keys(const std::string& keys) {
  std::vector<std::string> out;
  std::string k;
  std::stringstream ss(keys);
  while (std::getline(ss, k, ','))
    if (!k.empty()) out.push_back(k);
  return out;
}

void check_mu_key(const LabTest& test, const std::string& mu_key) {
  const std::vector<std::string> keys = split_keys(mu_key);
  if (keys.empty()) throw InputError("mu_key: no scene key given");
  for (const std::string& k : keys) {
    try {
      (void)scene_value(test, k);
    } catch (const std::exception& e) {
      throw InputError("mu_key " + k + " (test " + test.id + "): " + e.what());
    }
  }
}

SimRequest make_request(const LabTest& test, const std::string& mu_key, double mu_r,
                        std::uint64_t seed, const std::vector<EffectSetting>& effects,
                        const ImageVariant& base_image) {
  SimRequest r;
  r.test = &test;
  r.seed = seed;
  r.image = base_image;
  if (base_image.use_lab_cameras && !test.cameras.empty()) r.image.lab_cameras = test.cameras;
  if (test.camera_height_m) {
    r.image.camera_height_m = *test.camera_height_m;
    r.image.declared_height_m = *test.camera_height_m;
  }
  for (const std::string& k : split_keys(mu_key))
    r.extra.emplace_back(resolve_key(test, k), toml_float(mu_r, 12));
  for (const EffectSetting& s : effects) {
    const CandidateEffect& e = *s.effect;
    switch (e.apply) {
      case EffectApply::kSetScene:
        r.extra.emplace_back(resolve_key(test, e.key), toml_float(s.value, 12));
        for (const auto& [k, v] : e.companions) {
          if (v != "{d_ref}") {
            r.extra.emplace_back(resolve_key(test, k), v);
            continue;
          }
          const double d_ref = test.reference_diameter_m > 0.0 ? test.reference_diameter_m
                                                                : median_grain_diameter(test);
          r.extra.emplace_back(resolve_key(test, k), toml_float(d_ref, 12));
        }
        break;
      case EffectApply::kFactorScene:
        r.extra.emplace_back(resolve_key(test, e.key),
                             toml_float(s.value * scene_value(test, e.key), 12));
        break;
      case EffectApply::kImageHeight:
        r.image.camera_height_m = r.image.declared_height_m + s.value;
        break;
      case EffectApply::kImagePose:
        // At 0 the base model's level camera and framing, so the off value is the baseline.
        r.image.camera_height_m = r.image.declared_height_m + s.value;
        r.image.aim_at_axis_foot = s.value != 0.0;
        break;
      case EffectApply::kImageK1:
        r.image.k1 = r.image.declared_k1 + s.value;
        break;
      case EffectApply::kShape:
        r.extra.emplace_back("sample.shape",
                             "{name = \"elongated\", kind = \"generated\", "
                             "elongation = " +
                                 toml_float(s.value, 12) +
                                 ", spheres = " + std::to_string(kShapeSpheres) + "}");
        break;
    }
  }
  return r;
}

std::string effect_unavailable(const LabTest& test, const CandidateEffect& e) {
  if (e.kind == EffectKind::kMeasurement) return "";
  try {
    if (e.key.find("{plate}") != std::string::npos) {
      const SceneConfig s = load_scene(test.scene_path, sets_of(test));
      if (s.plate_material == s.sample_material)
        return "the plate is made of the sample's material (" + s.plate_material +
               "), so its friction cannot differ";
    }
    if (e.apply == EffectApply::kShape && !load_scene(test.scene_path, sets_of(test)).shapes.empty())
      return "the scene declares its own grain shapes";
    // A factor on a declared value of 0 (no simulated cut-off d_min) changes nothing: its
    // fingerprint would be zero and its simulations a waste.
    if (e.apply == EffectApply::kFactorScene && scene_value(test, e.key) == 0.0)
      return "the declared " + e.key + " is 0, so a factor on it changes nothing";
    const SimRequest r = make_request(test, "contacts.{sample}-{sample}.rolling_friction", 0.1, 1,
                                      {{&e, e.probe}}, ImageVariant{});
    (void)load_scene(test.scene_path, resolved_overrides(r));
  } catch (const std::exception& ex) {
    return ex.what();
  }
  return "";
}

std::string effect_unidentifiable(const std::vector<LabTest>& tests, const CandidateEffect& e) {
  if (!e.needs_size_contrast || tests.size() < 2) return "";
  auto intervals = [](const LabTest& t) {
    return sim::resolve_psd(load_scene(t.scene_path, sets_of(t)).psd.spec).intervals;
  };
  // Sizes in metres and fractions near 1: one absolute tolerance serves both.
  auto same = [](const sim::PsdInterval& a, const sim::PsdInterval& b) {
    return std::abs(a.lower - b.lower) <= 1e-12 && std::abs(a.upper - b.upper) <= 1e-12 &&
           std::abs(a.mass_fraction - b.mass_fraction) <= 1e-9;
  };
  const std::vector<sim::PsdInterval> first = intervals(tests.front());
  for (std::size_t i = 1; i < tests.size(); ++i) {
    const std::vector<sim::PsdInterval> other = intervals(tests[i]);
    if (!std::equal(first.begin(), first.end(), other.begin(), other.end(), same)) return "";
  }
  return "every test simulates the same size distribution (" +
         significant(1e3 * first.front().lower, 3) + "-" + significant(1e3 * first.back().upper, 3) +
         " mm), so a size-dependent rolling resistance is a change of mu_r, which the "
         "calibration takes up; tests of different size bands (d_min, d_max or another PSD) "
         "tell them apart";
}

json to_json(const CandidateEffect& e) {
  return {{"name", e.name},
          {"kind", e.kind == EffectKind::kPhysics ? "physics" : "measurement"},
          {"key", e.key},
          {"off", e.off_from_scene ? json("scene value") : json(e.off)},
          {"probe", e.probe},
          {"range", {e.lo, e.hi}},
          {"units", e.units},
          {"opt_in", e.opt_in},
          {"description", e.description}};
}

}  // namespace reposetwin::experiments
