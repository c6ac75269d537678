#include "experiments/photos/pile_images.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "experiments/io/input_error.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/io/vtk_output.hpp"
#include "vision/measure.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// measurement.json: every view, the side summary, the top footprint, settings and provenance.
// A view vision could not measure is listed with its error; the summary is over the others
// (null when none measured).
json measurement_json(const PilePhotos& photos, const ImageSettings& settings,
                      const json& provenance) {
  json views = json::array();
  for (const SideView& v : photos.sides) {
    json j = v.measured ? vision::to_json(*v.measured) : json{{"error", v.error}};
    j["image"] = v.stem + ".png";
    j["azimuth_deg"] = v.azimuth_deg;
    views.push_back(j);
  }
  json out = {{"method",
               "vision on renders: theta = atan(2H/D) per side view, perspective "
               "corrected with the render's camera; mean and spread over azimuths"},
              {"side_views", views},
              {"pile_centre_shift_m", {photos.centre_shift.x(), photos.centre_shift.y()}},
              {"settings",
               {{"width_px", settings.width_px},
                {"height_px", settings.height_px},
                {"side_views", settings.side_views},
                {"camera_height_m", settings.camera_height_m},
                {"distance_radii", settings.distance_radii},
                {"k1", settings.k1},
                {"cameras", settings.lab_cameras.empty()
                                ? "the twin's framing (distance_radii pile radii away)"
                                : "the lab's sidecar cameras (" +
                                      std::to_string(settings.lab_cameras.size()) +
                                      " side views), as given"}}},
              {"provenance", provenance},
              {"gl", photos.gl}};
  if (photos.summary) {
    const vision::SideSummary& summary = *photos.summary;
    out["side_summary"] = vision::to_json(summary);
    // A picture that is not the settled pile has no headline: its numbers stay in the views,
    // under the warning, and nothing reads them as the pile's angle.
    if (settings.warning.empty()) {
      out["theta_deg"] = summary.theta_deg.mean;
      out["theta_sd_deg"] = summary.theta_deg.stddev;
      out["height_m"] = summary.height_m.mean;
      out["diameter_m"] = summary.diameter_m.mean;
      out["flank_deg"] = summary.flank_deg.mean;
      out["crest_width_m"] = summary.crest_width_m.mean;
    }
  }
  if (!settings.warning.empty()) {
    out["settled_pile"] = false;
    out["warning"] = settings.warning;
  }
  if (photos.top_taken) {
    out["top"] = photos.top ? vision::to_json(*photos.top) : json{{"error", photos.top_error}};
    out["top"]["image"] = "top.png";
  }
  return out;
}

}  // namespace

json render_and_measure(const PileSpheres& pile, const std::string& out_dir,
                        const ImageSettings& settings, const json& provenance,
                        std::optional<Eigen::Vector2d> centre,
                        const std::function<void()>& after_photographs) {
  const PilePhotos photos = photograph_pile(pile, settings, out_dir, provenance, centre);
  if (after_photographs) after_photographs();
  const json out = measurement_json(photos, settings, provenance);
  write_json_atomic((fs::path(out_dir) / "measurement.json").string(), out);
  return out;
}

json render_and_measure(const std::vector<Eigen::Vector3d>& positions,
                        const std::vector<double>& radii, const std::vector<int>& materials,
                        const std::string& out_dir, const ImageSettings& settings,
                        const json& provenance) {
  return render_and_measure(PileSpheres{positions, radii, materials}, out_dir, settings,
                            provenance);
}

