// The one content hash of experiments/: FNV-1a 64, written as 16 hex digits. It names run
// folders by their inputs (scene text, overrides, code version) and detects an edited input when
// a campaign resumes; it is not cryptographic, only stable across platforms and versions.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string_view>
#include <string>

namespace reposetwin::experiments {

/// FNV-1a 64 of `text` as 16 lower-case hex digits.
inline std::string fnv1a_hex(std::string_view text) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : text) {
    h ^= c;
    h *= 1099511628211ull;
  }
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

}  // namespace reposetwin::experiments
