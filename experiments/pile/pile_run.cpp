#include "experiments/pile/pile_run.hpp"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>

#include "experiments/io/format.hpp"
#include "experiments/io/hash.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/io/vtk_output.hpp"
#include "experiments/pile/pile_sample.hpp"
#include "experiments/pile/run_controller.hpp"
#include "experiments/pile/run_folder.hpp"
#include "experiments/pile/run_state.hpp"
#include "experiments/pile/stop_hint.hpp"
#include "sim/checkpoint.hpp"
#include "sim/psd.hpp"
#include "sim/random.hpp"
#include "sim/world.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

using pile_detail::Controller;
using pile_detail::Phase;
using pile_detail::phase_name;

PileSpheres spheres_of(const sim::State& st) {
  const sim::Particles& p = st.particles;
  PileSpheres s{{p.x.begin(), p.x.end()},
                {p.radius.begin(), p.radius.end()},
                {p.material.begin(), p.material.end()},
                {}};
  if (st.bodies.size() == 0) return s;
  s.body.resize(p.size(), -1);
  for (std::size_t i = 0; i < p.size(); ++i)
    if (p.body[i] >= 0) s.body[i] = st.bodies.id[static_cast<std::size_t>(p.body[i])];
  return s;
}

// CPU time of this process, every thread [s]: what a run costs, apart from the machine's load
// (its wall time is not, on shared cores).
double process_cpu_s() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// The phase as the time-limit message says it ("while filling").
const char* phase_doing(Phase p) {
  switch (p) {
    case Phase::kFill:
      return "filling";
    case Phase::kLift:
      return "lifting";
    case Phase::kSettle:
      return "settling";
    case Phase::kDone:
      break;
  }
  return "finishing";
}

std::string eta_text(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "?";
  std::ostringstream os;
  const long s = static_cast<long>(seconds);
  if (s >= 3600)
    os << s / 3600 << "h" << (s % 3600) / 60 << "m";
  else if (s >= 60)
    os << s / 60 << "m" << s % 60 << "s";
  else
    os << s << "s";
  return os.str();
}

/// One pile test from its folder to its record: the phases of RunOptions' design note, each a
/// method, run() their table of contents.
class PileRunner {
 public:
  PileRunner(const SceneConfig& scene, const RunOptions& opt)
      : scene_(scene), opt_(opt), out_(opt.out_dir), wall0_(std::chrono::steady_clock::now()),
        cpu0_(process_cpu_s()) {}

  std::optional<PileRun> run() {
    prepare_folder();
    const bool resuming = load_controller_or_sample();
    build_world(resuming);
    if (resuming) {
      resume_from_checkpoint();
    } else {
      fill_and_check();
      start_clean_folder();  // only now: --force deletes nothing for inputs that fail
    }
    provenance_ = make_provenance();
    if (!resuming && scene_.output.frame_interval > 0) write_frame();
    if (!advance_until_done()) return std::nullopt;  // checkpointed; --resume continues
    return finish();
  }

