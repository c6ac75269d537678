// Small helpers shared by vision's source files (numbers in messages, the pixel's quantisation
// error, the degree conversion); not for use outside vision/. One definition each, so that the
// unity build (CMakeLists.txt) can compile several of vision's files as one.
#pragma once

#include <cmath>
#include <iomanip>
#include <numbers>
#include <sstream>
#include <string>

namespace reposetwin::vision::detail {

inline constexpr double kRadToDeg = 180.0 / std::numbers::pi;
// Standard deviation of a uniform error over one pixel [px].
inline const double kQuantisationPx = 1.0 / std::sqrt(12.0);

// A number as a stream writes it by default (6 significant digits), for messages.
inline std::string str(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

// A number with a fixed count of decimals.
inline std::string fixed(double v, int digits) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(digits) << v;
  return os.str();
}

}  // namespace reposetwin::vision::detail