namespace {

// A run's photographs, with its provenance and where the snapshot came from. The final pile is
// centred where the run measured it (with the scene's pile settings); a mid-run frame where
// its own footprint is.
json photograph_run(const PileRun& run, const PileSpheres& spheres, const std::string& run_dir,
                    const std::string& snapshot, const fs::path& out,
                    const ImageSettings& settings, const std::function<void()>& after) {
  // images -> elsewhere would aim the photographs (and --force's replacing) at another folder.
  refuse_escaping_links(run_dir);
  json prov = to_json(run.provenance);
  prov["run_dir"] = run_dir;
  prov["snapshot"] = snapshot;
  std::optional<Eigen::Vector2d> centre;
  if (snapshot == "final.vtp") centre = Eigen::Vector2d(run.pile.centre_x_m, run.pile.centre_y_m);
  return render_and_measure(spheres, out.string(), settings, prov, centre, after);
}

// A frame of the series is photographed as it was: the funnel where it stood, and, unless the
// run recorded it as the settled pile, with a warning instead of a headline, and views vision
// cannot read (a pile still pouring) recorded rather than fatal.
void frame_settings(const SnapshotParticles& p, const std::string& snapshot, ImageSettings& s) {
  if (p.info && p.info->container) {
    // The engine's wall is the funnel's inner surface; the camera sees the outer one, a steel
    // sheet's thickness out (grains touching the wall overlap it by a hair and would show
    // through a surface drawn exactly there).
    constexpr double kWallThickness = 1.5e-3;  // [m]
    const ShellPlacement& c = *p.info->container;
    const double out =
        kWallThickness * std::hypot(1.0, (c.r_top_m - c.r_bottom_m) / (c.z_top_m - c.z_bottom_m));
    render::Shell shell;
    shell.z_bottom_m = c.z_bottom_m;
    shell.z_top_m = c.z_top_m;
    shell.r_bottom_m = c.r_bottom_m + out;
    shell.r_top_m = c.r_top_m + out;
    s.shells.push_back(shell);
  }
  if (p.info && p.info->settled) return;
  char when[96] = "";
  if (p.info)
    std::snprintf(when, sizeof when, " (t = %.3f s, phase %s)", p.info->time_s,
                  p.info->phase.c_str());
  s.warning = "NOT A SETTLED PILE: " + fs::path(snapshot).filename().string() + when +
              (p.info ? "" : " carries no phase record") + "; not a measurement";
  s.views_must_measure = false;
}

}  // namespace

json render_and_measure_run(const PileRun& run, const std::string& run_dir,
                            const ImageSettings& settings,
                            const std::function<void()>& after_photographs) {
  if (run.final_spheres.x.empty())
    return render_and_measure_run(run_dir, settings, "", after_photographs);
  if (run.pile.status == sim::PileStatus::kNoPile)
    throw InputError(run_dir + ": the run formed no pile (" + run.stop.detail +
                     "); nothing to photograph");
  return photograph_run(run, run.final_spheres, run_dir, "final.vtp", fs::path(run_dir) / "images",
                        settings, after_photographs);
}

json render_and_measure_run(const std::string& run_dir, const ImageSettings& settings,
                            const std::string& frame,
                            const std::function<void()>& after_photographs) {
  const fs::path dir(run_dir);
  const fs::path result = dir / "result.json";
  const fs::path snapshot = dir / (frame.empty() ? "final.vtp" : frame);
  if (!fs::exists(result))
    throw InputError(run_dir + ": not a finished run (result.json is missing)");
  if (!fs::exists(snapshot)) throw InputError(snapshot.string() + ": snapshot does not exist");
  const PileRun run = pile_run_from_json(read_json_file(result.string()));
  if (frame.empty() && run.pile.status == sim::PileStatus::kNoPile)
    throw InputError(run_dir + ": the run formed no pile (" + run.stop.detail +
                     "); nothing to photograph");
  const SnapshotParticles p = read_vtp(snapshot.string());
  const fs::path out = frame.empty() ? dir / "images" : dir / "images" / snapshot.stem();
  ImageSettings s = settings;
  if (!frame.empty()) frame_settings(p, snapshot.string(), s);
  return photograph_run(run, PileSpheres{p.x, p.radius, p.material, p.body}, run_dir,
                        snapshot.filename().string(), out, s, after_photographs);
}

}  // namespace reposetwin::experiments
