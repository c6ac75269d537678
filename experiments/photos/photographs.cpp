#include "experiments/photos/photographs.hpp"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "experiments/io/input_error.hpp"
#include "experiments/io/provenance.hpp"
#include "render/output.hpp"
#include "render/renderer.hpp"
#include "sim/pile_geometry.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;

render::Scene centred_pile_scene(const PileSpheres& pile, std::optional<Eigen::Vector2d> centre,
                                 Eigen::Vector2d* shift) {
  if (!centre) {
    const sim::PileGeometry g = sim::measure_pile(pile.x, pile.radius);
    centre = Eigen::Vector2d(g.centre.x(), g.centre.y());
  }
  render::Scene scene;
  scene.positions = pile.x;
  for (Eigen::Vector3d& x : scene.positions) {
    x.x() -= centre->x();
    x.y() -= centre->y();
  }
  if (shift) *shift = *centre;
  scene.radii = pile.radius;
  scene.material_ids = pile.material;
  // A clump's components share their grain's tone; a loose sphere (-1) is a grain of its own.
  if (!pile.body.empty()) {
    scene.body_ids.resize(pile.body.size());
    for (std::size_t i = 0; i < pile.body.size(); ++i)
      scene.body_ids[i] = pile.body[i] >= 0 ? pile.body[i] : -static_cast<std::int64_t>(i) - 1;
  }
  // The plate is as large as the lab's board must be: wider than the pile's footprint.
  scene.plate.half_size_m =
      std::max(scene.plate.half_size_m, 1.3 * render::pile_extent(scene).radius_m);
  return scene;
}

namespace {

// The side camera the measurement assumes: the true one unless the settings declare another
// height or distortion (a lab that does not know its camera is high measures as if level).
camera::Camera declared_camera(const camera::Camera& truth, const PhotoSettings& s) {
  camera::Camera declared = truth;
  if (s.declared_height_m) {
    declared.extrinsics.position.z() = *s.declared_height_m;
    declared.extrinsics.look_at.z() = *s.declared_height_m;
  }
  if (s.declared_k1) declared.intrinsics.k1 = *s.declared_k1;
  return declared;
}

void add_noise(cv::Mat& image, double sd, cv::RNG& rng) {
  cv::Mat noise(image.size(), CV_32FC(image.channels()));
  rng.fill(noise, cv::RNG::NORMAL, 0.0, sd);
  cv::Mat f;
  image.convertTo(f, CV_32F);
  f += noise;
  f.convertTo(image, image.type());  // saturating
}

// A lab picks a ruler to suit its pile: the bar stands a little taller than the pile, so the
// frame, which must hold both, is filled by the pile. At least 7 bands (4 black): the bottom
// black band meets the dark plate edge and merges with it in vision's dark class, and vision's
// bar finder needs 3 black bands clear of it.
int bar_bands(const render::Scene& scene) {
  const double band = 1e-3 * scene.scale_reference.band_mm;
  const double height = std::max(render::pile_extent(scene).z_max_m, 0.0);
  const int bands = static_cast<int>(std::ceil(1.2 * height / band));
  return std::clamp(bands, 7, std::max(scene.scale_reference.count, 7));
}

// The warning across the top of an overlay, white on red, readable at any image size.
cv::Mat stamp_warning(cv::Mat overlay, const std::string& warning) {
  if (warning.empty()) return overlay;
  const double scale = std::max(0.5, overlay.cols / 1600.0);
  const int thickness = std::max(1, static_cast<int>(2 * scale));
  int baseline = 0;
  const cv::Size text =
      cv::getTextSize(warning, cv::FONT_HERSHEY_SIMPLEX, scale, thickness, &baseline);
  const int pad = static_cast<int>(10 * scale);
  cv::rectangle(overlay, cv::Rect(0, 0, overlay.cols, text.height + baseline + 2 * pad),
                cv::Scalar(40, 40, 200), cv::FILLED);
  cv::putText(overlay, warning, cv::Point(pad, pad + text.height), cv::FONT_HERSHEY_SIMPLEX, scale,
              cv::Scalar(255, 255, 255), thickness, cv::LINE_AA);
  return overlay;
}

std::string side_stem(double azimuth_deg) {
  char stem[32];
  std::snprintf(stem, sizeof stem, "side_az%03d", static_cast<int>(azimuth_deg + 0.5));
  return stem;
}

// A side camera's azimuth about the pile axis in camera::side_view's convention (0 = from -y,
// 90 = from +x) [deg], in [0, 360).
double azimuth_of(const camera::Camera& cam) {
  const Eigen::Vector3d& p = cam.extrinsics.position;
  const double a = std::atan2(p.x(), -p.y()) * 180.0 / 3.14159265358979323846;
  return a < 0.0 ? a + 360.0 : a;
}

// The side views' true cameras: the lab's, or the twin's framing at azimuths over 180 degrees.
std::vector<camera::Camera> side_cameras(const render::Scene& scene, const PhotoSettings& s,
                                         render::LabCameraSettings cams) {
  if (!s.lab_cameras.empty()) {
    std::vector<camera::Camera> out = s.lab_cameras;
    for (std::size_t i = 0; i < out.size(); ++i) {
      if (s.aim_at_axis_foot) out[i].extrinsics.look_at = Eigen::Vector3d::Zero();
      camera::validate(out[i], "images: lab camera " + std::to_string(i + 1));
    }
    return out;
  }
  std::vector<camera::Camera> out;
  // A pitched camera centred on the foot: a shift lens framed for a level view would push the
  // pile out of the top of the picture.
  if (s.aim_at_axis_foot) cams.shift_lens = false;
  for (int k = 0; k < s.side_views; ++k) {
    cams.azimuth_deg = 180.0 * k / s.side_views;
    camera::Camera truth = render::lab_side_camera(scene, cams);
    truth.intrinsics.k1 = s.k1;
    if (s.aim_at_axis_foot) truth.extrinsics.look_at = Eigen::Vector3d::Zero();
    out.push_back(truth);
  }
  return out;
}

// This thread's renderer, kept for the thread's life: creating the GL context, compiling the
// shaders and llvmpipe's compile of them at the first draw cost about 0.3 s, more than
// photographing a small pile, and a loop photographs thousands (on threads, loop_sim.cpp). A
// reused renderer gives the same bytes as a fresh one (tests/render:
// SameInputRendersBitIdentically). One per thread, never handed to another: a context left current
// in a thread that makes another one current is released there, under the other thread's feet. A
// process forked after it rendered cannot render: llvmpipe's rasteriser threads are process-wide
// and do not exist in the child, where any new context waits on them forever. So a child asking for
// a renderer gets an error, not a hang; callers photograph on threads, or in children of a process
// that has not rendered (the campaign's pool). An overlay PNG: a file that cannot be written (a
// full disk, a read-only folder) is an error naming it and the reason, never a photograph silently
// missing.
void write_overlay(const std::string& path, const cv::Mat& image) {
  write_image_atomic(path, image);
}

render::Renderer& thread_renderer() {
  static std::atomic<pid_t> rendering_process{0};
  pid_t first = 0;
  if (!rendering_process.compare_exchange_strong(first, ::getpid()) && first != ::getpid())
    throw std::logic_error(
        "render: this process was forked after its parent rendered (llvmpipe's threads are not "
        "in the child, so a render would hang); photograph on threads or before forking");
  thread_local render::Renderer renderer;
  return renderer;
}

}  // namespace

