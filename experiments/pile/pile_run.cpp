#include "experiments/pile/pile_run.hpp"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "experiments/io/provenance.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/vtk_output.hpp"
#include "sim/checkpoint.hpp"
#include "sim/psd.hpp"
#include "sim/random.hpp"
#include "sim/world.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;
constexpr int kPlate = 0, kContainer = 1;

enum class Phase { kFill, kLift, kSettle, kDone };

const char* phase_name(Phase p) {
  switch (p) {
    case Phase::kFill: return "fill";
    case Phase::kLift: return "lift";
    case Phase::kSettle: return "settle";
    case Phase::kDone: return "done";
  }
  return "?";
}

Phase phase_from(const std::string& s) {
  if (s == "fill") return Phase::kFill;
  if (s == "lift") return Phase::kLift;
  if (s == "settle") return Phase::kSettle;
  return Phase::kDone;
}

/// The controller's own state: saved beside each engine checkpoint.
struct Controller {
  Phase phase = Phase::kFill;
  double phase_start = 0.0;        // [s]
  double lift_start = -1.0;        // [s]
  double lift_end = -1.0;          // [s]
  std::int64_t inside_last = -1;   // particles inside the container at the last check
  double inside_changed = 0.0;     // when that count last changed [s]
  double next_frame = 0.0;         // [s]
  int frames = 0;
  double ke_threshold = 0.0;       // KE per particle below which the pile is settled [J]
  double r_min = 0.0, r_max = 0.0; // particle radii the model was built for [m]
  double wall_seconds = 0.0;       // wall time of earlier sessions of this run [s]
  double max_overlap_seen = 0.0;   // largest overlap / smaller radius at any check [-]
  std::int64_t retained = 0;       // particles left in the container and lifted away with it
  double retained_mass = 0.0;      // their mass [kg]
  std::string stop_reason;         // set when done
  std::string stop_detail;
  json psd = json::object();       // PSD sampling summary
  json events = json::array();     // phase changes with their times

  json to_json() const {
    return {{"phase", phase_name(phase)}, {"phase_start", phase_start},
            {"lift_start", lift_start},   {"lift_end", lift_end},
            {"inside_last", inside_last}, {"inside_changed", inside_changed},
            {"next_frame", next_frame},   {"frames", frames},
            {"ke_threshold", ke_threshold}, {"r_min", r_min},
            {"r_max", r_max},             {"wall_seconds", wall_seconds}, {"max_overlap_seen", max_overlap_seen},
            {"stop_reason", stop_reason}, {"stop_detail", stop_detail},
            {"retained", retained},       {"retained_mass", retained_mass},
            {"psd", psd},                 {"events", events}};
  }
  static Controller from_json(const json& j) {
    Controller c;
    c.phase = phase_from(j.at("phase").get<std::string>());
    c.phase_start = j.at("phase_start");
    c.lift_start = j.at("lift_start");
    c.lift_end = j.at("lift_end");
    c.inside_last = j.at("inside_last");
    c.inside_changed = j.at("inside_changed");
    c.next_frame = j.at("next_frame");
    c.frames = j.at("frames");
    c.ke_threshold = j.at("ke_threshold");
    c.r_min = j.at("r_min");
    c.r_max = j.at("r_max");
    c.wall_seconds = j.at("wall_seconds");
    c.max_overlap_seen = j.at("max_overlap_seen");
    c.stop_reason = j.at("stop_reason");
    c.stop_detail = j.at("stop_detail");
    // Checkpoints written before the retained-material rule have none retained.
    c.retained = j.value("retained", std::int64_t{0});
    c.retained_mass = j.value("retained_mass", 0.0);
    c.psd = j.at("psd");
    c.events = j.at("events");
    return c;
  }
};

json psd_json(const sim::PsdSummary& s, const PsdFile& file) {
  json intervals = json::array();
  for (const auto& iv : s.intervals)
    intervals.push_back({{"lower_mm", iv.lower * 1e3}, {"upper_mm", iv.upper * 1e3},
                         {"target_mass_fraction", iv.target_mass_fraction},
                         {"drawn_mass_fraction", iv.drawn_mass_fraction}, {"count", iv.count}});
  return {{"source", file.source},
          {"name", file.name},
          {"provenance", file.provenance},
          {"assumption", file.assumption},
          {"target_mass_kg", s.target_mass},
          {"simulated_target_mass_kg", s.simulated_target_mass},
          {"drawn_mass_kg", s.drawn_mass},
          {"count", s.count},
          {"d_min_mm", s.d_min * 1e3},
          {"d_max_mm", s.d_max * 1e3},
          {"d_min_drawn_mm", s.d_min_drawn * 1e3},
          {"d_max_drawn_mm", s.d_max_drawn * 1e3},
          {"fines_fraction_not_simulated", s.fines_fraction},
          {"scalped_fraction", s.scalped_fraction},
          {"fines_policy", sim::to_string(s.fines)},
          {"intervals", intervals}};
}

