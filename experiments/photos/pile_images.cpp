#include "experiments/photos/pile_images.hpp"

#include <algorithm>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "experiments/io/provenance.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/vtk_output.hpp"
#include "render/output.hpp"
#include "render/renderer.hpp"
#include "render/scene.hpp"
#include "sim/pile_geometry.hpp"
#include "vision/measure.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;
using nlohmann::json;

render::Scene centred_pile_scene(const std::vector<Eigen::Vector3d>& positions,
                                 const std::vector<double>& radii,
                                 const std::vector<int>& materials, Eigen::Vector2d* shift) {
  // Centre the pile on the camera axis (the footprint centre, as sim/pile_geometry finds it).
  const sim::PileGeometry g = sim::measure_pile(positions, radii);
  render::Scene scene;
  scene.positions = positions;
  for (Eigen::Vector3d& x : scene.positions) {
    x.x() -= g.centre.x();
    x.y() -= g.centre.y();
  }
  if (shift) *shift = Eigen::Vector2d(g.centre.x(), g.centre.y());
  scene.radii = radii;
  scene.material_ids = materials;
  // The plate is as large as the lab's board must be: wider than the pile's footprint.
  scene.plate.half_size_m =
      std::max(scene.plate.half_size_m, 1.3 * render::pile_extent(scene).radius_m);
  return scene;
}

json render_and_measure(const std::vector<Eigen::Vector3d>& positions,
                        const std::vector<double>& radii, const std::vector<int>& materials,
                        const std::string& out_dir, const ImageSettings& settings,
                        const json& provenance) {
  if (settings.side_views < 1) throw InputError("images: side_views must be at least 1");
  Eigen::Vector2d centre;
  render::Scene scene = centred_pile_scene(positions, radii, materials, &centre);
  fs::create_directories(out_dir);
  render::Renderer renderer;
  render::RenderOptions options;
  options.tint_seed = settings.tint_seed;
  render::LabCameraSettings cams;
  cams.width_px = settings.width_px;
  cams.height_px = settings.height_px;
  cams.distance_radii = settings.distance_radii;
  cams.side_height_m = settings.camera_height_m;

  json views = json::array();
  std::vector<vision::SideMeasurement> sides;
  for (int k = 0; k < settings.side_views; ++k) {
    cams.azimuth_deg = 180.0 * k / settings.side_views;
    camera::Camera cam = render::lab_side_camera(scene, cams);
    cam.intrinsics.k1 = settings.k1;
    char stem[64];
    std::snprintf(stem, sizeof stem, "side_az%03d", static_cast<int>(cams.azimuth_deg + 0.5));
    const std::string base = (fs::path(out_dir) / stem).string();
    options.view = render::View::kSide;
    const cv::Mat image = render::render_and_write(renderer, scene, cam, options, base, provenance);
    const vision::SideMeasurement m = vision::measure_side_camera(image, cam, {}, base + ".png");
    cv::imwrite(base + ".measured.png", vision::draw_side_overlay(image, m));
    sides.push_back(m);
    json v = vision::to_json(m);
    v["image"] = std::string(stem) + ".png";
    v["azimuth_deg"] = cams.azimuth_deg;
    views.push_back(v);
  }
  const vision::SideSummary summary = vision::combine_sides(sides);
  json out = {{"method", "vision on renders: theta = atan(2H/D) per side view, perspective "
                         "corrected with the render's camera; mean and spread over azimuths"},
              {"side_views", views},
              {"side_summary", vision::to_json(summary)},
              {"theta_deg", summary.theta_deg.mean},
              {"theta_sd_deg", summary.theta_deg.stddev},
              {"height_m", summary.height_m.mean},
              {"diameter_m", summary.diameter_m.mean},
              {"flank_deg", summary.flank_deg.mean},
              {"pile_centre_shift_m", {centre.x(), centre.y()}},
              {"settings",
               {{"width_px", settings.width_px},
                {"height_px", settings.height_px},
                {"side_views", settings.side_views},
                {"camera_height_m", settings.camera_height_m},
                {"distance_radii", settings.distance_radii},
                {"k1", settings.k1}}},
              {"provenance", provenance},
              {"gl", renderer.gl_description()}};
  if (settings.top_view) {
    options.view = render::View::kTop;
    const camera::Camera cam = render::lab_top_camera(scene, cams);
    const std::string base = (fs::path(out_dir) / "top").string();
    const cv::Mat image = render::render_and_write(renderer, scene, cam, options, base, provenance);
    try {
      const vision::TopMeasurement m = vision::measure_top_camera(image, cam, {}, base + ".png");
      cv::imwrite(base + ".measured.png", vision::draw_top_overlay(image, m));
      out["top"] = vision::to_json(m);
    } catch (const std::exception& e) {
      // The footprint is a secondary quantity (the angle comes from the side views): a top view
      // that cannot be measured (a thin, patchy pile) is reported, not fatal.
      out["top"] = {{"error", e.what()}};
    }
    out["top"]["image"] = "top.png";
  }
  write_json_atomic((fs::path(out_dir) / "measurement.json").string(), out);
  return out;
}

json render_and_measure_run(const std::string& run_dir, const ImageSettings& settings,
                            const std::string& frame) {
  const fs::path dir(run_dir);
  const fs::path result = dir / "result.json";
  const fs::path snapshot = dir / (frame.empty() ? "final.vtp" : frame);
  if (!fs::exists(result))
    throw InputError(run_dir + ": not a finished run (result.json is missing)");
  if (!fs::exists(snapshot)) throw InputError(snapshot.string() + ": snapshot does not exist");
  const json r = json::parse(read_file(result.string()));
  if (frame.empty() && r.at("pile").at("status") == "no pile")
    throw InputError(run_dir + ": the run formed no pile (" +
                     r["stop"]["detail"].get<std::string>() + "); nothing to photograph");
  const SnapshotParticles p = read_vtp(snapshot.string());
  json prov = r.at("provenance");
  prov["run_dir"] = run_dir;
  prov["snapshot"] = snapshot.filename().string();
  const fs::path out = frame.empty() ? dir / "images" : dir / "images" / snapshot.stem();
  return render_and_measure(p.x, p.radius, p.material, out.string(), settings, prov);
}

}  // namespace reposetwin::experiments
