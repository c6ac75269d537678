// Reading numbers back from result files. JSON has no NaN: nlohmann writes a NaN (an angle
// vision could not fit, say) as null, so a reader must take null back as NaN, or a result that
// was written could not be read again.
#pragma once

#include <limits>
#include <nlohmann/json.hpp>
#include <string>

namespace reposetwin::experiments {

/// A JSON number as a double: NaN for null.
inline double json_number(const nlohmann::json& v) {
  return v.is_null() ? std::numeric_limits<double>::quiet_NaN() : v.get<double>();
}

/// j[key] as a double: NaN for null, `fallback` when the key is absent.
inline double json_number(const nlohmann::json& j, const char* key, double fallback = 0.0) {
  const auto it = j.find(key);
  if (it == j.end()) return fallback;
  return it->is_null() ? std::numeric_limits<double>::quiet_NaN() : it->get<double>();
}

/// A text that may be absent, as JSON: null when empty.
inline nlohmann::json text_or_null(const std::string& text) {
  return text.empty() ? nlohmann::json() : nlohmann::json(text);
}

/// j[key] as a text: empty when the key is absent (a file older than the field) or null.
inline std::string json_text(const nlohmann::json& j, const char* key) {
  const auto it = j.find(key);
  return it == j.end() || it->is_null() ? std::string() : it->get<std::string>();
}

}  // namespace reposetwin::experiments