nlohmann::json to_json(const PhotoSettings& s) {
  const auto opt = [](const std::optional<double>& v) {
    return v ? nlohmann::json(*v) : nlohmann::json(nullptr);
  };
  const auto cams = [](const std::vector<camera::Camera>& cs) {
    nlohmann::json a = nlohmann::json::array();
    for (const camera::Camera& c : cs) a.push_back(camera::to_json(c));
    return a;
  };
  nlohmann::json shells = nlohmann::json::array();
  for (const render::Shell& sh : s.shells)
    shells.push_back({sh.z_bottom_m, sh.z_top_m, sh.r_bottom_m, sh.r_top_m, sh.color.r,
                      sh.color.g, sh.color.b});
  return {{"width_px", s.width_px},
          {"height_px", s.height_px},
          {"side_views", s.side_views},
          {"top_view", s.top_view},
          {"distance_radii", s.distance_radii},
          {"camera_height_m", s.camera_height_m},
          {"k1", s.k1},
          {"aim_at_axis_foot", s.aim_at_axis_foot},
          {"declared_height_m", opt(s.declared_height_m)},
          {"declared_k1", opt(s.declared_k1)},
          {"noise_sd", s.noise_sd},
          {"noise_seed", s.noise_seed},
          {"tint_seed", s.tint_seed},
          {"scale_reference", s.scale_reference},
          {"write_photos", s.write_photos},
          {"write_overlays", s.write_overlays},
          {"views_must_measure", s.views_must_measure},
          {"lab_look", s.lab_look},
          {"lab_cameras", cams(s.lab_cameras)},
          {"declared_cameras", cams(s.declared_cameras)},
          {"lab_top_camera", s.lab_top_camera ? camera::to_json(*s.lab_top_camera)
                                              : nlohmann::json(nullptr)},
          {"shells", shells},
          {"warning", s.warning}};
}

