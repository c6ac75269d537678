// vision/admission: the checks a side photo passes before vision gives a number for it.
//
// Design note. A lab records a reading with the checks it passed; vision does the same. A photo
// is measured only when it passes every check below, and a photo that fails one is refused with
// a Refusal naming that check, the value it measured and the limit, never with a number and
// never with another check's reason. The checks, in the order they are made:
//  - kPilePresent: the largest object standing on the plate where the pile should be is a pile:
//    at least min_height_mm tall and min_diameter_mm wide at the scale, and narrowing upwards
//    (its width at 80% of its height at most kTaperLimit of its width at 20%); a scale bar, a box
//    or an empty plate is not.
//  - kFlankLimits: both flanks between min_flank_deg and max_flank_deg (no granular pile stands
//    steeper than about 60 deg; a 90 deg flank is an edge of an object).
//  - kNotCut: the pile's own silhouette keeps clear of the photo's border (other objects at the
//    border are not the pile and do not count).
//  - kNoForeignObject: nothing dark hangs near the pile's top or rests against its silhouette
//    from above (the funnel's outlet, a hand, a tool): any other object within
//    foreign_gap_fraction of the pile's height of its silhouette, not standing on the plate, or a
//    silhouette that narrows to a neck and widens again above it.
//  - kExposure: the pile stands out from what is behind it (contrast at least min_contrast of the
//    backdrop's level) and its top is not washed out (its top fifth reading more than a fifth of
//    the way to the backdrop's level while more than max_clipped_fraction of the band above it is at the
//    sensor's maximum). A photo in which no pile is found while more than
//    max_clipped_photo_fraction of it is at the sensor's maximum is refused for its exposure,
//    not as an empty plate: the pile may be lost in the white.
//  - kCameraConsistent: the photo's lines fall where the declared camera puts them
//    (measure.hpp): the plate line within max(3 px, 3 sigma) of the predicted row.
//  - kViewAngle: the camera looks at the pile from below its flanks' slope (less 3 deg), so that
//    the apex is on the silhouette; a camera looking down more steeply sees the flanks face on.
// Every threshold is a field of AdmissionSettings with its unit.
#pragma once

#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace reposetwin::vision {

/// One admission check (the design note says what each asks).
enum class Check {
  kPilePresent,
  kFlankLimits,
  kNotCut,
  kNoForeignObject,
  kExposure,
  kCameraConsistent,
  kViewAngle,
  kCount
};
inline constexpr int kChecks = static_cast<int>(Check::kCount);

/// The check's name in records and messages: "no_pile", "flank_limits", "cut_by_border",
/// "foreign_object", "exposure", "camera_mismatch", "view_too_steep" (what a refusal by it says
/// of the photo).
std::string to_string(Check check);

/// The limits of the checks. SI-like units as named.
struct AdmissionSettings {
  double min_height_mm = 3.0;     // a pile at least this tall [mm] (about a grain or two)
  double min_diameter_mm = 10.0;  // and this wide at its base [mm]
  double min_height_px = 8.0;     // and this many pixels tall (else nothing can be read) [px]
  double min_flank_deg = 3.0;     // flanks at least this steep [deg]
  double max_flank_deg = 65.0;    // and at most this steep [deg]
  double foreign_gap_fraction = 0.25;  // objects nearer the silhouette than this times H [-]
  double min_contrast = 0.12;          // |1 - pile level| against the backdrop, at least [-]
  double max_clipped_fraction = 0.5;   // of the band above a faded top clipped white, at most [-]
  double max_clipped_photo_fraction = 0.25;  // of a photo with no pile found clipped white [-]
  double camera_tolerance_px = 3.0;    // lines off their predicted rows by more: a mismatch [px]
};

/// A photo that failed an admission check: the check, the value measured and the limit it
/// failed (NaN where the check has no single number), and the sentence of what.
class Refusal : public std::runtime_error {
 public:
  Refusal(Check check, const std::string& message,
          double measured = std::numeric_limits<double>::quiet_NaN(),
          double limit = std::numeric_limits<double>::quiet_NaN())
      : std::runtime_error(message), check_(check), measured_(measured), limit_(limit) {}
  Check check() const { return check_; }
  double measured() const { return measured_; }
  double limit() const { return limit_; }

 private:
  Check check_;
  double measured_, limit_;
};

}  // namespace reposetwin::vision
