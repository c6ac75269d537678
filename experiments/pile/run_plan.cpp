#include "experiments/pile/run_plan.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "experiments/io/format.hpp"
#include "experiments/io/input_error.hpp"
#include "sim/psd.hpp"

namespace reposetwin::experiments {
namespace {

// Solid fraction of the loose fill lattice, as the scene's container check assumes.
constexpr double kLooseSolidFraction = 0.6;
// Settling inside the container before the lift, and after it (both measured on the shipped
// funnel scenes: 0.17-0.33 s and 0.15-0.65 s).
constexpr double kFillSettleS = 0.3;
constexpr double kFinalSettleS = 0.5;
// The lift empties the container before it has risen the whole fill height: material flows out
// of the outlet as it rises (measured: 0.75 of h / v on the funnel scenes).
constexpr double kLiftFraction = 0.75;

// Height [m] of a loose bulk volume [m^3] in the container (frustum or cylinder), by bisection.
double fill_height(const ContainerConfig& c, double volume) {
  const double r0 = 0.5 * c.bottom_diameter;
  const double slope = (0.5 * c.top_diameter - r0) / c.height;
  auto v = [&](double h) {
    const double r = r0 + slope * h;
    return std::numbers::pi / 3.0 * h * (r0 * r0 + r0 * r + r * r);
  };
  double lo = 0.0, hi = c.height;
  if (v(hi) <= volume) return hi;
  for (int i = 0; i < 60; ++i) (v(0.5 * (lo + hi)) < volume ? lo : hi) = 0.5 * (lo + hi);
  return 0.5 * (lo + hi);
}

}  // namespace

std::string duration_text(double seconds) {
  const auto s = static_cast<long long>(std::llround(std::max(0.0, seconds)));
  char buf[48];
  if (s >= 86400)
    std::snprintf(buf, sizeof buf, "%lldd%lldh", s / 86400, (s % 86400) / 3600);
  else if (s >= 3600)
    std::snprintf(buf, sizeof buf, "%lldh%lldm", s / 3600, (s % 3600) / 60);
  else if (s >= 60)
    std::snprintf(buf, sizeof buf, "%lldm%llds", s / 60, s % 60);
  else
    std::snprintf(buf, sizeof buf, "%llds", s);
  return buf;
}

RunPlan plan_run(const SceneConfig& scene, int threads, const PlanSettings& settings) {
  RunPlan p;
  const sim::ResolvedPsd psd = sim::resolve_psd(scene.psd.spec);
  const double density =
      scene.materials[material_index(scene, scene.sample_material, "sample.material")].density;
  // The sampler's count of spheres, turned into grains of the shape mix: shape s takes a mass
  // share f_s in grains of volume v_s d^3 against a sphere's pi/6 d^3 (as sim/psd.cpp draws).
  const double spheres = sim::expected_particle_count(scene.psd.spec, scene.mass, density);
  double grains_per_sphere = 1.0, components_per_sphere = 1.0;
  if (!scene.shapes.empty()) {
    grains_per_sphere = components_per_sphere = 0.0;
    for (const GrainShape& g : scene.shapes) {
      const double grains = std::numbers::pi / 6.0 * g.mass_fraction / g.volume_per_cube();
      grains_per_sphere += grains;
      components_per_sphere += grains * static_cast<double>(g.unit.size());
    }
  }
  p.particles = std::llround(spheres * grains_per_sphere);
  p.components = std::llround(spheres * components_per_sphere);
  p.fines_fraction = psd.fines_fraction;
  p.d_min_mm = 1e3 * psd.d_min;
  p.d_max_mm = 1e3 * psd.d_max;
  // The step of the smallest component, as the run and the scene's bounds take it: a clump's
  // spheres are smaller than its sieve size (tetrahedra of d_min: 1.9x the spheres' steps).
  const auto [r_min, r_max] = grain_radius_range(scene, psd.d_min, psd.d_max);
  p.time_step_s = build_model(scene, r_min, r_max).dt;
  const double bulk = scene.mass * psd.simulated_mass_factor / (density * kLooseSolidFraction);
  p.fill_height_m = fill_height(scene.container, bulk);
  p.simulated_time_s = std::min(
      scene.procedure.max_time,
      kFillSettleS + kFinalSettleS + kLiftFraction * p.fill_height_m / scene.procedure.lift_speed);
  p.steps = std::llround(std::ceil(p.simulated_time_s / p.time_step_s));
  p.threads = std::max(1, threads);
  p.particle_steps_per_s = settings.particle_steps_per_s_per_thread * p.threads;
  p.wall_s =
      static_cast<double>(p.steps) * static_cast<double>(p.components) / p.particle_steps_per_s;
  p.representative = representativeness(scene);
  p.psd_source = scene.psd.source;
  p.psd_note = scene.psd.note;
  return p;
}

std::string plan_text(const RunPlan& p, const PlanSettings& s) {
  const std::string grains =
      p.components == p.particles
          ? std::to_string(p.particles) + " particles"
          : std::to_string(p.particles) + " grains of " + std::to_string(p.components) +
                " spheres (clumps)";
  std::string t = "plan: " + grains + " (d " +
                  printf_text("%.3g", p.d_min_mm) + "-" + printf_text("%.3g", p.d_max_mm) +
                  " mm); " + printf_text("%.1f", 100.0 * p.fines_fraction) +
                  "% of the mass is finer than d_min and not simulated\n";
  t += "plan: dt " + printf_text("%.3g", p.time_step_s) + " s, about " +
       printf_text("%.2g", p.simulated_time_s) + " s simulated (fill height " +
       printf_text("%.0f", 1e3 * p.fill_height_m) + " mm), " + std::to_string(p.steps) + " steps\n";
  t += "plan: estimated wall time " + duration_text(p.wall_s) + " at " +
       printf_text("%.2g", p.particle_steps_per_s) + " particle-steps/s (" +
       printf_text("%.2g", s.particle_steps_per_s_per_thread) +
       " per thread, measured on whole pile " + "runs, x " + std::to_string(p.threads) +
       " thread(s))\n";
  if (!p.psd_note.empty()) t += "plan: the sieve sheet " + p.psd_source + ": " + p.psd_note + "\n";
  return t + representativeness_text(p.representative);
}

namespace {

// Why `subject` is above the limits (empty when it is not), and what shrinks it.
std::string refusal(const std::string& subject, std::int64_t particles, double wall_s,
                    double d_min_mm, double d_max_mm, const KeySource& source,
                    const PlanSettings& s) {
  std::string why;
  if (particles > s.max_particles)
    why = std::to_string(particles) + " particles is above the limit of " +
          std::to_string(s.max_particles);
  if (wall_s > s.max_wall_s)
    why += (why.empty() ? "" : " and ") + std::string("the estimated ") + duration_text(wall_s) +
           " is above the limit of " + duration_text(s.max_wall_s);
  if (why.empty()) return "";
  const double bigger = 2.0 * d_min_mm;
  const std::string example =
      bigger < 0.9 * d_max_mm
          ? ", e.g. " + how_to_set(source, "sample.d_min_mm", printf_text("%.3g", bigger))
          : "";
  return subject + " is too large to start unasked: " + why +
         ". Raise the cut-off sample.d_min_mm (now " + printf_text("%.3g", d_min_mm) +
         " mm; the count grows about as d_min^-3)" + example +
         ", or lower sample.mass_kg; or pass --yes to run it anyway";
}

}  // namespace

std::string how_to_set(const KeySource& source, const std::string& key, const std::string& value) {
  switch (source.kind) {
    case KeySource::Kind::kSetOption:
      return "--set " + key + "=" + value;
    case KeySource::Kind::kSceneFile: {
      const auto dot = key.rfind('.');
      return dot == std::string::npos
                 ? key + " = " + value + " in " + source.file
                 : key.substr(dot + 1) + " = " + value + " in [" + key.substr(0, dot) + "] of " +
                       source.file;
    }
    case KeySource::Kind::kCampaignFile:
      return "overrides = { \"" + key + "\" = " + value + " } in " + source.file;
    case KeySource::Kind::kTestSheet:
      return "a column set:" + key + " of " + value + " on every row of " + source.file +
             ", or " + key + " in the base scene";
  }
  return key + " = " + value;
}

std::string plan_refusal(const RunPlan& p, const KeySource& source, const PlanSettings& s) {
  return refusal("this run", p.particles, p.wall_s, p.d_min_mm, p.d_max_mm, source, s);
}

BatchPlan plan_batch(std::vector<BatchPlan::Part> parts, int workers) {
  BatchPlan b;
  b.workers = std::max(1, workers);
  double cpu_s = 0.0;
  for (const BatchPlan::Part& part : parts) {
    b.runs += part.runs;
    cpu_s += part.runs * part.plan.wall_s;
  }
  b.wall_s = cpu_s / std::min(b.workers, std::max(1, b.runs));
  b.parts = std::move(parts);
  return b;
}

std::string plan_text(const BatchPlan& b, const PlanSettings& s) {
  std::string t = "plan: at most " + std::to_string(b.runs) + " pile runs, " +
                  std::to_string(b.workers) + " at a time: estimated wall time " +
                  duration_text(b.wall_s) + " (simulation; the photographs add seconds a run)\n";
  for (const BatchPlan::Part& part : b.parts) {
    t += "plan: " + std::to_string(part.runs) + " x " + part.what + ", each:\n";
    const std::string one = plan_text(part.plan, s);
    std::size_t from = 0;
    while (from < one.size()) {
      const std::size_t end = one.find('\n', from);
      t += "  " + one.substr(from, end == std::string::npos ? std::string::npos : end - from + 1);
      if (end == std::string::npos) break;
      from = end + 1;
    }
  }
  return t;
}

std::string plan_refusal(const BatchPlan& b, const KeySource& source, const PlanSettings& s) {
  const RunPlan* largest = nullptr;
  for (const BatchPlan::Part& part : b.parts)
    if (!largest || part.plan.particles > largest->particles) largest = &part.plan;
  if (!largest) return "";
  return refusal("this batch of " + std::to_string(b.runs) + " runs", largest->particles,
                 b.wall_s, largest->d_min_mm, largest->d_max_mm, source, s);
}

}  // namespace reposetwin::experiments
