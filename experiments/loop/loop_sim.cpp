#include "experiments/loop/loop_sim.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "experiments/campaign/campaign.hpp"
#include "experiments/io/format.hpp"
#include "experiments/io/overrides.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/io/scene.hpp"
#include "experiments/io/vtk_output.hpp"
#include "experiments/photos/photographs.hpp"
#include "experiments/pile/pile_run.hpp"
#include "vision/measure.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::string num(double v) { return significant(v, 9); }

// A pile run: what its case function needs.
struct SimJob {
  std::string scene_path;
  std::vector<std::string> sets;  // key=value, in order
  std::uint64_t seed = 1;
};

// A photograph of a finished pile run.
struct PhotoJob {
  std::string sim_run_dir;  // absolute: <cache>/sim_<h>/seed_<n>/run
  ImageVariant variant;
};

SceneConfig job_scene(const SimJob& job) {
  std::vector<Override> overrides;
  for (const std::string& s : job.sets) overrides.push_back(parse_override(s, job.scene_path));
  SceneDoc doc(job.scene_path, overrides, job.scene_path);
  doc.set_seed(job.seed);
  // The loop needs the final pile only: no frame series.
  doc.final_frame_only();
  return doc.config();
}

Campaign cache_campaign(const std::string& dir) {
  Campaign c;
  c.name = "loop_cache";
  c.file = dir;
  c.scene_path = dir;
  return c;
}

// run_batch with the cache's lock: another process (a parallel test) may hold the folder for a
// while; wait for it instead of failing.
std::vector<json> batch_with_retry(const std::string& dir, const std::vector<CaseSpec>& runs,
                                   const CaseFn& fn, const RunnerSettings& rs) {
  for (int attempt = 0;; ++attempt) {
    try {
      return run_batch(cache_campaign(dir), runs, dir, fn, rs);
    } catch (const FolderBusy&) {
      if (attempt > 3600) throw;
      std::this_thread::sleep_for(std::chrono::milliseconds(500));
    }
  }
}

}  // namespace

std::string ImageVariant::key() const {
  std::ostringstream s;
  s << width_px << "x" << height_px << "_v" << side_views << "_d" << num(distance_radii) << "_h"
    << num(camera_height_m) << "_k" << num(k1) << "_dh" << num(declared_height_m) << "_dk"
    << num(declared_k1) << "_n" << num(noise_sd) << "_s" << noise_seed
    << (keep_photos ? "_keep" : "") << (keep_overlays ? "_ovl" : "")
    << (aim_at_axis_foot ? "_aim" : "");
  // Absent lab cameras leave the key as it was, so photos cached without them stay valid.
  if (!lab_cameras.empty()) {
    json cams = json::array();
    for (const camera::Camera& c : lab_cameras) cams.push_back(camera::to_json(c));
    s << "_cam" << lab_cameras.size() << "_" << fnv1a_hex(cams.dump());
  }
  return s.str();
}

std::vector<std::string> resolved_overrides(const SimRequest& r) {
  std::vector<std::string> out;
  std::map<std::string, std::size_t> at;
  auto add = [&](const std::string& k, const std::string& v) {
    if (auto it = at.find(k); it != at.end()) {
      out[it->second] = k + "=" + v;
    } else {
      at[k] = out.size();
      out.push_back(k + "=" + v);
    }
  };
  for (const auto& [k, v] : r.test->overrides) add(k, v);
  for (const auto& [k, v] : r.extra) add(k, v);
  return out;
}

PhotoSettings photo_settings(const ImageVariant& v) {
  if (v.side_views < 1) throw InputError("loop images: side_views must be at least 1");
  PhotoSettings s;
  s.width_px = v.width_px;
  s.height_px = v.height_px;
  s.side_views = v.side_views;
  s.top_view = false;
  s.distance_radii = v.distance_radii;
  s.camera_height_m = v.camera_height_m;
  s.k1 = v.k1;
  s.aim_at_axis_foot = v.aim_at_axis_foot;
  if (v.lab_cameras.empty()) {
    s.declared_height_m = v.declared_height_m;
    s.declared_k1 = v.declared_k1;
  }
  // The lab's cameras as declared are what the measurement assumes; the true ones carry the
  // measurement effects (a level raise keeps the lab camera's pitch; an aimed one looks at the
  // axis foot).
  const double raise = v.camera_height_m - v.declared_height_m;
  for (const camera::Camera& lab : v.lab_cameras) {
    camera::Camera truth = lab;
    truth.extrinsics.position.z() += raise;
    truth.extrinsics.look_at.z() += raise;
    if (v.aim_at_axis_foot) truth.extrinsics.look_at = Eigen::Vector3d::Zero();
    truth.intrinsics.k1 += v.k1 - v.declared_k1;
    s.lab_cameras.push_back(truth);
    s.declared_cameras.push_back(lab);
  }
  s.noise_sd = v.noise_sd;
  s.noise_seed = v.noise_seed;
  s.tint_seed = v.noise_seed;
  // The scale comes from the camera (sidecar), so no scale bar: the pile fills the frame
  // (a 10-band bar is taller than a small pile and would shrink it to a few pixels).
  s.scale_reference = false;
  s.write_photos = v.keep_photos;
  s.write_overlays = v.keep_overlays;
  s.views_must_measure = false;  // a small pile's pours are repeated when no view measures
  return s;
}

