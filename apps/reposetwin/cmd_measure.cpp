// `reposetwin measure`: the lab's photo measurement (theta = atan(2H/D)) on one or more side
// images and an optional top image, printed as one line (the whole record as JSON with --json),
// with an annotated overlay per image.
// Thin: all measuring is vision/; this file only resolves files, scales and outputs.
#include <cmath>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "apps/reposetwin/commands.hpp"
#include "experiments/io/files.hpp"
#include "experiments/photos/photographs.hpp"
#include "apps/reposetwin/validators.hpp"
#include "experiments/io/provenance.hpp"
#include "vision/image.hpp"
#include "vision/measure.hpp"

namespace reposetwin::cli {
namespace {

namespace fs = std::filesystem;

struct MeasureOptions {
  std::string side;
  std::vector<std::string> more_sides;
  std::string top;
  std::optional<double> mm_per_px;
  std::vector<std::string> cameras;
  bool marker = false;
  std::optional<double> top_mm_per_px;
  std::string top_camera;
  std::string overlay;
  std::string top_overlay;
  bool no_overlay = false;
  bool force = false;
  std::vector<int> roi;
  std::vector<double> flank_band;
  bool json = false;
  bool trust_photo_pose = false;
};

std::string sidecar_next_to(const std::string& image) {
  return fs::path(image).replace_extension(".json").string();
}

std::string overlay_next_to(const std::string& image) {
  fs::path p(image);
  return (p.parent_path() / (p.stem().string() + ".measured.png")).string();
}

// The scale of one image: explicit option, else its sidecar, else the marker in the image.
vision::ScaleSpec resolve_scale(const std::string& image, const std::optional<double>& mm_per_px,
                                const std::string& camera_sidecar, bool marker_only,
                                camera::SidecarView view) {
  if (marker_only) return vision::ScaleSpec{};
  if (mm_per_px) {
    vision::ScaleSpec s;
    s.mm_per_px = mm_per_px;
    s.search_marker = false;
    s.note = "--mm-per-px";
    return s;
  }
  if (!camera_sidecar.empty()) return vision::scale_from_sidecar(camera_sidecar, view);
  const std::string auto_sidecar = sidecar_next_to(image);
  std::error_code ec;
  if (fs::is_regular_file(auto_sidecar, ec)) return vision::scale_from_sidecar(auto_sidecar, view);
  vision::ScaleSpec s;
  s.note = "no sidecar (" + auto_sidecar + " not found); scale marker searched in the image";
  return s;
}


// "angle of repose 25.65 ± 0.40 deg (image atan(2H/D), 1 side view, perspective corrected); H
// 9.2 mm, D 38.1 mm; flank 31.20 deg; overlay side.measured.png": the measurement in one line.
std::string measure_line(const vision::SideSummary& s, const std::string& projection,
                         const std::vector<std::string>& overlays) {
  const auto fixed = [](double v, int digits) {
    std::ostringstream os;
    os.setf(std::ios::fixed);
    os.precision(digits);
    os << v;
    return os.str();
  };
  std::string line = "angle of repose " + fixed(s.theta_deg.mean, 2) + " \u00b1 " +
                     fixed(s.theta_deg.sigma_mean, 2) + " deg (image atan(2H/D), " +
                     std::to_string(s.views) + (s.views == 1 ? " side view, " : " side views, ") +
                     projection + "); H " + fixed(1e3 * s.height_m.mean, 1) + " mm, D " +
                     fixed(1e3 * s.diameter_m.mean, 1) + " mm; flank " +
                     fixed(s.flank_deg.mean, 2) + " deg";
  if (!overlays.empty()) {
    line += overlays.size() == 1 ? "; overlay" : "; overlays";
    for (const std::string& p : overlays) line += " " + p;
  }
  return line;
}

void run_measure(const MeasureOptions& o) {
  // One camera per side image, in order: with fewer, the images after them would silently take
  // another scale (their own sidecar, or the scale bar).
  if (!o.cameras.empty() && o.cameras.size() != 1 + o.more_sides.size())
    throw std::invalid_argument("--camera: " + std::to_string(o.cameras.size()) +
                                " sidecar(s) given for " + std::to_string(1 + o.more_sides.size()) +
                                " side images; give one --camera per side image, in order");
  vision::SideSettings settings;
  if (!o.roi.empty()) {
    if (o.roi.size() != 4 || o.roi[2] <= 0 || o.roi[3] <= 0)
      throw std::invalid_argument("--roi must be x,y,width,height with positive width and height");
    settings.roi = cv::Rect(o.roi[0], o.roi[1], o.roi[2], o.roi[3]);
  }
  if (!o.flank_band.empty()) {
    if (o.flank_band.size() != 2)
      throw std::invalid_argument("--flank-band must be two fractions of H, e.g. 0.2,0.8");
    settings.flank_band_low = o.flank_band[0];
    settings.flank_band_high = o.flank_band[1];
    if (!(settings.flank_band_low >= 0 && settings.flank_band_low < settings.flank_band_high &&
          settings.flank_band_high <= 1)) {
      std::ostringstream os;
      os << "--flank-band " << o.flank_band[0] << "," << o.flank_band[1]
         << ": must be low,high fractions of H with 0 <= low < high <= 1";
      throw std::invalid_argument(os.str());
    }
  }

  std::vector<std::string> sides{o.side};
  sides.insert(sides.end(), o.more_sides.begin(), o.more_sides.end());
  experiments::refuse_repeated_contents(sides, "measure (side and --side)");
  if (!o.cameras.empty()) experiments::refuse_repeated_contents(o.cameras, "measure --camera");
  // The overlays go beside the user's photos: checked against every input and each other before
  // anything is measured (experiments/io/files.hpp).
  const auto side_overlay = [&](std::size_t i) {
    return (i == 0 && !o.overlay.empty()) ? o.overlay : overlay_next_to(sides[i]);
  };
  const std::string top_overlay_path =
      o.top_overlay.empty() ? overlay_next_to(o.top) : o.top_overlay;
  experiments::OutputPlan plan(o.force);
  for (const std::string& p : sides) plan.add_input(p);
  if (!o.top.empty()) plan.add_input(o.top);
  for (const std::string& p : o.cameras) plan.add_input(p);
  if (!o.top_camera.empty()) plan.add_input(o.top_camera);
  for (const std::string& p : sides) plan.add_input(sidecar_next_to(p));
  if (!o.top.empty()) plan.add_input(sidecar_next_to(o.top));
  if (!o.no_overlay) {
    for (std::size_t i = 0; i < sides.size(); ++i)
      plan.add_output(side_overlay(i), i == 0 && !o.overlay.empty()
                                           ? "--overlay"
                                           : "the overlay of " + sides[i] + ":");
    if (!o.top.empty())
      plan.add_output(top_overlay_path,
                      o.top_overlay.empty() ? "the overlay of " + o.top + ":" : "--top-overlay");
  }
  plan.check();

  // Measure everything first: nothing is printed or written unless every image succeeds.
  std::vector<vision::SideMeasurement> views;
  std::vector<cv::Mat> overlays;
  for (size_t i = 0; i < sides.size(); ++i) {
    const cv::Mat img = vision::load_image(sides[i]);
    vision::ScaleSpec scale =
        resolve_scale(sides[i], o.mm_per_px, i < o.cameras.size() ? o.cameras[i] : "", o.marker,
                      camera::SidecarView::kSide);
    if (o.trust_photo_pose) scale.pose_policy = vision::PosePolicy::kEstimate;
    try {
      views.push_back(vision::measure_side(img, scale, settings, sides[i]));
    } catch (const vision::Refusal& r) {
      // A refused photo gives no number: the check, what it measured and its limit.
      auto number = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); };
      if (o.json)
        std::cout << nlohmann::json{{"tool", "reposetwin measure"},
                                    {"image", sides[i]},
                                    {"refused",
                                     {{"check", vision::to_string(r.check())},
                                      {"measured", number(r.measured())},
                                      {"limit", number(r.limit())},
                                      {"message", r.what()}}}}
                         .dump(2)
                  << "\n";
      std::cerr << "reposetwin: refused by the " << vision::to_string(r.check())
                << " check: " << r.what() << "\n";
      set_exit_code(ExitCode::kRefused);
      return;
    }
    if (!o.no_overlay) overlays.push_back(vision::draw_side_overlay(img, views.back()));
  }
  std::optional<vision::TopMeasurement> top;
  cv::Mat top_overlay;
  if (!o.top.empty()) {
    const cv::Mat img = vision::load_image(o.top);
    vision::ScaleSpec scale =
        resolve_scale(o.top, o.top_mm_per_px, o.top_camera, o.marker, camera::SidecarView::kTop);
    // The crest stands at the pile's height: its width is read on that plane.
    scale.crest_height_m = vision::combine_sides(views).height_m.mean;
    top = vision::measure_top(img, scale, {}, o.top);
    if (!o.no_overlay) top_overlay = vision::draw_top_overlay(img, *top);
  }

