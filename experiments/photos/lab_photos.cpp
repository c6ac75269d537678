#include "experiments/photos/lab_photos.hpp"

#include "experiments/io/numbers.hpp"

#include "experiments/io/files.hpp"

#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "experiments/io/format.hpp"
#include "experiments/io/input_error.hpp"
#include "vision/image.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// Restores OpenCV's thread count when the measurement ends, also by an exception.
class SingleOpenCvThread {
 public:
  SingleOpenCvThread() : old_(cv::getNumThreads()) { cv::setNumThreads(1); }
  ~SingleOpenCvThread() { cv::setNumThreads(old_); }
  SingleOpenCvThread(const SingleOpenCvThread&) = delete;
  SingleOpenCvThread& operator=(const SingleOpenCvThread&) = delete;

 private:
  int old_;
};

}  // namespace

LabPhotoMeasurement measure_lab_photos(const std::vector<std::string>& photos,
                                       const LabPhotoScale& scale, const LabPhotoFields& fields,
                                       bool draw_overlays) {
  if (photos.empty()) throw InputError(fields.photo + ": no photo given");
  refuse_repeated_contents(photos, fields.photo);
  vision::ScaleSpec common;
  if (!scale.camera_json.empty()) {
    try {
      common = vision::scale_from_sidecar(scale.camera_json);
    } catch (const std::exception& e) {
      throw InputError(fields.camera + ": " + e.what());
    }
    common.search_marker = false;
  } else if (scale.mm_per_px) {
    common.mm_per_px = positive_finite(*scale.mm_per_px, fields.mm_per_px);
    common.search_marker = false;
  }
  const bool declared_scale = !scale.camera_json.empty() || scale.mm_per_px.has_value();
  const SingleOpenCvThread one_thread;
  std::vector<vision::SideMeasurement> views;
  std::vector<camera::Camera> cameras;
  std::vector<cv::Mat> overlays;
  json unmeasured = json::array();
  for (const std::string& p : photos) {
    cv::Mat image;
    try {
      image = vision::load_image(p);  // refuses an oversized image before decoding it
    } catch (const std::invalid_argument& e) {
      throw InputError(fields.photo + ": \"" + p + "\" cannot be read as an image (" + e.what() +
                       ")");
    }
    vision::ScaleSpec this_scale = common;
    const fs::path sidecar = fs::path(p).replace_extension(".json");
    const bool own_sidecar = !declared_scale && fs::exists(sidecar);
    if (own_sidecar) {  // a render-style sidecar next to the photo gives its camera
      try {
        this_scale = vision::scale_from_sidecar(sidecar.string());
      } catch (const std::exception& e) {
        throw InputError(fields.photo + ": sidecar " + e.what());
      }
      this_scale.search_marker = false;
    }
    if (this_scale.camera) cameras.push_back(*this_scale.camera);
    try {
      views.push_back(vision::measure_side(image, this_scale, {}, p));
      // A measure vision says may be biased is no measure: refused like a contradicted pose.
      if (const auto w = vision::first_biasing_warning(views.back())) {
        views.pop_back();
        throw vision::PoseContradiction(p + ": not measured through the declared camera (" +
                                        vision::to_string(w->kind) + "): " + w->text);
      }
      if (draw_overlays) overlays.push_back(vision::draw_side_overlay(image, views.back()));
    } catch (const vision::Refusal& e) {
      // A photo that fails an admission check (vision/admission.hpp) gives no number; the test
      // goes on with its other photos, and the record says which check refused which photo.
      if (photos.size() == 1)
        throw InputError(fields.photo + ": " + e.what() + " (refused by the " +
                         vision::to_string(e.check()) + " check)");
      unmeasured.push_back({{"photo", p}, {"check", vision::to_string(e.check())},
                            {"error", e.what()}});
    } catch (const std::exception& e) {
      // A photo without any scale source is an error at once; with several photos of one test,
      // one that cannot be measured is recorded and the others still count.
      const bool no_scale = !declared_scale && !own_sidecar;
      if (no_scale || photos.size() == 1)
        throw InputError(fields.photo + ": " + e.what() +
                         (no_scale ? " (give the photo's scale: a " + fields.camera_name +
                                         " sidecar JSON or " + fields.mm_per_px_name + ")"
                                   : std::string()));
      unmeasured.push_back({{"photo", p}, {"check", nullptr}, {"error", e.what()}});
    }
  }
  if (views.empty()) {
    std::string why;
    for (const json& u : unmeasured)
      why += (why.empty() ? "" : "; ") + u["photo"].get<std::string>() + ": " +
             (u["check"].is_string() ? "refused by the " + u["check"].get<std::string>() + " check"
                                     : u["error"].get<std::string>());
    throw InputError(fields.photo + ": none of the " + std::to_string(photos.size()) +
                     " photos could be measured (" + why + "; first: " +
                     unmeasured[0]["error"].get<std::string>() + ")");
  }
  LabPhotoMeasurement m;
  m.summary = vision::combine_sides(views);
  m.record = vision::to_json(m.summary);
  m.record["views"] = json::array();
  for (const auto& v : views) m.record["views"].push_back(vision::to_json(v));
  m.record["unmeasured"] = unmeasured;
  m.cameras = std::move(cameras);
  m.overlays = std::move(overlays);
  return m;
}

}  // namespace reposetwin::experiments