json photograph_pile(const std::vector<Eigen::Vector3d>& positions,
                     const std::vector<double>& radii, const std::vector<int>& materials,
                     const ImageVariant& v, const std::string& out_dir) {
  const PhotoSettings s = photo_settings(v);
  const PilePhotos photos = photograph_pile(PileSpheres{positions, radii, materials}, s, out_dir);
  json views = json::array();
  for (const SideView& view : photos.sides) {
    json j = view.measured ? vision::to_json(*view.measured) : json{{"error", view.error}};
    j["azimuth_deg"] = view.azimuth_deg;
    if (v.keep_photos) j["photo"] = view.stem + ".png";
    if (v.keep_overlays && view.measured) j["overlay"] = view.stem + ".measured.png";
    views.push_back(j);
  }
  // A pile too small for any view (a few spheres through a jammed outlet) has no angle: the
  // caller counts it as a pour that formed no pile.
  if (!photos.summary)
    return {{"error", "no side view of the pile could be measured: " +
                          views[0]["error"].get<std::string>()},
            {"views", views},
            {"variant", v.key()}};
  const vision::SideSummary& m = *photos.summary;
  return {{"angle_deg", m.theta_deg.mean},
          {"angle_sd_deg", m.theta_deg.stddev},
          {"flank_deg", m.flank_deg.mean},
          {"height_mm", 1e3 * m.height_m.mean},
          {"diameter_mm", 1e3 * m.diameter_m.mean},
          {"crest_width_mm", 1e3 * m.crest_width_m.mean},
          {"views", views},
          {"variant", v.key()}};
}

std::vector<std::vector<std::size_t>> pour_groups(const std::vector<int>& jams) {
  std::vector<std::size_t> jammed, rest;
  for (std::size_t i = 0; i < jams.size(); ++i) (jams[i] > 0 ? jammed : rest).push_back(i);
  if (jammed.empty() || rest.empty()) {
    jammed.insert(jammed.end(), rest.begin(), rest.end());
    return {jammed};
  }
  return {jammed, rest};
}

std::vector<SimOutcome> run_repouring(
    const std::vector<SimRequest>& requests, int max_pours,
    const std::function<std::vector<SimOutcome>(const std::vector<SimRequest>&)>& run) {
  if (max_pours < 1)
    throw std::invalid_argument("loop: max_pours must be at least 1, got " +
                                std::to_string(max_pours));
  std::vector<SimOutcome> out = run(requests);
  for (int pour = 1; pour < max_pours; ++pour) {
    std::vector<std::size_t> again;
    std::vector<SimRequest> repeat;
    for (std::size_t i = 0; i < out.size(); ++i) {
      if (out[i].pile) continue;
      again.push_back(i);
      repeat.push_back(requests[i]);
      repeat.back().seed = requests[i].seed + static_cast<std::uint64_t>(pour) * kRepourSeedStride;
    }
    if (again.empty()) break;
    const std::vector<SimOutcome> got = run(repeat);
    for (std::size_t k = 0; k < again.size(); ++k) {
      out[again[k]] = got[k];
      out[again[k]].clogged_pours = pour;
    }
  }
  return out;
}

std::string sim_case_name(const std::string& scene_hash, const std::vector<std::string>& sets,
                          const std::string& version) {
  std::string key = scene_hash;
  for (const auto& s : sets) key += "\n" + s;
  return "sim_" + fnv1a_hex(key + "\ncode " + version);
}

SimCache::SimCache(std::string dir, SimCacheSettings settings)
    : dir_(fs::absolute(dir).lexically_normal().string()), settings_(settings) {
  fs::create_directories(dir_);
}