  std::vector<std::string> overlay_paths;
  if (!o.no_overlay) {
    for (size_t i = 0; i < sides.size(); ++i) {
      const std::string path = side_overlay(i);
      plan.write(path, experiments::encode_image(path, overlays[i]));
      overlay_paths.push_back(path);
    }
    if (top) {
      plan.write(top_overlay_path, experiments::encode_image(top_overlay_path, top_overlay));
      overlay_paths.push_back(top_overlay_path);
    }
  }

  const vision::SideSummary summary = vision::combine_sides(views);
  nlohmann::json j;
  j["tool"] = "reposetwin measure";
  j["code_version"] = experiments::code_version();
  j["views"] = static_cast<int>(views.size());
  j["H_m"] = summary.height_m.mean;
  j["D_m"] = summary.diameter_m.mean;
  j["theta_deg"] = summary.theta_deg.mean;
  j["sigma_theta_deg"] = summary.theta_deg.sigma_mean;
  j["flank_left_deg"] = summary.flank_left_deg.mean;
  j["flank_right_deg"] = summary.flank_right_deg.mean;
  j["flank_deg"] = summary.flank_deg.mean;
  j["sigma_flank_deg"] = summary.flank_deg.sigma_mean;
  bool all_corrected = true, any_corrected = false;
  std::vector<std::string> sources;
  for (const auto& v : views) {
    all_corrected = all_corrected && v.perspective_corrected;
    any_corrected = any_corrected || v.perspective_corrected;
    sources.push_back(vision::to_string(v.scale_source));
  }
  j["projection"] = all_corrected   ? "perspective corrected"
                    : any_corrected ? "mixed (see side)"
                                    : "assumed orthographic";
  j["scale_sources"] = sources;
  std::vector<std::string> warnings;
  for (const auto& v : views)
    for (const auto& w : v.warnings) warnings.push_back(v.source + ": " + w.text);
  j["warnings"] = warnings;
  j["summary"] = vision::to_json(summary);
  j["side"] = nlohmann::json::array();
  for (const auto& v : views) j["side"].push_back(vision::to_json(v));
  j["top"] = top ? vision::to_json(*top) : nlohmann::json(nullptr);
  j["overlays"] = overlay_paths;
  // One line for a person (warnings on stderr, never lost), or the whole record for a script.
  if (o.json) {
    std::cout << j.dump(2) << "\n";
  } else {
    for (const std::string& w : warnings) std::cerr << "reposetwin: warning: " << w << "\n";
    std::cout << measure_line(summary, j["projection"].get<std::string>(), overlay_paths)
              << std::endl;
  }
  set_exit_code(ExitCode::kOk);
}

}  // namespace