/// Radius of the container's inside at height z above its lower rim [m].
double container_radius(const ContainerConfig& c, double z_rel) {
  const double t = std::clamp(z_rel / c.height, 0.0, 1.0);
  return 0.5 * (c.bottom_diameter + t * (c.top_diameter - c.bottom_diameter));
}

/// Places the sample on a loose square lattice inside the container, bottom up; above the
/// container's top the lattice continues in a column of the top's radius (it falls in).
void fill_container(sim::World& world, const SceneConfig& scene,
                    const std::vector<double>& diameters, int material) {
  double d_max = 0.0;
  for (double d : diameters) d_max = std::max(d_max, d);
  const double s = d_max * (1.0 + scene.procedure.lattice_gap);
  const ContainerConfig& c = scene.container;
  // Clearance from a slanted wall, measured horizontally: (s/2) / cos(wall slant).
  const double slope = 0.5 * (c.top_diameter - c.bottom_diameter) / c.height;
  const double clearance = 0.5 * s * std::sqrt(1.0 + slope * slope);
  std::size_t next = 0;
  for (int level = 0; next < diameters.size(); ++level) {
    const double z_rel = 0.5 * s + level * s;
    const double r_avail = container_radius(c, z_rel) - clearance;
    if (level > 100000) throw std::logic_error("fill_container: runaway lattice");
    if (r_avail <= 0.0) continue;
    const int k = static_cast<int>(std::floor(r_avail / s));
    const double shift = (level % 2) ? 0.5 * s : 0.0;  // staggered layers
    for (int ix = -k - 1; ix <= k && next < diameters.size(); ++ix) {
      for (int iy = -k - 1; iy <= k && next < diameters.size(); ++iy) {
        const double x = ix * s + shift, y = iy * s + shift;
        if (std::hypot(x, y) > r_avail) continue;
        world.add_particle(sim::Vec3(x, y, c.gap + z_rel), 0.5 * diameters[next++], material);
      }
    }
  }
}

// Which particles are inside the container (none when it is removed).
std::vector<char> inside_mask(const sim::World& world, const ContainerConfig& c) {
  const sim::State& st = world.state();
  std::vector<char> in(st.particles.size(), 0);
  if (!st.walls[kContainer].enabled) return in;
  const double z0 = c.gap + st.walls[kContainer].offset.z();
  for (std::size_t i = 0; i < in.size(); ++i) {
    const sim::Vec3& x = st.particles.x[i];
    const double z_rel = x.z() - z0;
    if (z_rel < 0.0 || z_rel > c.height) continue;
    in[i] = std::hypot(x.x(), x.y()) < container_radius(c, z_rel);
  }
  return in;
}

std::int64_t count_inside(const sim::World& world, const ContainerConfig& c) {
  const std::vector<char> in = inside_mask(world, c);
  return std::count(in.begin(), in.end(), 1);
}

std::string eta_text(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "?";
  std::ostringstream os;
  const long s = static_cast<long>(seconds);
  if (s >= 3600) os << s / 3600 << "h" << (s % 3600) / 60 << "m";
  else if (s >= 60) os << s / 60 << "m" << s % 60 << "s";
  else os << s << "s";
  return os.str();
}

}  // namespace

