// The campaign file as the commands load it: read at the file edge, then its calibration target
// measured when the lab's photos give it.
//
// Design note. io/ (campaign_file.hpp) records the photos that calibration.target_photos names
// and nothing more, so the file edge does not depend on photos/ and vision/. Measuring them is
// a step of its own here, taken as part of loading, so that a photo that cannot be read or has
// no scale is still an error naming the file, the key and the value before any case runs, like
// every other bad input of the file. The measurement is that of photos/lab_photos.hpp, the one
// that reads the twin's renders: the mean atan(2H/D) when the simulated angle is an atan(2H/D)
// (image, particles), the mean flank angle when it is a protractor-like angle (image_flank,
// slice), so both sides are read alike. The target's sd is the measurement's uncertainty of the
// mean (spread over the photos and their own errors); target_sd_deg, when given, replaces it.
#pragma once

#include <string>

#include "experiments/io/campaign_file.hpp"

namespace reposetwin::experiments {

/// Measures the lab photos of `cc.target_photo_files` (nothing to do without them) and sets
/// `cc.target` and `cc.target_photos` (the measurement record, with "photos" and "target_from").
/// Throws InputError naming `file`, the key and the value for an unreadable photo, a bad scale,
/// a photo without any scale, or a measured target outside (0, 90) deg.
void measure_target_photos(CampaignCalibration& cc, const std::string& file);

/// Reads a campaign file (read_campaign_file) and measures its calibration target photos: the
/// campaign every command runs. Throws as those two do.
Campaign load_campaign(const std::string& path);

}  // namespace reposetwin::experiments
