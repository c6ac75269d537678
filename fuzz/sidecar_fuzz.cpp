// Fuzz harness: a render's sidecar JSON (its camera, and the scale vision takes from it), as
// `reposetwin measure` and the loop's photo columns read one next to an image. Beyond a clear
// refusal, a property of what is accepted: the file itself holds every value the projection uses
// (nothing taken from a default camera), and the camera projects with a finite, positive focal
// length and a bounded distortion.
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "camera/camera.hpp"
#include "fuzz/fuzz_support.hpp"
#include "vision/measure.hpp"

namespace {

void check_complete(const std::string& path, const reposetwin::camera::Camera& cam) {
  using reposetwin::fuzz::finding;
  std::ifstream in(path);
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  if (j.is_discarded() || !j.is_object() || !j.contains("camera"))
    finding("an accepted sidecar has no camera object");
  const nlohmann::json& c = j["camera"];
  auto has = [&](const char* block, const char* key) {
    if (!c.contains(block) || !c[block].is_object() || !c[block].contains(key))
      finding(std::string("an accepted sidecar lacks ") + block + "." + key);
  };
  if (!c.contains("projection")) finding("an accepted sidecar lacks camera.projection");
  has("intrinsics", "width_px");
  has("intrinsics", "height_px");
  if (cam.projection == reposetwin::camera::Projection::kPerspective) {
    has("intrinsics", "focal_length_mm");
    has("intrinsics", "sensor_width_mm");
  } else {
    has("intrinsics", "ortho_width_m");
  }
  for (const char* key : {"position", "look_at", "up"}) has("extrinsics", key);
  const double f = reposetwin::camera::focal_px(cam);
  if (!(f > 0 && std::isfinite(f)))
    finding("an accepted sidecar's focal length is " + std::to_string(f));
  if (!(std::abs(cam.intrinsics.k1) <= 1 && std::abs(cam.intrinsics.k2) <= 1))
    finding("an accepted sidecar's distortion is out of bounds");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace reposetwin;
  const std::string path = fuzz::write_input(data, size, "fuzz_view.json");
  std::optional<camera::Camera> cam;
  fuzz::expect_clear_refusal("fuzz_view.json", [&] { cam = camera::read_sidecar(path); });
  if (cam) check_complete(path, *cam);
  fuzz::expect_clear_refusal("fuzz_view.json", [&] { (void)vision::scale_from_sidecar(path); });
  return 0;
}
