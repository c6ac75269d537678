#include "experiments/pile/pile_record.hpp"

#include <algorithm>
#include <numbers>
#include <stdexcept>
#include <utility>

#include "experiments/io/json_fields.hpp"
#include "sim/contact.hpp"

namespace reposetwin::experiments {
using nlohmann::json;

namespace {

constexpr double kRadToDeg = 180.0 / std::numbers::pi;

// The status of a pile record whose run ended in no pile to measure (a physics stop).
constexpr const char* kNotMeasured = "not measured";

constexpr const char* kMethodHd =
    "theta = atan(2H/D), H = top of the highest pile particle, D = 2 x median over azimuth "
    "sectors of the footprint's furthest reach";
constexpr const char* kMethodSlice =
    "protractor: line fit to each flank between 20% and 80% of H on vertical slices through the "
    "pile centre, averaged over azimuths";

sim::PileStatus pile_status_from(const std::string& s) {
  for (sim::PileStatus p :
       {sim::PileStatus::kOk, sim::PileStatus::kNoPile, sim::PileStatus::kNoFlanks})
    if (sim::to_string(p) == s) return p;
  throw std::invalid_argument("pile.status: unknown value \"" + s + "\"");
}

sim::FinesPolicy fines_policy_from(const std::string& s) {
  for (sim::FinesPolicy p : {sim::FinesPolicy::kRenormalise, sim::FinesPolicy::kDrop})
    if (sim::to_string(p) == s) return p;
  throw std::invalid_argument("psd.fines_policy: unknown value \"" + s + "\"");
}

template <typename T>
std::optional<T> optional_field(const json& j, const char* key) {
  if (!j.contains(key) || j.at(key).is_null()) return std::nullopt;
  return j.at(key).get<T>();
}

}  // namespace

// ---- stop ----------------------------------------------------------------------------------

std::string stop_reason_text(const RunStop& stop) {
  switch (stop.reason) {
    case StopReason::kSettled:
      return "settled";
    case StopReason::kSettleTimeLimit:
      return "settle time limit";
    case StopReason::kTimeLimit:
      return "time limit";
    case StopReason::kClogged:
      return "clogged";
    case StopReason::kPhysics:
      return std::string("physics: ") + sim::status_name(stop.physics);
  }
  throw std::logic_error("stop_reason_text: unknown reason");
}

RunStop stop_from_json(const json& j) {
  RunStop s;
  const std::string reason = j.at("reason").get<std::string>();
  s.detail = j.value("detail", std::string());
  s.likely_cause = j.value("likely_cause", std::string());
  for (StopReason r : {StopReason::kSettled, StopReason::kSettleTimeLimit, StopReason::kTimeLimit,
                       StopReason::kClogged}) {
    s.reason = r;
    if (stop_reason_text(s) == reason) return s;
  }
  s.reason = StopReason::kPhysics;
  for (sim::Status st : {sim::Status::kNan, sim::Status::kOverlap, sim::Status::kEscaped}) {
    s.physics = st;
    if (stop_reason_text(s) == reason) return s;
  }
  throw std::invalid_argument("stop.reason: unknown value \"" + reason + "\"");
}

json to_json(const RunStop& stop) {
  json j = {{"reason", stop_reason_text(stop)}, {"detail", stop.detail}};
  if (!stop.likely_cause.empty()) j["likely_cause"] = stop.likely_cause;
  return j;
}

// ---- pile ----------------------------------------------------------------------------------

PileMeasure pile_measure(const sim::PileGeometry& g) {
  PileMeasure p;
  p.status = g.status;
  p.height_m = g.height;
  p.base_diameter_m = g.base_diameter;
  p.theta_hd_deg = g.theta_hd * kRadToDeg;
  p.slice_angle_mean_deg = g.slice_angle_mean * kRadToDeg;
  p.slice_angle_sd_deg = g.slice_angle_sd * kRadToDeg;
  p.flank_angle_sd_deg = g.flank_angle_sd * kRadToDeg;
  p.valid_slices = g.valid_slices;
  p.equal_area_angle_deg = g.equal_area_angle * kRadToDeg;
  p.centre_of_mass_angle_deg = g.centre_of_mass_angle * kRadToDeg;
  p.centre_x_m = g.centre.x();
  p.centre_y_m = g.centre.y();
  p.pile_count = static_cast<std::int64_t>(g.pile_count);
  p.footprint_count = static_cast<std::int64_t>(g.footprint_count);
  p.stray_count = static_cast<std::int64_t>(g.stray_count);
  p.median_diameter_m = g.median_diameter;
  for (const sim::PileSlice& s : g.slices)
    p.slices.push_back(
        {s.azimuth * kRadToDeg, s.valid, s.angle * kRadToDeg, s.equal_area_angle * kRadToDeg});
  return p;
}

PileMeasure clogged_pile(std::int64_t lodged, const std::string& detail) {
  PileMeasure p;
  p.status = sim::PileStatus::kNoPile;
  p.clogged = true;
  p.lodged = lodged;
  p.detail = detail;
  return p;
}

PileMeasure unmeasured_pile(const std::string& detail) {
  PileMeasure p;
  p.status = sim::PileStatus::kNoPile;
  p.not_measured = true;
  p.detail = detail;
  return p;
}

json to_json(const PileMeasure& p) {
  if (p.not_measured)
    return {{"status", kNotMeasured},
            {"detail", p.detail},
            {"theta_hd_deg", 0.0},
            {"slice_angle_mean_deg", 0.0}};
  if (p.clogged)
    return {{"status", sim::to_string(p.status)},
            {"detail", p.detail},
            {"theta_hd_deg", 0.0},
            {"slice_angle_mean_deg", 0.0},
            {"lodged_particles", p.lodged}};
  json slices = json::array();
  for (const PileSliceRecord& s : p.slices)
    slices.push_back({{"azimuth_deg", s.azimuth_deg},
                      {"valid", s.valid},
                      {"angle_deg", s.angle_deg},
                      {"equal_area_angle_deg", s.equal_area_angle_deg}});
  return {{"status", sim::to_string(p.status)},
          {"method_hd", kMethodHd},
          {"method_slice", kMethodSlice},
          {"height_m", p.height_m},
          {"base_diameter_m", p.base_diameter_m},
          {"theta_hd_deg", p.theta_hd_deg},
          {"slice_angle_mean_deg", p.slice_angle_mean_deg},
          {"slice_angle_sd_deg", p.slice_angle_sd_deg},
          {"flank_angle_sd_deg", p.flank_angle_sd_deg},
          {"valid_slices", p.valid_slices},
          {"equal_area_angle_deg", p.equal_area_angle_deg},
          {"centre_of_mass_angle_deg", p.centre_of_mass_angle_deg},
          {"centre_m", {p.centre_x_m, p.centre_y_m}},
          {"pile_count", p.pile_count},
          {"footprint_count", p.footprint_count},
          {"stray_count", p.stray_count},
          {"median_diameter_m", p.median_diameter_m},
          {"slices", slices}};
}

PileMeasure pile_measure_from_json(const json& j) {
  if (j.value("status", std::string()) == kNotMeasured)
    return unmeasured_pile(j.value("detail", std::string()));
  if (j.contains("lodged_particles"))
    return clogged_pile(j.at("lodged_particles").get<std::int64_t>(),
                        j.value("detail", std::string()));
  PileMeasure p;
  p.status = pile_status_from(j.at("status").get<std::string>());
  p.height_m = json_number(j, "height_m");
  p.base_diameter_m = json_number(j, "base_diameter_m");
  p.theta_hd_deg = json_number(j, "theta_hd_deg");
  p.slice_angle_mean_deg = json_number(j, "slice_angle_mean_deg");
  p.slice_angle_sd_deg = json_number(j, "slice_angle_sd_deg");
  p.flank_angle_sd_deg = json_number(j, "flank_angle_sd_deg");
  p.valid_slices = j.value("valid_slices", 0);
  p.equal_area_angle_deg = json_number(j, "equal_area_angle_deg");
  p.centre_of_mass_angle_deg = json_number(j, "centre_of_mass_angle_deg");
  if (j.contains("centre_m")) {
    p.centre_x_m = j.at("centre_m").at(0);
    p.centre_y_m = j.at("centre_m").at(1);
  }
  p.pile_count = j.value("pile_count", std::int64_t{0});
  p.footprint_count = j.value("footprint_count", std::int64_t{0});
  p.stray_count = j.value("stray_count", std::int64_t{0});
  p.median_diameter_m = json_number(j, "median_diameter_m");
  for (const json& sl : j.value("slices", json::array()))
    p.slices.push_back(
        {sl.at("azimuth_deg"), sl.at("valid"), sl.at("angle_deg"), sl.at("equal_area_angle_deg")});
  return p;
}

// ---- PSD -----------------------------------------------------------------------------------

PsdRecord psd_record(const sim::PsdSummary& s, const std::string& source, const std::string& name,
                     const std::string& provenance, const std::string& assumption) {
  PsdRecord p;
  p.source = source;
  p.name = name;
  p.provenance = provenance;
  p.assumption = assumption;
  p.target_mass_kg = s.target_mass;
  p.simulated_target_mass_kg = s.simulated_target_mass;
  p.drawn_mass_kg = s.drawn_mass;
  p.count = static_cast<std::int64_t>(s.count);
  p.d_min_mm = s.d_min * 1e3;
  p.d_max_mm = s.d_max * 1e3;
  p.d_min_drawn_mm = s.d_min_drawn * 1e3;
  p.d_max_drawn_mm = s.d_max_drawn * 1e3;
  p.fines_fraction_not_simulated = s.fines_fraction;
  p.scalped_fraction = s.scalped_fraction;
  p.fines_policy = s.fines;
  for (const auto& iv : s.intervals)
    p.intervals.push_back({iv.lower * 1e3, iv.upper * 1e3, iv.target_mass_fraction,
                           iv.drawn_mass_fraction, static_cast<std::int64_t>(iv.count)});
  return p;
}

json to_json(const PsdRecord& p) {
  json intervals = json::array();
  for (const PsdIntervalRecord& iv : p.intervals)
    intervals.push_back({{"lower_mm", iv.lower_mm},
                         {"upper_mm", iv.upper_mm},
                         {"target_mass_fraction", iv.target_mass_fraction},
                         {"drawn_mass_fraction", iv.drawn_mass_fraction},
                         {"count", iv.count}});
  return {{"source", p.source},
          {"name", p.name},
          {"provenance", p.provenance},
          {"assumption", p.assumption},
          {"target_mass_kg", p.target_mass_kg},
          {"simulated_target_mass_kg", p.simulated_target_mass_kg},
          {"drawn_mass_kg", p.drawn_mass_kg},
          {"count", p.count},
          {"d_min_mm", p.d_min_mm},
          {"d_max_mm", p.d_max_mm},
          {"d_min_drawn_mm", p.d_min_drawn_mm},
          {"d_max_drawn_mm", p.d_max_drawn_mm},
          {"fines_fraction_not_simulated", p.fines_fraction_not_simulated},
          {"scalped_fraction", p.scalped_fraction},
          {"fines_policy", sim::to_string(p.fines_policy)},
          {"intervals", intervals}};
}

PsdRecord psd_record_from_json(const json& j) {
  PsdRecord p;
  p.source = j.at("source");
  p.name = j.at("name");
  p.provenance = j.at("provenance");
  p.assumption = j.at("assumption");
  p.target_mass_kg = j.at("target_mass_kg");
  p.simulated_target_mass_kg = j.at("simulated_target_mass_kg");
  p.drawn_mass_kg = j.at("drawn_mass_kg");
  p.count = j.at("count");
  p.d_min_mm = j.at("d_min_mm");
  p.d_max_mm = j.at("d_max_mm");
  p.d_min_drawn_mm = j.at("d_min_drawn_mm");
  p.d_max_drawn_mm = j.at("d_max_drawn_mm");
  p.fines_fraction_not_simulated = j.at("fines_fraction_not_simulated");
  p.scalped_fraction = j.at("scalped_fraction");
  p.fines_policy = fines_policy_from(j.at("fines_policy").get<std::string>());
  for (const json& iv : j.at("intervals"))
    p.intervals.push_back({iv.at("lower_mm"), iv.at("upper_mm"), iv.at("target_mass_fraction"),
                           iv.at("drawn_mass_fraction"), iv.at("count")});
  return p;
}

// ---- events --------------------------------------------------------------------------------

RunEvent run_event(double t, std::string what, std::optional<std::int64_t> particles,
                   std::optional<std::string> code_version) {
  RunEvent e;
  e.t = t;
  e.event = std::move(what);
  e.particles = particles;
  e.code_version = std::move(code_version);
  return e;
}

json to_json(const RunEvent& e) {
  json j = {{"t", e.t}, {"event", e.event}};
  if (e.particles) j["particles"] = *e.particles;
  if (e.code_version) j["code_version"] = *e.code_version;
  return j;
}

RunEvent run_event_from_json(const json& j) {
  return run_event(j.at("t"), j.at("event"), optional_field<std::int64_t>(j, "particles"),
                   optional_field<std::string>(j, "code_version"));
}

json to_json(const std::vector<RunEvent>& events) {
  json a = json::array();
  for (const RunEvent& e : events) a.push_back(to_json(e));
  return a;
}

std::vector<RunEvent> run_events_from_json(const json& j) {
  std::vector<RunEvent> events;
  for (const json& e : j) events.push_back(run_event_from_json(e));
  return events;
}

// ---- provenance ----------------------------------------------------------------------------

json to_json(const RunProvenance& p) {
  json j = {{"scene_file", p.scene_file},
            {"scene_name", p.scene_name},
            {"seed", p.seed},
            {"code_version", p.code_version},
            {"engine_version", p.engine_version},
            {"time_step_s", p.time_step_s},
            {"rayleigh_time_s", p.rayleigh_time_s},
            {"rayleigh_fraction", p.time_step_s / p.rayleigh_time_s},
            {"softened_youngs_modulus_pa",
             p.softened_youngs_modulus_pa ? json(*p.softened_youngs_modulus_pa) : json(nullptr)},
            {"youngs_modulus_real_pa", p.youngs_modulus_real_pa},
            {"threads", p.threads},
            {"rolling_models", json::array()},
            {"created_utc", p.created_utc}};
  // The rolling laws' exact definitions, so a reader can convert mu_r between conventions.
  for (const auto& row : sim::kRollingModels)
    j["rolling_models"].push_back({{"keyword", row.keyword},
                                   {"torque", row.torque},
                                   {"radius", row.radius},
                                   {"angular_velocity", row.angular_velocity}});
  for (auto it = p.extra.begin(); it != p.extra.end(); ++it) j[it.key()] = it.value();
  return j;
}

RunProvenance run_provenance_from_json(const json& j) {
  static const char* const kOwn[] = {"scene_file",
                                     "scene_name",
                                     "seed",
                                     "code_version",
                                     "engine_version",
                                     "time_step_s",
                                     "rayleigh_time_s",
                                     "rayleigh_fraction",
                                     "softened_youngs_modulus_pa",
                                     "youngs_modulus_real_pa",
                                     "threads",
                                     "rolling_models",
                                     "created_utc"};
  RunProvenance p;
  p.scene_file = j.value("scene_file", std::string());
  p.scene_name = j.value("scene_name", std::string());
  p.seed = j.value("seed", std::uint64_t{0});
  p.code_version = j.value("code_version", std::string());
  p.engine_version = j.value("engine_version", std::string());
  p.time_step_s = json_number(j, "time_step_s");
  p.rayleigh_time_s = json_number(j, "rayleigh_time_s");
  p.softened_youngs_modulus_pa = optional_field<double>(j, "softened_youngs_modulus_pa");
  p.youngs_modulus_real_pa = json_number(j, "youngs_modulus_real_pa");
  p.threads = j.value("threads", 0);
  p.created_utc = j.value("created_utc", std::string());
  for (auto it = j.begin(); it != j.end(); ++it)
    if (std::find(std::begin(kOwn), std::end(kOwn), it.key()) == std::end(kOwn))
      p.extra[it.key()] = it.value();
  return p;
}

// ---- counts and performance ---------------------------------------------------------------

json to_json(const ParticleCounts& c) {
  return {{"initial", c.initial},
          {"final", c.final},
          {"retained_in_container", c.retained_in_container},
          {"retained_mass_kg", c.retained_mass_kg}};
}

ParticleCounts particle_counts_from_json(const json& j) {
  return {j.value("initial", std::int64_t{0}), j.value("final", std::int64_t{0}),
          j.value("retained_in_container", std::int64_t{0}), json_number(j, "retained_mass_kg")};
}

json to_json(const RunPerformance& p) {
  return {{"steps", p.steps},
          {"wall_s", p.wall_s},
          {"cpu_s", p.cpu_s},
          {"particle_steps_per_s", p.particle_steps_per_s},
          {"neighbor_builds", p.neighbor_builds},
          {"max_overlap_ratio_seen", p.max_overlap_ratio_seen}};
}

RunPerformance run_performance_from_json(const json& j) {
  return {j.value("steps", std::int64_t{0}), json_number(j, "wall_s"), json_number(j, "cpu_s"),
          json_number(j, "particle_steps_per_s"), j.value("neighbor_builds", std::int64_t{0}),
          json_number(j, "max_overlap_ratio_seen")};
}

namespace {
json pile_run_json(const PileRun& r);  // the fields of every pile run's result
}  // namespace

// ---- grain shapes -------------------------------------------------------------------------

json to_json(const ShapeRecord& s) {
  json shapes = json::array();
  for (const GrainShapeRecord& g : s.shapes)
    shapes.push_back({{"name", g.name},
                      {"kind", g.kind},
                      {"target_mass_fraction", g.target_mass_fraction},
                      {"drawn_mass_fraction", g.drawn_mass_fraction},
                      {"count", g.count},
                      {"components", g.components},
                      {"elongation", g.elongation},
                      {"flatness", g.flatness},
                      {"roundness", g.roundness},
                      {"angularity", g.angularity},
                      {"measured_elongation", g.measured_elongation},
                      {"measured_flatness", g.measured_flatness},
                      {"volume_per_cube", g.volume_per_cube},
                      {"outlet_diameter", g.outlet_diameter}});
  return {{"grains", "clumps"},
          {"sieve_convention", s.sieve_convention},
          {"shapes", shapes},
          {"bodies_initial", s.bodies_initial},
          {"bodies_final", s.bodies_final},
          {"components_initial", s.components_initial},
          {"components_final", s.components_final}};
}

ShapeRecord shape_record_from_json(const json& j) {
  ShapeRecord s;
  s.sieve_convention = j.value("sieve_convention", std::string());
  for (const json& g : j.at("shapes")) {
    GrainShapeRecord r;
    r.name = g.at("name");
    r.kind = g.at("kind");
    r.target_mass_fraction = json_number(g, "target_mass_fraction");
    r.drawn_mass_fraction = json_number(g, "drawn_mass_fraction");
    r.count = g.value("count", std::int64_t{0});
    r.components = g.value("components", 0);
    r.elongation = json_number(g, "elongation", 1.0);
    r.flatness = json_number(g, "flatness", 1.0);
    r.roundness = json_number(g, "roundness", 1.0);
    r.angularity = json_number(g, "angularity", 0.0);
    r.measured_elongation = json_number(g, "measured_elongation", 1.0);
    r.measured_flatness = json_number(g, "measured_flatness", 1.0);
    r.volume_per_cube = json_number(g, "volume_per_cube");
    r.outlet_diameter = json_number(g, "outlet_diameter");
    s.shapes.push_back(r);
  }
  s.bodies_initial = j.value("bodies_initial", std::int64_t{0});
  s.bodies_final = j.value("bodies_final", std::int64_t{0});
  s.components_initial = j.value("components_initial", std::int64_t{0});
  s.components_final = j.value("components_final", std::int64_t{0});
  return s;
}

// ---- the run -------------------------------------------------------------------------------

json to_json(const PileRun& r) {
  json j = pile_run_json(r);
  if (r.shape) j["shape"] = to_json(*r.shape);
  return j;
}

namespace {
json pile_run_json(const PileRun& r) {
  const ProcedureRecord& pr = r.procedure;
  return {{"provenance", to_json(r.provenance)},
          {"stop", to_json(r.stop)},
          {"pile", to_json(r.pile)},
          {"psd", to_json(r.psd)},
          {"particles", to_json(r.particles)},
          {"procedure",
           {{"lift_speed_m_s", pr.lift_speed_m_s},
            {"lift_start_s", pr.lift_start_s},
            {"lift_end_s", pr.lift_end_s},
            {"clog_window_s", pr.clog_window_s},
            {"max_retained_fraction", pr.max_retained_fraction},
            {"end_s", pr.end_s},
            {"ke_threshold_j", pr.ke_threshold_j},
            {"container",
             {{"kind", pr.container_kind},
              {"bottom_diameter_m", pr.container_bottom_diameter_m},
              {"top_diameter_m", pr.container_top_diameter_m},
              {"height_m", pr.container_height_m}}},
            {"events", to_json(pr.events)}}},
          {"performance", to_json(r.performance)},
          {"files",
           {{"final_snapshot", "final.vtp"},
            {"series", "series.pvd"},
            {"checkpoint", "checkpoint.bin"},
            {"scene", "scene.resolved.toml"}}}};
}
}  // namespace

PileRun pile_run_from_json(const json& j) {
  try {
    PileRun r;
    r.provenance = run_provenance_from_json(j.at("provenance"));
    r.stop = stop_from_json(j.at("stop"));
    r.pile = pile_measure_from_json(j.at("pile"));
    if (j.contains("psd")) r.psd = psd_record_from_json(j.at("psd"));
    r.particles = particle_counts_from_json(j.at("particles"));
    if (j.contains("shape")) r.shape = shape_record_from_json(j.at("shape"));
    const json& pr = j.at("procedure");
    const json c = pr.value("container", json::object());
    ProcedureRecord& p = r.procedure;
    p.lift_speed_m_s = json_number(pr, "lift_speed_m_s");
    p.lift_start_s = json_number(pr, "lift_start_s", -1.0);
    p.lift_end_s = json_number(pr, "lift_end_s", -1.0);
    p.end_s = json_number(pr, "end_s");
    p.clog_window_s = json_number(pr, "clog_window_s");
    p.max_retained_fraction = json_number(pr, "max_retained_fraction");
    p.ke_threshold_j = json_number(pr, "ke_threshold_j");
    p.container_kind = c.value("kind", std::string());
    p.container_bottom_diameter_m = json_number(c, "bottom_diameter_m");
    p.container_top_diameter_m = json_number(c, "top_diameter_m");
    p.container_height_m = json_number(c, "height_m");
    p.events = run_events_from_json(pr.value("events", json::array()));
    r.performance = run_performance_from_json(j.at("performance"));
    return r;
  } catch (const json::exception& e) {
    throw std::invalid_argument(std::string("not a pile run's result: ") + e.what());
  } catch (const JsonFieldError& e) {  // a field of the wrong type, at its JSON pointer
    throw std::invalid_argument(std::string("not a pile run's result: ") + e.what());
  }
}

}  // namespace reposetwin::experiments
