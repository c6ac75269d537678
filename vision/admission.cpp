#include "vision/admission.hpp"

namespace reposetwin::vision {

std::string to_string(Check check) {
  switch (check) {
    case Check::kPilePresent:
      return "no_pile";
    case Check::kFlankLimits:
      return "flank_limits";
    case Check::kNotCut:
      return "cut_by_border";
    case Check::kNoForeignObject:
      return "foreign_object";
    case Check::kExposure:
      return "exposure";
    case Check::kCameraConsistent:
      return "camera_mismatch";
    case Check::kViewAngle:
      return "view_too_steep";
    case Check::kCount:
      break;
  }
  return "unknown";
}

}  // namespace reposetwin::vision
