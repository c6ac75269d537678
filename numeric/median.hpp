// The median of a sample, shared by sim/ (pile geometry) and vision/ (image measurement), so
// that both follow one rule. Standard library only: the engine and the imaging may both depend
// on it.
#pragma once

#include <algorithm>
#include <cstddef>
#include <limits>
#include <vector>

namespace reposetwin::numeric {

/// The median of `v` (taken by value: reordered in the copy, O(n)). The rule:
///  - an empty sample has no median: NaN, which a caller must test for where a sample may be
///    empty (NaN fails every comparison, so it cannot pass a threshold by accident);
///  - an odd-length sample gives its middle value;
///  - an even-length sample gives the mean of its two middle values, 0.5 (lower + upper).
inline double median(std::vector<double> v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  const double upper = *mid;
  if (v.size() % 2 == 1) return upper;
  const double lower = *std::max_element(v.begin(), mid);
  return 0.5 * (lower + upper);
}

}  // namespace reposetwin::numeric