json pile_json(const sim::PileGeometry& g) {
  json slices = json::array();
  for (const auto& s : g.slices)
    slices.push_back({{"azimuth_deg", s.azimuth * kRadToDeg},
                      {"valid", s.valid},
                      {"angle_deg", s.angle * kRadToDeg},
                      {"equal_area_angle_deg", s.equal_area_angle * kRadToDeg}});
  return {{"status", sim::to_string(g.status)},
          {"method_hd", "theta = atan(2H/D), H = top of the highest pile particle, D = 2 x median "
                        "over azimuth sectors of the footprint's furthest reach"},
          {"method_slice", "protractor: line fit to each flank between 20% and 80% of H on "
                           "vertical slices through the pile centre, averaged over azimuths"},
          {"height_m", g.height},
          {"base_diameter_m", g.base_diameter},
          {"theta_hd_deg", g.theta_hd * kRadToDeg},
          {"slice_angle_mean_deg", g.slice_angle_mean * kRadToDeg},
          {"slice_angle_sd_deg", g.slice_angle_sd * kRadToDeg},
          {"flank_angle_sd_deg", g.flank_angle_sd * kRadToDeg},
          {"valid_slices", g.valid_slices},
          {"equal_area_angle_deg", g.equal_area_angle * kRadToDeg},
          {"centre_of_mass_angle_deg", g.centre_of_mass_angle * kRadToDeg},
          {"centre_m", {g.centre.x(), g.centre.y()}},
          {"pile_count", g.pile_count},
          {"footprint_count", g.footprint_count},
          {"stray_count", g.stray_count},
          {"median_diameter_m", g.median_diameter},
          {"slices", slices}};
}

