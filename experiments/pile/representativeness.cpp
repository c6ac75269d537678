#include "experiments/pile/representativeness.hpp"

#include <cmath>
#include <cstdio>
#include <numbers>

#include "experiments/io/format.hpp"
#include "sim/psd.hpp"

namespace reposetwin::experiments {
namespace {

std::size_t at(RepresentativenessCheck c) { return static_cast<std::size_t>(c); }

// Height [m] of a cone of bulk volume `volume` [m^3] whose flanks rise at `angle_deg`.
double cone_height(double volume, double angle_deg) {
  const double t = std::tan(angle_deg * std::numbers::pi / 180.0);
  return std::cbrt(3.0 * volume * t * t / std::numbers::pi);
}

void check_height(Representativeness& r) {
  const RepresentativenessRules& k = r.rules;
  const double limit = k.min_height_over_d_max * r.d_max_m;
  const bool low_predicted = r.height_lo_m < limit;
  const bool low_measured = r.measured_height_m && *r.measured_height_m < limit;
  if (!low_predicted && !low_measured) return;
  std::string w = "the pile is low for its grains: ";
  if (r.measured_height_m)
    w += "H = " + printf_text("%.1f", 1e3 * *r.measured_height_m) + " mm measured (" +
         printf_text("%.1f", *r.measured_height_m / r.d_max_m) + " d_max), predicted ";
  else
    w += "predicted H = ";
  w += printf_text("%.0f", 1e3 * r.height_lo_m) + "-" + printf_text("%.0f", 1e3 * r.height_hi_m) +
       " mm (a cone of the simulated mass at " + printf_text("%.0f", k.angle_lo_deg) + "-" +
       printf_text("%.0f", k.angle_hi_deg) + " deg), against " +
       printf_text("%g", k.min_height_over_d_max) + " d_max = " + printf_text("%.0f", 1e3 * limit) +
       " mm; an angle from a pile a few grains high is not the material's. Raise sample.mass_kg "
       "(H grows as its cube root) or simulate smaller grains";
  r.warnings[at(RepresentativenessCheck::kPileHeight)] = w;
}

}  // namespace

std::vector<std::string> Representativeness::warning_list() const {
  std::vector<std::string> out;
  for (const std::string& w : warnings)
    if (!w.empty()) out.push_back(w);
  return out;
}

const char* check_word(RepresentativenessCheck c) {
  switch (c) {
    case RepresentativenessCheck::kPileHeight:
      return "pile_height";
    case RepresentativenessCheck::kMassNotSimulated:
      return "mass_not_simulated";
    case RepresentativenessCheck::kOutletWidth:
      return "outlet_width";
    case RepresentativenessCheck::kCount:
      break;
  }
  return "?";
}

Representativeness representativeness(const SceneConfig& scene,
                                      const RepresentativenessRules& rules) {
  Representativeness r;
  r.rules = rules;
  const sim::ResolvedPsd psd = sim::resolve_psd(scene.psd.spec);
  const double density =
      scene.materials[material_index(scene, scene.sample_material, "sample.material")].density;
  r.d_max_m = psd.d_max;
  const double volume = scene.mass * psd.simulated_mass_factor / (density * rules.solid_fraction);
  r.height_lo_m = cone_height(volume, rules.angle_lo_deg);
  r.height_hi_m = cone_height(volume, rules.angle_hi_deg);
  r.fines_fraction = psd.fines_fraction;
  r.scalped_fraction = psd.scalped_fraction;
  r.not_simulated_fraction = 1.0 - (1.0 - psd.scalped_fraction) * (1.0 - psd.fines_fraction);
  r.outlet_m = scene.container.bottom_diameter;
  r.outlet_over_d_max = r.outlet_m / r.d_max_m;

  check_height(r);
  if (r.not_simulated_fraction > rules.max_not_simulated)
    r.warnings[at(RepresentativenessCheck::kMassNotSimulated)] =
        printf_text("%.0f", 100.0 * r.not_simulated_fraction) +
        "% of the sieve sheet's mass is not simulated (" +
        printf_text("%.0f", 100.0 * r.fines_fraction) +
        "% finer than d_min = " + printf_text("%.3g", 1e3 * psd.d_min) + " mm, " +
        printf_text("%.0f", 100.0 * r.scalped_fraction) +
        "% above d_max = " + printf_text("%.3g", 1e3 * psd.d_max) + " mm), above " +
        printf_text("%.0f", 100.0 * rules.max_not_simulated) +
        "%: the pile is of the simulated sizes only. Lower sample.d_min_mm to simulate more of "
        "the fines (the particle count grows about as d_min^-3)";
  if (r.outlet_over_d_max < rules.min_outlet_over_d_max)
    r.warnings[at(RepresentativenessCheck::kOutletWidth)] =
        "the outlet is narrow for the grains: W / d_max = " +
        printf_text("%.2f", r.outlet_over_d_max) +
        " (W = container.bottom_diameter_m = " + printf_text("%.3g", 1e3 * r.outlet_m) +
        " mm, d_max = " + printf_text("%.3g", 1e3 * r.d_max_m) + " mm), below " +
        printf_text("%g", rules.min_outlet_over_d_max) +
        ", where the paper's Fig. 10 funnel flow arches and the outlet may jam";
  return r;
}

Representativeness representativeness(const SceneConfig& scene, double measured_height_m,
                                      const RepresentativenessRules& rules) {
  Representativeness r = representativeness(scene, rules);
  r.measured_height_m = measured_height_m;
  r.warnings[at(RepresentativenessCheck::kPileHeight)].clear();
  check_height(r);
  return r;
}

nlohmann::json to_json(const Representativeness& r) {
  nlohmann::json warnings = nlohmann::json::object();
  for (std::size_t i = 0; i < kRepresentativenessChecks; ++i)
    if (!r.warnings[i].empty())
      warnings[check_word(static_cast<RepresentativenessCheck>(i))] = r.warnings[i];
  const RepresentativenessRules& k = r.rules;
  nlohmann::json j = {
      {"d_max_m", r.d_max_m},
      {"predicted_height_m", {r.height_lo_m, r.height_hi_m}},
      {"predicted_height_angles_deg", {k.angle_lo_deg, k.angle_hi_deg}},
      {"min_height_over_d_max", k.min_height_over_d_max},
      {"mass_not_simulated_fraction", r.not_simulated_fraction},
      {"max_mass_not_simulated_fraction", k.max_not_simulated},
      {"outlet_m", r.outlet_m},
      {"outlet_over_d_max", r.outlet_over_d_max},
      {"min_outlet_over_d_max", k.min_outlet_over_d_max},
      {"warnings", warnings},
      {"rules", "H below " + printf_text("%g", k.min_height_over_d_max) +
                    " d_max (H predicted as the cone of the simulated mass at solid fraction " +
                    printf_text("%g", k.solid_fraction) + " and " +
                    printf_text("%g", k.angle_lo_deg) + "-" + printf_text("%g", k.angle_hi_deg) +
                    " deg, and measured); more than " +
                    printf_text("%g", 100.0 * k.max_not_simulated) +
                    "% of the sieve sheet's mass outside the simulated sizes; W / d_max below " +
                    printf_text("%g", k.min_outlet_over_d_max) + " (the paper's Fig. 10)"}};
  if (r.measured_height_m) j["measured_height_m"] = *r.measured_height_m;
  return j;
}

std::string representativeness_text(const Representativeness& r) {
  std::string t;
  for (const std::string& w : r.warning_list()) t += "plan: warning: " + w + "\n";
  return t;
}

}  // namespace reposetwin::experiments
