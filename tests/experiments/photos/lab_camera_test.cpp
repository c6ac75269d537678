// The twin photographs its pile with the lab's own camera when the lab gives one (a sidecar per
// photo): same pose, lens, resolution and scale, as many views at the same azimuths. The check is
// against the sidecar's own projection (camera::project), not against our earlier output: the
// plate line vision detects in the twin's photo lies where the lab camera puts the plate at the
// pile axis, and the pile's axis stands in the column where it puts the axis.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "../../support/cone_pile.hpp"
#include "experiments/photos/lab_photos.hpp"
#include "experiments/photos/photographs.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;

// A lab sidecar as a lab writes it: the camera only, in camera::to_json's form.
std::string write_lab_sidecar(const fs::path& dir, const std::string& name,
                              const camera::Camera& cam) {
  fs::create_directories(dir);
  const fs::path p = dir / (name + ".json");
  std::ofstream(p) << nlohmann::json{{"camera", camera::to_json(cam)}}.dump(2);
  return p.string();
}

TEST(LabCamera, TwinPhotosAreTakenWithTheLabsCamera) {
  const test_support::Spheres s = test_support::make_cone(14e-3, 24e-3, 0.0, 0.0, 1.75e-3, 11, 0.3);
  const PileSpheres pile{{s.x.begin(), s.x.end()}, s.r, std::vector<int>(s.r.size(), 0)};
  const fs::path dir = fs::temp_directory_path() / "reposetwin_lab_camera";
  fs::remove_all(dir);
  // Two level lab cameras 0.3 m from the axis at azimuths 30 and 120 deg, 800 x 600 px, a field
  // 90 mm wide at the axis (the twin's own framing would be 960 x 720 at 12 pile radii = 0.29 m
  // and four views at 0, 45, 90, 135 deg).
  PhotoSettings settings;
  for (double az : {30.0, 120.0}) {
    const camera::Camera lab = camera::side_view(0.30, 0.09, 0.0, az, 800, 600);
    settings.lab_cameras.push_back(camera::read_sidecar(
        write_lab_sidecar(dir / "lab", "az" + std::to_string(static_cast<int>(az)), lab)));
  }
  settings.top_view = false;
  settings.scale_reference = false;
  settings.write_overlays = false;
  const PilePhotos photos = photograph_pile(pile, settings, (dir / "twin").string());
  ASSERT_EQ(photos.sides.size(), 2u);
  for (std::size_t i = 0; i < photos.sides.size(); ++i) {
    const SideView& v = photos.sides[i];
    const camera::Camera& lab = settings.lab_cameras[i];
    EXPECT_NEAR(v.azimuth_deg, i == 0 ? 30.0 : 120.0, 1e-9);
    EXPECT_EQ(camera::to_json(v.camera), camera::to_json(lab));
    // The photo has the lab's resolution, and its sidecar the lab's camera.
    const cv::Mat image = cv::imread((dir / "twin" / (v.stem + ".png")).string());
    EXPECT_EQ(image.cols, 800);
    EXPECT_EQ(image.rows, 600);
    const camera::Camera written =
        camera::read_sidecar((dir / "twin" / (v.stem + ".json")).string());
    EXPECT_EQ(camera::to_json(written), camera::to_json(lab));
    ASSERT_TRUE(v.measured) << v.error;
    const vision::SideProfile& p = v.measured->pixels;
    const auto foot = camera::project(lab, Eigen::Vector3d::Zero());
    ASSERT_TRUE(foot);
    EXPECT_NEAR(p.plate.v_at(foot->x()), foot->y(), 1.0) << v.stem;  // the plate line
    EXPECT_NEAR(0.5 * (p.toe_left.x + p.toe_right.x), foot->x(), 2.0) << v.stem;  // the axis
    EXPECT_NEAR(p.apex.x, foot->x(), 2.0) << v.stem;
    EXPECT_NEAR(v.measured->mm_per_px, camera::mm_per_px_at(lab, v.measured->base_center_m),
                1e-9);
    EXPECT_NEAR(1e3 * v.measured->height_m, 14.0, 0.5) << v.stem;
  }
  // The lab's photos measured with their sidecars hand back their cameras, for the twin's.
  std::vector<std::string> paths;
  for (const SideView& v : photos.sides) paths.push_back((dir / "twin" / (v.stem + ".png")).string());
  const LabPhotoMeasurement lab =
      measure_lab_photos(paths, {}, {"photos", "camera", "mm_per_px", "camera", "mm_per_px"});
  ASSERT_EQ(lab.cameras.size(), 2u);
  EXPECT_EQ(camera::to_json(lab.cameras[1]), camera::to_json(settings.lab_cameras[1]));
}

}  // namespace
}  // namespace reposetwin::experiments
