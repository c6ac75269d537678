// Reading fields back from result files that may predate them. JSON has no NaN: nlohmann writes
// a NaN (an angle vision could not fit, say) as null, so a reader must take null back as NaN,
// or a result that was written could not be read again; json_read.hpp's number_value does.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "experiments/io/json_read.hpp"

namespace reposetwin::experiments {

/// j[key] as a double as json_read.hpp's number_field reads it (null as NaN; anything but a
/// number a JsonFieldError at /key), or `fallback` when the key is absent: a result file older
/// than the field.
inline double json_number(const nlohmann::json& j, const char* key, double fallback = 0.0) {
  return j.contains(key) ? number_field(j, key) : fallback;
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
