#include "experiments/calibration/campaign_target.hpp"

#include <stdexcept>

#include "experiments/io/input_error.hpp"
#include "experiments/photos/lab_photos.hpp"

namespace reposetwin::experiments {

void measure_target_photos(CampaignCalibration& cc, const std::string& file) {
  if (!cc.target_photo_files) return;
  const TargetPhotoFiles& f = *cc.target_photo_files;
  const std::string prefix = "calibration.";
  const LabPhotoMeasurement m =
      measure_lab_photos(f.photos, LabPhotoScale{f.camera_json, f.mm_per_px},
                         {f.photos_at, f.camera_at, f.mm_per_px_at, prefix + "target_photo_camera",
                          prefix + "target_mm_per_px"});
  const bool flank = cc.angle == AngleMeasure::kImageFlank || cc.angle == AngleMeasure::kSlice;
  const vision::Spread& s = flank ? m.summary.flank_deg : m.summary.theta_deg;
  cc.target_photos = m.record;
  cc.target_photos["photos"] = f.photos;
  // How their scale was known, so that the report measures the same photo the same way.
  nlohmann::json& record = cc.target_photos;
  record["camera_sidecar"] = f.camera_json.empty() ? nlohmann::json() : nlohmann::json(f.camera_json);
  record["declared_mm_per_px"] = f.mm_per_px ? nlohmann::json(*f.mm_per_px) : nlohmann::json();
  cc.target_photos["target_from"] = flank ? "flank_deg (mean flank angle over the photos)"
                                          : "theta_deg (atan(2H/D), mean over the photos)";
  cc.target = Target{s.mean, f.sd_deg.value_or(s.sigma_mean)};
  try {
    validate_target(cc.target);
  } catch (const std::invalid_argument& e) {
    throw InputError(file + ": key '" + prefix + "target_photos' = measured " +
                     std::to_string(cc.target.angle_deg) + " deg: " + e.what());
  }
}

Campaign load_campaign(const std::string& path) {
  Campaign c = read_campaign_file(path);
  if (c.calibration) measure_target_photos(*c.calibration, c.file);
  return c;
}

}  // namespace reposetwin::experiments