std::vector<SimOutcome> SimCache::run(const std::vector<SimRequest>& requests) {
  // 1. Pile runs, one per distinct (scene text, overrides, seed).
  std::map<std::string, SimJob> sim_jobs;  // case name -> job
  std::vector<CaseSpec> sim_specs;
  std::vector<std::string> sim_of(requests.size());
  std::map<std::string, std::string> scene_hash;  // path -> hash of its text
  for (std::size_t i = 0; i < requests.size(); ++i) {
    const SimRequest& r = requests[i];
    if (r.test == nullptr) throw std::invalid_argument("SimCache: request without a test");
    SimJob job{r.test->scene_path, resolved_overrides(r), r.seed};
    if (!scene_hash.count(job.scene_path))
      scene_hash[job.scene_path] = fnv1a_hex(read_file(job.scene_path));
    const std::string name =
        sim_case_name(scene_hash[job.scene_path], job.sets, engine_version());
    sim_of[i] = name + "/seed_" + std::to_string(r.seed);
    if (sim_jobs.count(sim_of[i])) continue;
    sim_jobs[sim_of[i]] = job;
    CaseSpec spec;
    spec.case_name = name;
    spec.seed = r.seed;
    spec.scene_path = job.scene_path;
    spec.scene_hash = scene_hash[job.scene_path];
    for (std::size_t k = 0; k < job.sets.size(); ++k)
      set_override(spec.overrides, string_override(std::to_string(k), job.sets[k]));
    sim_specs.push_back(spec);
  }
  RunnerSettings rs;
  rs.workers = settings_.workers;
  rs.progress = settings_.progress;
  rs.rank = std::nullopt;
  for (const CaseSpec& s : sim_specs)
    if (!fs::exists(fs::path(dir_) / s.relative_dir() / "result.json")) ++started_sims_;
  const CaseFn sim_fn = [sim_jobs](const CaseSpec& spec, const std::string& case_dir) -> json {
    const SimJob& job = sim_jobs.at(spec.id());
    const SceneConfig scene = job_scene(job);
    RunOptions opt;
    opt.out_dir = (fs::path(case_dir) / "run").string();
    opt.progress = false;
    opt.threads = 1;
    opt.extra_provenance = {{"loop_overrides", job.sets}};
    // A killed run continues from its checkpoint.
    const std::optional<PileRun> run = run_pile_test_or_continue(scene, opt);
    if (!run) throw std::logic_error(opt.out_dir + ": a loop run has no stop limit, yet stopped");
    return {{"stop", to_json(run->stop)},
            {"pile", to_json(run->pile)},
            {"provenance", to_json(run->provenance)},
            {"overrides", job.sets}};
  };
  const std::vector<json> sims = batch_with_retry(dir_, sim_specs, sim_fn, rs);
  std::map<std::string, json> sim_result;
  for (std::size_t k = 0; k < sim_specs.size(); ++k) sim_result[sim_specs[k].id()] = sims[k];

  // 2. Photographs of the piles that formed.
  std::map<std::string, PhotoJob> photo_jobs;
  std::vector<CaseSpec> photo_specs;
  std::vector<std::string> photo_of(requests.size());
  for (std::size_t i = 0; i < requests.size(); ++i) {
    if (sim_result[sim_of[i]].at("pile").at("status") != "ok") continue;
    const ImageVariant& v = requests[i].image;
    const std::string name = "img_" + fnv1a_hex(sim_of[i] + "\n" + v.key() + "\n" + imaging_version());
    photo_of[i] = name + "/seed_" + std::to_string(requests[i].seed);
    if (photo_jobs.count(photo_of[i])) continue;
    photo_jobs[photo_of[i]] = {(fs::path(dir_) / "cases" / sim_of[i] / "run").string(), v};
    CaseSpec spec;
    spec.case_name = name;
    spec.seed = requests[i].seed;
    spec.scene_path = sim_of[i];
    spec.scene_hash = v.key();
    photo_specs.push_back(spec);
  }
  for (const CaseSpec& s : photo_specs)
    if (!fs::exists(fs::path(dir_) / s.relative_dir() / "result.json")) ++started_photos_;
  const CaseFn photo_fn = [photo_jobs](const CaseSpec& spec, const std::string& case_dir) -> json {
    const PhotoJob& job = photo_jobs.at(spec.id());
    const SnapshotParticles p = read_vtp((fs::path(job.sim_run_dir) / "final.vtp").string());
    return photograph_pile(p.x, p.radius, p.material, job.variant, case_dir);
  };
  // Photographs run on threads: each keeps its renderer from job to job (a forked job would
  // build a GL context and compile the shaders again, about half of a small pile's photo time).
  RunnerSettings photo_rs = rs;
  photo_rs.mode = WorkerMode::kThreads;
  const std::vector<json> photos = batch_with_retry(dir_, photo_specs, photo_fn, photo_rs);
  std::map<std::string, json> photo_result;
  for (std::size_t k = 0; k < photo_specs.size(); ++k) photo_result[photo_specs[k].id()] = photos[k];

  std::vector<SimOutcome> out(requests.size());
  for (std::size_t i = 0; i < requests.size(); ++i) {
    const json& s = sim_result[sim_of[i]];
    SimOutcome& o = out[i];
    o.sim_dir = (fs::path(dir_) / "cases" / sim_of[i]).string();
    o.provenance = s.at("provenance");
    o.seed = requests[i].seed;
    if (photo_of[i].empty()) continue;
    const json& p = photo_result[photo_of[i]];
    o.image_dir = (fs::path(dir_) / "cases" / photo_of[i]).string();
    o.views = p.value("views", json::array());
    if (p.contains("error")) {
      o.no_pile = p.at("error").get<std::string>();
      continue;
    }
    o.pile = true;
    o.angle_deg = p.at("angle_deg");
    o.flank_deg = p.value("flank_deg", std::numeric_limits<double>::quiet_NaN());
    o.height_mm = p.at("height_mm");
    o.diameter_mm = p.at("diameter_mm");
    o.crest_mm = p.value("crest_width_mm", std::numeric_limits<double>::quiet_NaN());
    o.positions_angle_deg = s.at("pile").value("theta_hd_deg", 0.0);
  }
  return out;
}

}  // namespace reposetwin::experiments