 private:
  fs::path path(const char* name) const { return out_ / name; }
  double wall_now() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0_).count();
  }
  double cpu_now() const { return process_cpu_s() - cpu0_; }
  const sim::State& state() const { return world_->state(); }
  void event(const std::string& what) { ctl_.events.push_back(run_event(state().time, what)); }
  void end(StopReason reason, const std::string& detail) {
    ctl_.stop = {reason, sim::Status::kOk, detail, ""};
    ctl_.phase = Phase::kDone;
  }

  // One process per run folder; a finished result is never overwritten without force.
  // A resumed run whose result.json is there but whose stage record is not complete stopped
  // between its result and its record (pile/run_state.hpp): it is finished again from its
  // checkpoint.
  void prepare_folder() {
    if (!opt_.lock_held) lock_.emplace(out_.string(), ".run.lock", "another pile run");
    // A link inside that leads outside would aim the run's writes and --force's removals at
    // another folder.
    refuse_escaping_links(out_.string());
    const fs::path result = path("result.json");
    if (fs::exists(result) && !opt_.force && !opt_.resume)
      throw InputError(result.string() +
                       ": a finished result is already there; pass --force to overwrite it");
    const std::optional<RunState> recorded = read_run_state(out_.string());
    if (opt_.resume && !opt_.force && recorded && recorded->complete())
      throw InputError(result.string() + ": the run is already finished; nothing to resume");
  }

  // A fresh run whose inputs have passed every check: with force, no stale result may look
  // like this run's; the resolved scene is the folder's first file.
  void start_clean_folder() {
    if (opt_.force) remove_run_files(out_);  // a user's own files beside them stay
    fs::create_directories(path("frames"));
    write_file_atomic(path("scene.resolved.toml").string(), scene_.resolved_toml);
  }

  // The sample is deterministic from the seed; a resumed run takes it from its controller file.
  bool load_controller_or_sample() {
    material_ = material_index(scene_, scene_.sample_material, "sample.material");
    const bool resuming =
        opt_.resume && fs::exists(path("checkpoint.bin")) && fs::exists(path("controller.json"));
    if (opt_.resume && !resuming)
      throw InputError(out_.string() +
                       ": no checkpoint to resume from (checkpoint.bin, controller.json)");
    if (resuming) {
      try {
        ctl_ = Controller::from_json(read_json_file(path("controller.json").string()));
      } catch (const std::exception& e) {
        throw ResumeError(path("controller.json").string() +
                          ": cannot resume from it: " + e.what());
      }
      check_same_scene_and_engine();
      // Clumps: the templates are the model's, rebuilt from the same draw (checked in
      // build_world against the controller's fingerprint).
      if (!scene_.shapes.empty()) sample_ = draw_pile_sample(scene_, material_);
      return true;
    }
    ctl_.scene_hash = fnv1a_hex(scene_.resolved_toml);
    sample_ = draw_pile_sample(scene_, material_);
    const PsdFile& f = scene_.psd;
    ctl_.psd = psd_record(sample_.summary, f.source, f.name, f.provenance, f.assumption);
    ctl_.r_min = sample_.r_min;
    ctl_.r_max = sample_.r_max;
    return false;
  }

  // A checkpoint continues only the run that wrote it: another scene (an edited file, another
  // --set) or another engine would finish a run whose result no single input describes.
  void check_same_scene_and_engine() const {
    const std::string here = fnv1a_hex(scene_.resolved_toml);
    if (!ctl_.scene_hash.empty() && ctl_.scene_hash != here)
      throw ResumeError(out_.string() +
                        ": the checkpoint was made from another scene (resolved "
                        "scene hash " +
                        ctl_.scene_hash + ", this run's is " + here +
                        "); run it again from the start with --force instead of --resume");
    // The engine's source hash decides (another commit with the same engine continues the run
    // to the same bits); a checkpoint written before the hash was stamped is compared by code
    // version.
    const bool other = !ctl_.engine_version.empty()
                           ? ctl_.engine_version != engine_version()
                           : !ctl_.code_version.empty() && ctl_.code_version != code_version();
    if (other)
      throw ResumeError(out_.string() + ": the checkpoint was written by engine " +
                        ctl_.code_version +
                        (ctl_.engine_version.empty() ? "" : " (" + ctl_.engine_version + ")") +
                        ", this is " + code_version() + " (" + engine_version() +
                        "); run it again from the start with --force instead of --resume");
  }

  void build_world(bool resuming) {
    settings_ = scene_.settings;
    if (opt_.threads > 0) settings_.threads = opt_.threads;
    SceneConfig sc = scene_;
    sc.settings = settings_;
    sim::Model model = build_model(sc, ctl_.r_min, ctl_.r_max);
    add_grain_templates(model, scene_, sample_);
    const std::string templates = template_fingerprint(model);
    if (resuming && ctl_.templates_hash != templates)
      throw ResumeError(out_.string() + ": the checkpoint's clump templates (fingerprint \"" +
                        ctl_.templates_hash + "\") are not those this scene builds (\"" +
                        templates + "\"); run it again with --force instead of --resume");
    ctl_.templates_hash = templates;
    world_ = std::make_unique<sim::World>(std::move(model));
    series_ = std::make_unique<PvdSeries>(path("series.pvd").string());
  }

  void resume_from_checkpoint() {
    try {
      sim::read_checkpoint(*world_, path("checkpoint.bin").string());
      series_->load();
    } catch (const std::exception& e) {
      throw ResumeError(std::string("cannot resume: ") + e.what());
    }
    // checkpoint.bin and controller.json are renamed into place one after the other: a kill
    // between the two renames leaves them from different moments, which their stamps show.
    if (ctl_.step >= 0 && ctl_.step != state().step)
      throw ResumeError(out_.string() + ": checkpoint.bin is at step " +
                        std::to_string(state().step) + " but controller.json at step " +
                        std::to_string(ctl_.step) + " (interrupted while checkpointing)");
    ctl_.events.push_back(run_event(state().time, "resumed", std::nullopt, code_version()));
    series_->truncate_after(state().time);
  }

  void fill_and_check() {
    fill_container(*world_, scene_, sample_, material_);
    world_->refresh_forces();
    const sim::Diagnostics d0 = world_->diagnose();
    if (d0.max_overlap_ratio > settings_.initial_overlap_tolerance) {
      throw InputError(scene_.file + ": the initial packing overlaps by " +
                       std::to_string(d0.max_overlap_ratio) + " of a radius, above " +
                       "numerics.initial_overlap_tolerance = " +
                       std::to_string(settings_.initial_overlap_tolerance));
    }
    // Per grain: a clump's components carry its mass, so the bodies' masses are averaged.
    double m_mean = 0.0;
    const bool clumps = state().bodies.size() > 0;
    for (double m : clumps ? state().bodies.mass : state().particles.mass) m_mean += m;
    m_mean /= static_cast<double>(std::max<std::int64_t>(1, grain_count(state())));
    const double v = scene_.procedure.settle_speed;
    ctl_.ke_threshold = 0.5 * m_mean * v * v;
    const std::int64_t n = grain_count(state());
    ctl_.events.push_back(run_event(0.0, "filled", n));
  }

  RunProvenance make_provenance() const {
    const sim::Model& model = world_->model();
    RunProvenance p;
    p.scene_file = scene_.file;
    p.scene_name = scene_.name;
    p.seed = scene_.seed;
    p.code_version = code_version();
    p.engine_version = engine_version();
    p.time_step_s = model.dt;
    p.rayleigh_time_s = model.rayleigh_time;
    if (settings_.softened_youngs_modulus > 0)
      p.softened_youngs_modulus_pa = settings_.softened_youngs_modulus;
    p.youngs_modulus_real_pa = scene_.materials[material_].youngs_modulus;
    p.threads = settings_.threads > 0 ? settings_.threads : omp_get_max_threads();
    p.created_utc = utc_now();
    p.extra = opt_.extra_provenance;
    return p;
  }

  // The sample as filled (a resumed run may already have lifted some away with the container).
  std::int64_t initial_count() const {
    return grain_count(state()) + ctl_.retained;
  }

  // Steps the engine; the controller looks every few milliseconds of simulated time, not every
  // step, and at once when the engine has seen a non-finite state (so a broken run stops in the
  // step that broke it). Returns false when a wall-time or step limit stopped the run (checkpointed).
  bool advance_until_done() {
    const std::int64_t check_every =
        std::max<std::int64_t>(1, std::llround(0.002 / world_->model().dt));
    step0_ = state().step;
    n0_ = initial_count();
    double last_ckpt_wall = 0.0;
    while (ctl_.phase != Phase::kDone) {
      world_->step();
      if (scene_.output.frame_interval > 0 && state().time >= ctl_.next_frame) {
        ctl_.next_frame = state().time + scene_.output.frame_interval;
        write_frame();
      }
      if ((state().step - step0_) % check_every != 0 && !world_->nonfinite_seen()) continue;
      if (!check_phase()) break;  // a physics stop
      const double wall = wall_now();
      report_progress(wall);
      if (ctl_.phase != Phase::kDone && wall - last_ckpt_wall > scene_.output.checkpoint_interval) {
        last_ckpt_wall = wall;
        save_checkpoint();
      }
      const bool wall_up = opt_.stop_after_wall_s > 0 && wall > opt_.stop_after_wall_s;
      const bool steps_up =
          opt_.stop_after_steps > 0 && state().step - step0_ >= opt_.stop_after_steps;
      if ((wall_up || steps_up) && ctl_.phase != Phase::kDone) {
        save_checkpoint();
        return false;
      }
    }
    return true;
  }

  // One look of the controller: the engine's health, then the phase's own rule. Returns false
  // when the engine reported trouble (the run ends at once).
  bool check_phase() {
    if (ctl_.phase == Phase::kFill) cap_fill_speeds();
    const sim::Diagnostics d = world_->diagnose();
    ctl_.max_overlap_seen = std::max(ctl_.max_overlap_seen, d.max_overlap_ratio);
    if (d.status != sim::Status::kOk) {
      ctl_.stop = {StopReason::kPhysics, d.status, d.detail, physics_stop_hint(d.status, scene_)};
      ctl_.phase = Phase::kDone;
      return false;
    }
    const double ke =
        d.kinetic_energy / static_cast<double>(std::max<std::int64_t>(1, grain_count(state())));
    ke_last_ = ke;
    const double in_phase = state().time - ctl_.phase_start;
    switch (ctl_.phase) {
      case Phase::kFill:
        check_fill(ke, in_phase);
        break;
      case Phase::kLift:
        check_lift();
        break;
      case Phase::kSettle:
        check_settle(ke, in_phase);
        break;
      case Phase::kDone:
        break;
    }
    if (ctl_.phase != Phase::kDone && state().time > scene_.procedure.max_time)
      end(StopReason::kTimeLimit,
          "procedure.max_time_s = " + significant(scene_.procedure.max_time) + " s reached while " +
              phase_doing(ctl_.phase));
    return true;
  }

  // Filling is preparation, not the test: the sample is lowered gently, as a lab fills the
  // funnel by hand, so soft particles do not hit the bottom at free-fall speed.
  void cap_fill_speeds() {
    const double cap = scene_.procedure.fill_max_speed;
    auto limit = [cap](sim::Vec3& v) {
      const double s = v.norm();
      if (s > cap) v *= cap / s;
    };
    for (sim::Vec3& v : world_->state().particles.v) limit(v);
    for (sim::Vec3& v : world_->state().bodies.v) limit(v);  // a clump moves as its body
  }

  void check_fill(double ke, double in_phase) {
    const double limit = scene_.procedure.fill_settle_max;
    if (!((ke < ctl_.ke_threshold && in_phase > 0.05) || in_phase > limit)) return;
    if (in_phase > limit) event("fill settling reached its time limit");
    world_->set_wall_velocity(kContainerWall, sim::Vec3(0, 0, scene_.procedure.lift_speed));
    ctl_.phase = Phase::kLift;
    ctl_.phase_start = ctl_.lift_start = state().time;
    ctl_.inside_last = count_inside(*world_, scene_.container);
    ctl_.inside_changed = state().time;
    event("lift started");
    // The sample as filled, the state another engine can start its lift from
    // (`reposetwin export --initial-state`), so the two compare the pour alone.
    if (scene_.output.frame_interval > 0)
      write_vtp(path("frames/filled.vtp").string(), state().particles, frame_info(false),
                &state().bodies);
  }

  // The container rises until it is empty. If the count inside stops changing, the flow has
  // stopped: with a little material left (cohesive grains on the wall) the container takes it
  // away, as in the lab; with more, the outlet has clogged and there is no pile.
  void check_lift() {
    const ProcedureConfig& pc = scene_.procedure;
    const double t = state().time;
    const std::int64_t inside = count_inside(*world_, scene_.container);
    const bool flow_stopped = inside != 0 && inside == ctl_.inside_last &&
                              t - ctl_.inside_changed > pc.clog_window &&
                              state().walls[kContainerWall].offset.z() > 4.0 * ctl_.r_max;
    const bool little_left =
        static_cast<double>(inside) <= pc.max_retained_fraction * static_cast<double>(n0_);
    if (inside == 0 || (flow_stopped && little_left)) {
      std::string what = "container empty; removed";
      if (inside > 0) {
        lift_away_retained();
        what = "flow stopped; " + std::to_string(ctl_.retained) +
               " particles stayed in the container and were lifted away with it";
      }
      world_->set_wall_velocity(kContainerWall, sim::Vec3::Zero());
      world_->set_wall_enabled(kContainerWall, false);
      ctl_.phase = Phase::kSettle;
      ctl_.phase_start = ctl_.lift_end = t;
      event(what);
    } else if (inside != ctl_.inside_last) {
      ctl_.inside_last = inside;
      ctl_.inside_changed = t;
    } else if (flow_stopped) {
      end(StopReason::kClogged,
          std::to_string(inside) + (scene_.shapes.empty() ? " particles" : " clumps") +
              " lodged in the container, their count unchanged for procedure.clog_window_s = " +
              significant(pc.clog_window) + " s");
    }
  }

  // Whole grains: a clump's mass once (its first component carries the body's mass).
  void lift_away_retained() {
    const std::vector<char> in = inside_mask(*world_, scene_.container);
    const sim::Particles& p = state().particles;
    for (std::size_t i = 0; i < in.size(); ++i)
      if (in[i] && p.component[i] <= 0) ctl_.retained_mass += p.mass[i];
    const std::int64_t before = grain_count(state());
    world_->remove_particles(in);
    ctl_.retained += before - grain_count(state());
  }

  void check_settle(double ke, double in_phase) {
    if (ke < ctl_.ke_threshold && in_phase > 0.1)
      end(StopReason::kSettled, "kinetic energy per particle below the threshold");
    else if (in_phase > scene_.procedure.final_settle_max)
      end(StopReason::kSettleTimeLimit,
          "procedure.final_settle_max_s = " + significant(scene_.procedure.final_settle_max) +
              " s reached with the kinetic energy per particle still above the threshold of "
              "procedure.settle_speed_m_s = " +
              significant(scene_.procedure.settle_speed) + " m/s");
  }

  void report_progress(double wall) {
    if (!opt_.progress || wall - last_progress_wall_ <= scene_.output.progress_interval) return;
    last_progress_wall_ = wall;
    const sim::State& st = state();
    const double dt = world_->model().dt;
    const double steps_done = static_cast<double>(st.step - step0_);
    const double rate =
        steps_done * static_cast<double>(st.particles.size()) / std::max(wall, 1e-9);
    // Remaining simulated time: the rest of the lift (by the fill height) plus settling.
    const ProcedureConfig& pc = scene_.procedure;
    double remaining = 1.0;
    if (ctl_.phase == Phase::kFill)
      remaining += 0.1 + scene_.container.height / pc.lift_speed * 0.5;
    if (ctl_.phase == Phase::kLift) {
      double top = 0;
      for (const sim::Vec3& x : st.particles.x) top = std::max(top, x.z());
      remaining += std::max(0.0, top - scene_.container.gap - st.walls[kContainerWall].offset.z()) /
                   pc.lift_speed;
    }
    const double sim_rate = (st.time - (step0_ * dt)) / std::max(wall, 1e-9);
    std::fprintf(stderr,
                 "%s: %-6s step %lld  t=%.3f s  %zu particles  KE/N=%.2e J  inside=%lld  "
                 "%.2e particle-steps/s  ETA %s\n",
                 scene_.name.c_str(), phase_name(ctl_.phase), static_cast<long long>(st.step),
                 st.time, st.particles.size(), ke_last_, static_cast<long long>(ctl_.inside_last),
                 rate, eta_text(remaining / std::max(sim_rate, 1e-12)).c_str());
  }

  void save_checkpoint() {
    Controller c = ctl_;
    c.wall_seconds = ctl_.wall_seconds + wall_now();
    c.cpu_seconds = ctl_.cpu_seconds + cpu_now();
    c.code_version = code_version();
    c.engine_version = engine_version();
    c.step = state().step;
    sim::write_checkpoint(*world_, path("checkpoint.bin").string());
    write_json_atomic(path("controller.json").string(), c.to_json());
  }

  // What a frame shows besides the particles: the phase, whether it is the settled pile (the
  // final state of a run that ended settling), the container where it stands, the plate and
  // the material names.
  FrameInfo frame_info(bool final_state) const {
    const sim::State& st = state();
    const ContainerConfig& c = scene_.container;
    FrameInfo info;
    info.time_s = st.time;
    info.phase = phase_name(ctl_.phase);
    info.scene_fnv1a = ctl_.scene_hash;  // what a snapshot is of: another scene's is refused
    info.settled = final_state && (ctl_.stop.reason == StopReason::kSettled ||
                                   ctl_.stop.reason == StopReason::kSettleTimeLimit);
    if (st.walls[kContainerWall].enabled) {
      const double z0 = c.gap + st.walls[kContainerWall].offset.z();
      info.container =
          ShellPlacement{z0, z0 + c.height, 0.5 * c.bottom_diameter, 0.5 * c.top_diameter};
    }
    // The engine's plate is a plane; ParaView shows the lab's board, wider than the funnel.
    info.plate_half_size_m = std::max(0.25, c.top_diameter);
    for (const sim::Material& m : world_->model().materials) info.material_names.push_back(m.name);
    return info;
  }

  // One time step of the series: the particles, the plate, the container while it stands and
  // the contacts (at the last frame always, at every frame if asked), as parts of one ParaView
  // time step. The pile's force chains are what a user opens the final state to see.
  void write_frame(bool final_state = false) {
    const int k = ctl_.frames++;
    auto name = [k](const char* stem) {
      char buf[64];
      std::snprintf(buf, sizeof buf, "frames/%s_%05d.vtp", stem, k);
      return std::string(buf);
    };
    const FrameInfo info = frame_info(final_state);
    std::vector<std::string> parts = {name("frame")};
    write_vtp((out_ / parts[0]).string(), state().particles, info, &state().bodies);
    if (!fs::exists(out_ / "frames" / "plate.vtp"))
      write_plate_vtp((out_ / "frames" / "plate.vtp").string(), info);
    parts.push_back("frames/plate.vtp");
    if (info.container) {
      parts.push_back(name("container"));
      write_shell_vtp((out_ / parts.back()).string(), *info.container);
    }
    if (scene_.output.contact_forces || final_state) {
      parts.push_back(name("contacts"));
      write_contacts_vtp((out_ / parts.back()).string(), state());
    }
    series_->add(state().time, parts);
  }

  // The pile measured from the particle positions, the final files and the record.
  PileRun finish() {
    const sim::State& st = state();
    PileRun r;
    // After a physics stop the state is not a pile (positions may not even be finite).
    if (ctl_.stop.is_physics())
      r.pile = unmeasured_pile("the run stopped on a physics failure: " + ctl_.stop.detail);
    else if (ctl_.stop.reason == StopReason::kClogged)
      r.pile = clogged_pile(ctl_.inside_last, ctl_.stop.detail);
    else
      r.pile = pile_measure(sim::measure_pile(st.particles.x, st.particles.radius, scene_.pile));
    write_vtp(path("final.vtp").string(), st.particles, frame_info(true), &st.bodies);
    write_frame(true);  // the series always ends with the final state
    save_checkpoint();
    const double wall_total = ctl_.wall_seconds + wall_now();
    r.provenance = provenance_;
    r.stop = ctl_.stop;
    r.psd = ctl_.psd;
    r.particles = {n0_, grain_count(st), ctl_.retained, ctl_.retained_mass};
    if (!scene_.shapes.empty()) r.shape = shape_record(scene_, sample_, st);
    const ProcedureConfig& pc = scene_.procedure;
    const ContainerConfig& c = scene_.container;
    r.procedure = {pc.lift_speed,     ctl_.lift_start,          ctl_.lift_end,     st.time,
                   pc.clog_window,    pc.max_retained_fraction, ctl_.ke_threshold, c.kind,
                   c.bottom_diameter, c.top_diameter,           c.height,          ctl_.events};
    r.performance = {
        st.step, wall_total, ctl_.cpu_seconds + cpu_now(),
        static_cast<double>(st.step) *
            static_cast<double>(r.shape ? r.shape->components_initial : n0_) /
            std::max(wall_total, 1e-9),
        st.neighbors.builds, ctl_.max_overlap_seen};
    write_json_atomic(path("result.json").string(), to_json(r));
    r.final_spheres = spheres_of(st);
    if (opt_.progress)
      std::fprintf(stderr, "%s: %s (%s) after %.3f s simulated, %.1f s wall; wrote %s\n",
                   scene_.name.c_str(), stop_reason_text(r.stop).c_str(), r.stop.detail.c_str(),
                   st.time, wall_total, path("result.json").string().c_str());
    return r;
  }

  const SceneConfig& scene_;
  const RunOptions& opt_;
  const fs::path out_;
  const std::chrono::steady_clock::time_point wall0_;
  const double cpu0_;  // the process's CPU time when this session of the run began [s]
  int material_ = 0;
  Controller ctl_;
  PileSample sample_;  // the sample as drawn (a fresh run; a resumed one of clumps)
  sim::Settings settings_;
  std::unique_ptr<sim::World> world_;
  std::unique_ptr<PvdSeries> series_;
  std::optional<FolderLock> lock_;
  RunProvenance provenance_;
  std::int64_t step0_ = 0;           // step at the start of this session
  std::int64_t n0_ = 0;              // the sample as filled [-]
  double last_progress_wall_ = 0.0;  // [s]
  double ke_last_ = 0.0;             // KE per particle at the last check [J]
};

}  // namespace

std::optional<PileRun> run_pile_test(const SceneConfig& scene, const RunOptions& opt) {
  return PileRunner(scene, opt).run();
}

std::optional<PileRun> run_pile_test_or_continue(const SceneConfig& scene, const RunOptions& opt) {
  const fs::path out(opt.out_dir);
  std::error_code ec;
  if (fs::is_regular_file(out / "result.json", ec)) {
    try {
      return pile_run_from_json(read_json_file((out / "result.json").string()));
    } catch (const std::exception&) {  // a damaged or foreign file: run again
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