json run_pile_test(const SceneConfig& scene, const RunOptions& opt) {
  const fs::path out(opt.out_dir);
  const fs::path result_path = out / "result.json";
  const fs::path ckpt_path = out / "checkpoint.bin";
  const fs::path ctrl_path = out / "controller.json";
  if (fs::exists(result_path) && !opt.force && !opt.resume) {
    throw InputError(result_path.string() +
                     ": a finished result is already there; pass --force to overwrite it");
  }
  if (fs::exists(result_path) && opt.resume && !opt.force) {
    throw InputError(result_path.string() + ": the run is already finished; nothing to resume");
  }
  if (opt.force && !opt.resume) {  // start clean: no stale result may look like this run's
    for (const char* f : {"result.json", "final.vtp", "checkpoint.bin", "controller.json",
                          "series.pvd", "scene.resolved.toml"})
      fs::remove(out / f);
    fs::remove_all(out / "frames");
    fs::remove_all(out / "images");
  }
  fs::create_directories(out / "frames");
  const auto wall0 = std::chrono::steady_clock::now();
  auto wall_now = [&]() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  };

  // The sample (deterministic from the seed) and the model built for its sizes.
  const int mat = material_index(scene, scene.sample_material, "sample.material");
  Controller ctl;
  std::vector<double> diameters;
  const bool resuming = opt.resume && fs::exists(ckpt_path) && fs::exists(ctrl_path);
  if (opt.resume && !resuming)
    throw InputError(out.string() + ": no checkpoint to resume from (checkpoint.bin, controller.json)");
  if (resuming) {
    try {
      ctl = Controller::from_json(json::parse(read_file(ctrl_path.string())));
    } catch (const std::exception& e) {
      throw ResumeError(ctrl_path.string() + ": cannot resume from it: " + e.what());
    }
  } else {
    sim::Rng rng(scene.seed);
    sim::PsdSample sample;
    try {
      sample = sim::sample_psd(scene.psd.spec, scene.mass, scene.materials[mat].density, rng);
    } catch (const std::invalid_argument& e) {
      throw InputError(scene.file + ": sample: " + e.what());
    }
    diameters = sample.diameter;
    ctl.psd = psd_json(sample.summary, scene.psd);
    ctl.r_min = 0.5 * sample.summary.d_min_drawn;
    ctl.r_max = 0.5 * sample.summary.d_max_drawn;
  }
  sim::Settings settings = scene.settings;
  if (opt.threads > 0) settings.threads = opt.threads;
  SceneConfig sc = scene;
  sc.settings = settings;
  sim::World world(build_model(sc, ctl.r_min, ctl.r_max));
  const sim::Model& model = world.model();
  const double dt = model.dt;

  PvdSeries series((out / "series.pvd").string());
  if (resuming) {
    try {
      sim::read_checkpoint(world, ckpt_path.string());
      series.load();
    } catch (const std::exception& e) {
      throw ResumeError(std::string("cannot resume: ") + e.what());
    }
    ctl.events.push_back({{"event", "resumed"},
                          {"t", world.state().time},
                          {"code_version", code_version()}});
    series.truncate_after(world.state().time);
  } else {
    write_file_atomic((out / "scene.resolved.toml").string(), scene.resolved_toml);
    fill_container(world, scene, diameters, mat);
    world.refresh_forces();
    const sim::Diagnostics d0 = world.diagnose();
    if (d0.max_overlap_ratio > settings.initial_overlap_tolerance) {
      throw InputError(scene.file + ": the initial packing overlaps by " +
                       std::to_string(d0.max_overlap_ratio) + " of a radius, above " +
                       "numerics.initial_overlap_tolerance = " +
                       std::to_string(settings.initial_overlap_tolerance));
    }
    double m_mean = 0.0;
    for (double m : world.state().particles.mass) m_mean += m;
    m_mean /= std::max<std::size_t>(1, world.state().particles.size());
    ctl.ke_threshold = 0.5 * m_mean * scene.procedure.settle_speed * scene.procedure.settle_speed;
    ctl.events.push_back({{"t", 0.0}, {"event", "filled"}, {"particles", world.state().particles.size()}});
  }

  // The sample as filled (a resumed run may already have lifted some away with the container).
  const std::size_t n0 = world.state().particles.size() + static_cast<std::size_t>(ctl.retained);
  const int threads = settings.threads > 0 ? settings.threads : omp_get_max_threads();
  json provenance = {
      {"scene_file", scene.file},
      {"scene_name", scene.name},
      {"seed", scene.seed},
      {"code_version", code_version()},
      {"time_step_s", dt},
      {"rayleigh_time_s", model.rayleigh_time},
      {"rayleigh_fraction", dt / model.rayleigh_time},
      {"softened_youngs_modulus_pa", settings.softened_youngs_modulus > 0
                                         ? json(settings.softened_youngs_modulus)
                                         : json(nullptr)},
      {"youngs_modulus_real_pa", scene.materials[mat].youngs_modulus},
      {"threads", threads},
      {"rolling_models", json::array()},
      {"created_utc", utc_now()}};
  for (const auto& row : sim::kRollingModels)
    provenance["rolling_models"].push_back({{"keyword", row.keyword}, {"torque", row.torque},
                                            {"radius", row.radius},
                                            {"angular_velocity", row.angular_velocity}});
  for (auto it = opt.extra_provenance.begin(); it != opt.extra_provenance.end(); ++it)
    provenance[it.key()] = it.value();

  // Checks run every few milliseconds of simulated time, not every step.
  const std::int64_t check_every = std::max<std::int64_t>(1, std::llround(0.002 / dt));
  double last_ckpt_wall = 0.0, last_progress_wall = 0.0;
  const std::int64_t step0 = world.state().step;
  auto save_checkpoint = [&]() {
    Controller c = ctl;
    c.wall_seconds = ctl.wall_seconds + wall_now();
    sim::write_checkpoint(world, ckpt_path.string());
    write_json_atomic(ctrl_path.string(), c.to_json());
  };
  auto write_frame = [&]() {
    char name[64];
    std::snprintf(name, sizeof name, "frames/frame_%05d.vtp", ctl.frames++);
    write_vtp((out / name).string(), world.state().particles);
    series.add(world.state().time, name);
  };
  auto ke_per_particle = [&](const sim::Diagnostics& d) {
    return d.kinetic_energy / std::max<std::size_t>(1, world.state().particles.size());
  };
  auto event = [&](const std::string& what) {
    ctl.events.push_back({{"t", world.state().time}, {"event", what}});
  };
  if (!resuming && scene.output.frame_interval > 0) write_frame();

  bool stopped_early = false;
  while (ctl.phase != Phase::kDone) {
    world.step();
    const sim::State& st = world.state();
    const double t = st.time;
    if (scene.output.frame_interval > 0 && t >= ctl.next_frame) {
      ctl.next_frame = t + scene.output.frame_interval;
      write_frame();
    }
    if ((st.step - step0) % check_every != 0) continue;

    if (ctl.phase == Phase::kFill) {
      // Filling is preparation, not the test: the sample is lowered gently, as a lab fills the
      // funnel by hand, so soft particles do not hit the bottom at free-fall speed.
      const double cap = scene.procedure.fill_max_speed;
      for (sim::Vec3& v : world.state().particles.v) {
        const double s = v.norm();
        if (s > cap) v *= cap / s;
      }
    }
    const sim::Diagnostics d = world.diagnose();
    ctl.max_overlap_seen = std::max(ctl.max_overlap_seen, d.max_overlap_ratio);
    if (d.status != sim::Status::kOk) {
      ctl.stop_reason = std::string("physics: ") + sim::status_name(d.status);
      ctl.stop_detail = d.detail;
      ctl.phase = Phase::kDone;
      break;
    }
    const double ke = ke_per_particle(d);
    const double in_phase = t - ctl.phase_start;
    switch (ctl.phase) {
      case Phase::kFill:
        if ((ke < ctl.ke_threshold && in_phase > 0.05) || in_phase > scene.procedure.fill_settle_max) {
          if (in_phase > scene.procedure.fill_settle_max) event("fill settling reached its time limit");
          world.set_wall_velocity(kContainer, sim::Vec3(0, 0, scene.procedure.lift_speed));
          ctl.phase = Phase::kLift;
          ctl.phase_start = ctl.lift_start = t;
          ctl.inside_last = count_inside(world, scene.container);
          ctl.inside_changed = t;
          event("lift started");
        }
        break;
      case Phase::kLift: {
        const std::int64_t inside = count_inside(world, scene.container);
        const bool flow_stopped = inside != 0 && inside == ctl.inside_last &&
                                  t - ctl.inside_changed > scene.procedure.clog_window &&
                                  st.walls[kContainer].offset.z() > 4.0 * ctl.r_max;
        const bool little_left = static_cast<double>(inside) <=
                                 scene.procedure.max_retained_fraction * static_cast<double>(n0);
        if (inside == 0 || (flow_stopped && little_left)) {
          std::string what = "container empty; removed";
          if (inside > 0) {
            // The flow has stopped with a little material left inside (cohesive grains on the
            // wall): it stays in the container, which is lifted away with it, as in the lab.
            const std::vector<char> in = inside_mask(world, scene.container);
            for (std::size_t i = 0; i < in.size(); ++i)
              if (in[i]) ctl.retained_mass += st.particles.mass[i];
            ctl.retained += static_cast<std::int64_t>(world.remove_particles(in));
            what = "flow stopped; " + std::to_string(ctl.retained) +
                   " particles stayed in the container and were lifted away with it";
          }
          world.set_wall_velocity(kContainer, sim::Vec3::Zero());
          world.set_wall_enabled(kContainer, false);
          ctl.phase = Phase::kSettle;
          ctl.phase_start = ctl.lift_end = t;
          event(what);
        } else if (inside != ctl.inside_last) {
          ctl.inside_last = inside;
          ctl.inside_changed = t;
        } else if (flow_stopped) {
          ctl.stop_reason = "clogged";
          ctl.stop_detail = "no pile: " + std::to_string(inside) + " particles lodged";
          ctl.phase = Phase::kDone;
        }
        break;
      }
      case Phase::kSettle:
        if (ke < ctl.ke_threshold && in_phase > 0.1) {
          ctl.stop_reason = "settled";
          ctl.stop_detail = "kinetic energy per particle below the threshold";
          ctl.phase = Phase::kDone;
        } else if (in_phase > scene.procedure.final_settle_max) {
          ctl.stop_reason = "settle time limit";
          ctl.stop_detail = "kinetic energy per particle still above the threshold";
          ctl.phase = Phase::kDone;
        }
        break;
      case Phase::kDone:
        break;
    }
    if (ctl.phase != Phase::kDone && t > scene.procedure.max_time) {
      ctl.stop_reason = "time limit";
      ctl.stop_detail = std::string("phase ") + phase_name(ctl.phase) + " at the time limit";
      ctl.phase = Phase::kDone;
    }
    const double wall = wall_now();
    if (opt.progress && wall - last_progress_wall > scene.output.progress_interval) {
      last_progress_wall = wall;
      const double steps_done = static_cast<double>(st.step - step0);
      const double rate = steps_done * static_cast<double>(st.particles.size()) / std::max(wall, 1e-9);
      // Remaining simulated time: the rest of the lift (by the fill height) plus settling.
      double remaining = 1.0;
      if (ctl.phase == Phase::kFill) remaining += 0.1 + scene.container.height / scene.procedure.lift_speed * 0.5;
      if (ctl.phase == Phase::kLift) {
        double top = 0;
        for (const sim::Vec3& x : st.particles.x) top = std::max(top, x.z());
        remaining += std::max(0.0, top - scene.container.gap - st.walls[kContainer].offset.z()) /
                     scene.procedure.lift_speed;
      }
      const double sim_rate = (t - (step0 * dt)) / std::max(wall, 1e-9);
      std::fprintf(stderr,
                   "%s: %-6s step %lld  t=%.3f s  %zu particles  KE/N=%.2e J  inside=%lld  "
                   "%.2e particle-steps/s  ETA %s\n",
                   scene.name.c_str(), phase_name(ctl.phase), static_cast<long long>(st.step), t,
                   st.particles.size(), ke, static_cast<long long>(ctl.inside_last), rate,
                   eta_text(remaining / std::max(sim_rate, 1e-12)).c_str());
    }
    if (ctl.phase != Phase::kDone && wall - last_ckpt_wall > scene.output.checkpoint_interval) {
      last_ckpt_wall = wall;
      save_checkpoint();
    }
    const bool wall_up = opt.stop_after_wall_s > 0 && wall > opt.stop_after_wall_s;
    const bool steps_up = opt.stop_after_steps > 0 && st.step - step0 >= opt.stop_after_steps;
    if ((wall_up || steps_up) && ctl.phase != Phase::kDone) {
      save_checkpoint();
      stopped_early = true;
      break;
    }
  }
  if (stopped_early) return json{{"stopped", "time or step limit; resume with --resume"}};

  // Measure the pile from the particle positions.
  const sim::State& st = world.state();
  json pile;
  if (ctl.stop_reason == "clogged") {
    pile = {{"status", "no pile"}, {"detail", ctl.stop_detail}, {"theta_hd_deg", 0.0},
            {"slice_angle_mean_deg", 0.0}, {"lodged_particles", ctl.inside_last}};
  } else {
    pile = pile_json(sim::measure_pile(st.particles.x, st.particles.radius, scene.pile));
  }
  write_vtp((out / "final.vtp").string(), st.particles);
  write_frame();  // the series always ends with the final state
  save_checkpoint();
  const double wall_total = ctl.wall_seconds + wall_now();
  const double steps = static_cast<double>(st.step);
  json result = {
      {"provenance", provenance},
      {"stop", {{"reason", ctl.stop_reason}, {"detail", ctl.stop_detail}}},
      {"pile", pile},
      {"psd", ctl.psd},
      {"particles",
       {{"initial", n0},
        {"final", st.particles.size()},
        {"retained_in_container", ctl.retained},
        {"retained_mass_kg", ctl.retained_mass}}},
      {"procedure",
       {{"lift_speed_m_s", scene.procedure.lift_speed},
        {"lift_start_s", ctl.lift_start},
        {"lift_end_s", ctl.lift_end},
        {"clog_window_s", scene.procedure.clog_window},
        {"max_retained_fraction", scene.procedure.max_retained_fraction},
        {"end_s", st.time},
        {"ke_threshold_j", ctl.ke_threshold},
        {"container", {{"kind", scene.container.kind},
                       {"bottom_diameter_m", scene.container.bottom_diameter},
                       {"top_diameter_m", scene.container.top_diameter},
                       {"height_m", scene.container.height}}},
        {"events", ctl.events}}},
      {"performance",
       {{"steps", st.step},
        {"wall_s", wall_total},
        {"particle_steps_per_s", steps * static_cast<double>(n0) / std::max(wall_total, 1e-9)},
        {"neighbor_builds", st.neighbors.builds},
        {"max_overlap_ratio_seen", ctl.max_overlap_seen}}},
      {"files", {{"final_snapshot", "final.vtp"}, {"series", "series.pvd"},
                 {"checkpoint", "checkpoint.bin"}, {"scene", "scene.resolved.toml"}}}};
  write_json_atomic(result_path.string(), result);
  if (opt.progress) {
    std::fprintf(stderr, "%s: %s (%s) after %.3f s simulated, %.1f s wall; wrote %s\n",
                 scene.name.c_str(), ctl.stop_reason.c_str(), ctl.stop_detail.c_str(), st.time,
                 wall_total, result_path.string().c_str());
  }
  return result;
}

json run_pile_test_or_continue(const SceneConfig& scene, const RunOptions& opt) {
  const fs::path out(opt.out_dir);
  std::error_code ec;
  if (fs::is_regular_file(out / "result.json", ec)) {
    try {
      json done = json::parse(read_file((out / "result.json").string()));
      if (done.contains("stop") && done.contains("pile")) return done;
    } catch (const std::exception&) {
    }
  }
  if (fs::is_regular_file(out / "checkpoint.bin", ec) &&
      fs::is_regular_file(out / "controller.json", ec)) {
    RunOptions resume = opt;
    resume.resume = true;
    try {
      return run_pile_test(scene, resume);
    } catch (const ResumeError& e) {
      std::cerr << out.string() << ": cannot continue from the checkpoint (" << e.what()
                << "); running again from the start\n";
    }
  }
  fs::remove_all(out, ec);
  if (ec) throw std::runtime_error(out.string() + ": cannot clear the run folder: " + ec.message());
  return run_pile_test(scene, opt);
}

}  // namespace reposetwin::experiments