void add_measure_command(CLI::App& app) {
  auto opts = std::make_shared<MeasureOptions>();
  auto* cmd = app.add_subcommand(
      "measure",
      "Measure a pile from images like the lab does: H, D, theta = atan(2H/D), flank angles. "
      "Prints one line (JSON with --json) and writes an annotated overlay per image. Scale: "
      "--mm-per-px, "
      "--camera SIDECAR.json, or --marker; by default NAME.json next to the image if present, "
      "else the scale bar found in the image.");
  cmd->add_option("side", opts->side, "Side-view image of the pile (PNG, JPEG, ...)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--side", opts->more_sides,
                  "More side views of the same pile (other azimuths); results are averaged")
      ->check(CLI::ExistingFile);
  cmd->add_option("--top", opts->top, "Top-view image: footprint diameter and ellipticity")
      ->check(CLI::ExistingFile);
  auto* mm = cmd->add_option("--mm-per-px", opts->mm_per_px,
                             "Scale at the pile axis [mm/px] for the side views; assumes an "
                             "orthographic view")
                 ->check(positive_number());
  auto* cam = cmd->add_option("--camera", opts->cameras,
                              "Render sidecar JSON with the camera (perspective corrected); "
                              "repeat for each side image in order")
                  ->check(CLI::ExistingFile);
  auto* marker = cmd->add_flag("--marker", opts->marker,
                               "Use only the scale marker found in the image (ignore sidecars)");
  mm->excludes(cam)->excludes(marker);
  cam->excludes(marker);
  cmd->add_option("--top-mm-per-px", opts->top_mm_per_px, "Scale on the plate in the top view")
      ->check(positive_number());
  cmd->add_option("--top-camera", opts->top_camera, "Sidecar JSON of the top view")
      ->check(CLI::ExistingFile);
  cmd->add_option("--overlay", opts->overlay,
                  "Overlay PNG for the first side image (default NAME.measured.png)");
  cmd->add_option("--top-overlay", opts->top_overlay,
                  "Overlay PNG for the top image (default NAME.measured.png)");
  cmd->add_flag("--no-overlay", opts->no_overlay, "Do not write overlay images");
  cmd->add_flag("--force", opts->force,
                "Replace an existing file at an overlay's path that reposetwin did not make "
                "(never an input image or sidecar)");
  cmd->add_option("--roi", opts->roi, "Region of interest in the side images: x,y,width,height")
      ->delimiter(',')
      ->check(integer_number())
      ->expected(4);
  cmd->add_option("--flank-band", opts->flank_band,
                  "Flank fit band as fractions of H (default 0.2,0.8)")
      ->delimiter(',')
      ->check(plain_number())
      ->expected(2);
  cmd->add_flag("--trust-photo-pose", opts->trust_photo_pose,
                "Measure a photo whose lines contradict its declared camera through the pose the "
                "photo implies (the declared camera re-pitched), saying so, where that pose is "
                "determined; by default such a photo is refused as a camera mismatch");
  cmd->add_flag("--json", opts->json,
                "Print the whole measurement as JSON on stdout instead of the one line");
  cmd->callback([opts]() { run_measure(*opts); });
}

}  // namespace reposetwin::cli