PilePhotos photograph_pile(const PileSpheres& pile, const PhotoSettings& s,
                           const std::string& out_dir, const nlohmann::json& provenance,
                           std::optional<Eigen::Vector2d> centre) {
  if (s.side_views < 1) throw InputError("images: side_views must be at least 1");
  PilePhotos photos;
  if (!s.shells.empty()) centre = Eigen::Vector2d::Zero();
  render::Scene scene = centred_pile_scene(pile, centre, &photos.centre_shift);
  scene.scale_reference.enabled = s.scale_reference;
  scene.scale_reference.count = bar_bands(scene);
  scene.shells = s.shells;
  if (s.write_photos || s.write_overlays) fs::create_directories(out_dir);
  render::Renderer& renderer = thread_renderer();
  render::RenderOptions options;
  if (s.lab_look) render::apply_lab_look(scene, options);
  options.tint_seed = s.tint_seed;
  options.view = render::View::kSide;
  render::LabCameraSettings cams;
  cams.width_px = s.width_px;
  cams.height_px = s.height_px;
  cams.distance_radii = s.distance_radii;
  cams.side_height_m = s.camera_height_m;
  cv::RNG rng(s.noise_seed * 7919 + 17);
  std::vector<vision::SideMeasurement> measured;
  std::vector<std::string> stems;
  if (!s.declared_cameras.empty() && s.declared_cameras.size() != s.lab_cameras.size())
    throw InputError("images: " + std::to_string(s.declared_cameras.size()) +
                     " declared cameras for " + std::to_string(s.lab_cameras.size()) +
                     " lab cameras");
  const std::vector<camera::Camera> truths = side_cameras(scene, s, cams);
  for (std::size_t k = 0; k < truths.size(); ++k) {
    const camera::Camera& truth = truths[k];
    const camera::Camera declared =
        s.declared_cameras.empty() ? declared_camera(truth, s) : s.declared_cameras[k];
    SideView view;
    view.azimuth_deg = s.lab_cameras.empty() ? 180.0 * photos.sides.size() / s.side_views
                                             : azimuth_of(truth);
    view.camera = truth;
    view.stem = side_stem(view.azimuth_deg);
    // Two lab photos from one azimuth keep apart: the second is side_az045_2, ...
    const auto same = std::count(stems.begin(), stems.end(), view.stem);
    stems.push_back(view.stem);
    if (same > 0) view.stem += "_" + std::to_string(same + 1);
    const std::string base = (fs::path(out_dir) / view.stem).string();
    cv::Mat image = renderer.render(scene, truth, options);
    if (s.noise_sd > 0.0) add_noise(image, s.noise_sd, rng);
    if (s.write_photos)
      render::write_render(base, image, render::make_sidecar(scene, declared, options, provenance));
    try {
      view.measured = vision::measure_side_camera(image, declared, {}, base + ".png");
      measured.push_back(*view.measured);
    } catch (const std::exception& e) {
      if (s.views_must_measure) throw;
      view.error = e.what();  // one view of a small pile may defeat vision; the others count
    }
    if (view.measured && s.write_overlays)
      write_overlay(base + ".measured.png",
                    stamp_warning(vision::draw_side_overlay(image, *view.measured), s.warning));
    photos.sides.push_back(std::move(view));
  }
  if (!measured.empty()) photos.summary = vision::combine_sides(measured);
  photos.gl = renderer.gl_description();
  if (!s.top_view) return photos;
  options.view = render::View::kTop;
  const camera::Camera cam = s.lab_top_camera.value_or(render::lab_top_camera(scene, cams));
  const std::string base = (fs::path(out_dir) / "top").string();
  const cv::Mat image = renderer.render(scene, cam, options);
  if (s.write_photos)
    render::write_render(base, image, render::make_sidecar(scene, cam, options, provenance));
  photos.top_taken = true;
  try {
    vision::ScaleSpec spec;
    spec.camera = cam;
    if (photos.summary) spec.crest_height_m = photos.summary->height_m.mean;
    photos.top = vision::measure_top(image, spec, {}, base + ".png");
  } catch (const std::exception& e) {
    // The footprint is a secondary quantity (the angle comes from the side views): a top view
    // that cannot be measured (a thin, patchy pile) is reported, not fatal.
    photos.top_error = e.what();
  }
  if (photos.top && s.write_overlays)
    write_overlay(base + ".measured.png",
                  stamp_warning(vision::draw_top_overlay(image, *photos.top), s.warning));
  return photos;
}

std::string encode_image(const std::string& path, const cv::Mat& image) {
  std::vector<unsigned char> bytes;
  bool ok = false;
  try {
    const std::string ext = fs::path(path).extension().string();
    ok = cv::imencode(ext.empty() ? ".png" : ext, image, bytes);
  } catch (const cv::Exception& e) {
    throw std::runtime_error(path + ": cannot encode the image (" + e.what() + ")");
  }
  if (!ok) throw std::runtime_error(path + ": cannot encode the image");
  return std::string(bytes.begin(), bytes.end());
}

void write_image_atomic(const std::string& path, const cv::Mat& image) {
  write_file_atomic(path, encode_image(path, image));
}

}  // namespace reposetwin::experiments
