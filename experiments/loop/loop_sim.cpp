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
            {"views", views}};
  const vision::SideSummary& m = *photos.summary;
  return {{"angle_deg", m.theta_deg.mean},
          {"angle_sd_deg", m.theta_deg.stddev},
          {"flank_deg", m.flank_deg.mean},
          {"height_mm", 1e3 * m.height_m.mean},
          {"diameter_mm", 1e3 * m.diameter_m.mean},
          {"crest_width_mm", 1e3 * m.crest_width_m.mean},
          {"views", views}};
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

PileRequest pile_request(const SimRequest& r) {
  if (r.test == nullptr) throw std::invalid_argument("SimCache: request without a test");
  PileRequest out;
  out.scene_path = r.test->scene_path;
  for (const std::string& set : resolved_overrides(r))
    out.overrides.push_back(parse_override(set, r.test->scene_path));
  out.seed = r.seed;
  out.photo = PhotoRequest{photo_settings(r.image), false, PhotographWhen::kFormed};
  return out;
}

namespace {

// The photograph's views as the loop's page reads them: each view's measurement, its azimuth,
// and the names of its photo and overlay when they were written.
json loop_views(const PhotoOutcome& p, const ImageVariant& v) {
  json views = json::array();
  for (json view : p.side_views) {
    const std::string image = view.value("image", std::string());
    view.erase("image");
    const std::string stem = fs::path(image).stem().string();
    if (v.keep_photos) view["photo"] = image;
    if (v.keep_overlays && !view.contains("error")) view["overlay"] = stem + ".measured.png";
    views.push_back(view);
  }
  return views;
}

}  // namespace

SimOutcome sim_outcome(const PileOutcome& o, const ImageVariant& v, std::uint64_t seed) {
  SimOutcome out;
  out.sim_dir = fs::path(o.run_dir).parent_path().string();
  out.provenance = to_json(o.provenance);
  out.seed = seed;
  if (!o.photo) return out;
  const PhotoOutcome& p = *o.photo;
  out.image_dir = p.dir;
  out.views = loop_views(p, v);
  if (!p.measured) {
    out.no_pile = p.error;
    return out;
  }
  out.pile = true;
  out.angle_deg = p.measured->theta_deg;
  out.flank_deg = p.measured->flank_deg;
  out.height_mm = 1e3 * p.measured->height_m;
  out.diameter_mm = 1e3 * p.measured->diameter_m;
  out.crest_mm = 1e3 * p.measured->crest_width_m;
  out.positions_angle_deg = o.pile.theta_hd_deg;
  return out;
}

SimCache::SimCache(std::string dir, SimCacheSettings settings)
    : service_(std::move(dir), PileServiceSettings{settings.workers, 1, false, settings.progress}) {}

std::vector<SimOutcome> SimCache::run(const std::vector<SimRequest>& requests) {
  std::vector<PileRequest> piles;
  piles.reserve(requests.size());
  for (const SimRequest& r : requests) piles.push_back(pile_request(r));
  const std::vector<PileOutcome> got = service_.run(piles);
  std::vector<SimOutcome> out;
  out.reserve(got.size());
  for (std::size_t i = 0; i < got.size(); ++i)
    out.push_back(sim_outcome(got[i], requests[i].image, requests[i].seed));
  return out;
}

}  // namespace reposetwin::experiments
