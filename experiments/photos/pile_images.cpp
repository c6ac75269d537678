#include "experiments/photos/pile_images.hpp"

#include <algorithm>
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
  const std::optional<vision::SideSummary>& summary = photos.summary;
  json out = {{"method",
               "vision on renders: theta = atan(2H/D) per side view, perspective "
               "corrected with the render's camera; mean and spread over azimuths"},
              {"side_views", views},
              {"side_summary", summary ? vision::to_json(*summary) : json()},
              {"theta_deg", summary ? json(summary->theta_deg.mean) : json()},
              {"theta_sd_deg", summary ? json(summary->theta_deg.stddev) : json()},
              {"height_m", summary ? json(summary->height_m.mean) : json()},
              {"diameter_m", summary ? json(summary->diameter_m.mean) : json()},
              {"flank_deg", summary ? json(summary->flank_deg.mean) : json()},
              {"pile_centre_shift_m", {photos.centre_shift.x(), photos.centre_shift.y()}},
              {"settings",
               {{"width_px", settings.width_px},
                {"height_px", settings.height_px},
                {"side_views", settings.side_views},
                {"camera_height_m", settings.camera_height_m},
                {"distance_radii", settings.distance_radii},
                {"k1", settings.k1}}},
              {"provenance", provenance},
              {"gl", photos.gl}};
  if (photos.top_taken) {
    out["top"] = photos.top ? vision::to_json(*photos.top) : json{{"error", photos.top_error}};
    out["top"]["image"] = "top.png";
  }
  return out;
}

}  // namespace

json render_and_measure(const PileSpheres& pile, const std::string& out_dir,
                        const ImageSettings& settings, const json& provenance,
                        std::optional<Eigen::Vector2d> centre) {
  const PilePhotos photos = photograph_pile(pile, settings, out_dir, provenance, centre);
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
                    const ImageSettings& settings) {
  json prov = to_json(run.provenance);
  prov["run_dir"] = run_dir;
  prov["snapshot"] = snapshot;
  std::optional<Eigen::Vector2d> centre;
  if (snapshot == "final.vtp") centre = Eigen::Vector2d(run.pile.centre_x_m, run.pile.centre_y_m);
  return render_and_measure(spheres, out.string(), settings, prov, centre);
}

}  // namespace

json render_and_measure_run(const PileRun& run, const std::string& run_dir,
                            const ImageSettings& settings) {
  if (run.final_spheres.x.empty()) return render_and_measure_run(run_dir, settings);
  if (run.pile.status == sim::PileStatus::kNoPile)
    throw InputError(run_dir + ": the run formed no pile (" + run.stop.detail +
                     "); nothing to photograph");
  return photograph_run(run, run.final_spheres, run_dir, "final.vtp", fs::path(run_dir) / "images",
                        settings);
}

json render_and_measure_run(const std::string& run_dir, const ImageSettings& settings,
                            const std::string& frame) {
  const fs::path dir(run_dir);
  const fs::path result = dir / "result.json";
  const fs::path snapshot = dir / (frame.empty() ? "final.vtp" : frame);
  if (!fs::exists(result))
    throw InputError(run_dir + ": not a finished run (result.json is missing)");
  if (!fs::exists(snapshot)) throw InputError(snapshot.string() + ": snapshot does not exist");
  const PileRun run = pile_run_from_json(json::parse(read_file(result.string())));
  if (frame.empty() && run.pile.status == sim::PileStatus::kNoPile)
    throw InputError(run_dir + ": the run formed no pile (" + run.stop.detail +
                     "); nothing to photograph");
  const SnapshotParticles p = read_vtp(snapshot.string());
  const fs::path out = frame.empty() ? dir / "images" : dir / "images" / snapshot.stem();
  return photograph_run(run, PileSpheres{p.x, p.radius, p.material, p.body}, run_dir,
                        snapshot.filename().string(), out, settings);
}

}  // namespace reposetwin::experiments
