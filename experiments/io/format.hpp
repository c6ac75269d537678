// Numbers as text in messages, case names, cache keys and TOML values: one formatter, so the
// same number reads the same everywhere and a change of format is made once. (Report pages have
// their own conventions, report/format.hpp, built on the same printf rules.)
#pragma once

#include <charconv>
#include <cstdio>
#include <string>
#include <string_view>

namespace reposetwin::experiments {

/// `v` to `digits` significant digits, as printf's "%.*g" (and an ostream of that precision).
inline std::string significant(double v, int digits = 6) {
  char b[64];
  std::snprintf(b, sizeof b, "%.*g", digits, v);
  return b;
}

/// `v` through one printf conversion (`pattern`, e.g. "%.1f"), for fixed layouts in messages.
inline std::string printf_text(const char* pattern, double v) {
  char b[64];
  std::snprintf(b, sizeof b, pattern, v);
  return b;
}

/// The shortest text that reads back to the same double ("0.1", "1e-30", "1000000000000"): a
/// value quoted back to the user as they typed it, not to seventeen digits.
inline std::string shortest_text(double v) {
  char b[64];
  const auto r = std::to_chars(b, b + sizeof b, v);
  return std::string(b, r.ptr);
}

/// A float in TOML syntax: significant(v, digits) with ".0" added where it would read as an
/// integer (inf and nan are TOML floats as they are).
inline std::string toml_float(double v, int digits = 17) {
  std::string t = significant(v, digits);
  if (t.find_first_of(".eEn") == std::string::npos) t += ".0";
  return t;
}

/// `word` as one word of a POSIX shell command a person can paste: as it is when it holds only
/// letters, digits and _ . / - + = : , @ % (a plain path), else in single quotes (a ' inside as
/// '\'').
inline std::string shell_word(const std::string& word) {
  bool plain = !word.empty();
  for (char c : word)
    plain = plain && ((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                      std::string_view("_./-+=:,@%").find(c) != std::string_view::npos);
  if (plain) return word;
  std::string q = "'";
  for (char c : word) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

}  // namespace reposetwin::experiments
