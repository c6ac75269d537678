// Command-line checks whose messages read as a person would write them ("must be a positive
// number, got -1"), where CLI11's own PositiveNumber prints its bounds as 300-digit numbers.
#pragma once

#include <CLI/CLI.hpp>
#include <cmath>
#include <optional>
#include <string>

#include "experiments/io/numbers.hpp"

namespace reposetwin::cli {

/// A finite number > 0.
inline CLI::Validator positive_number() {
  return CLI::Validator(
      [](std::string& s) -> std::string {
        const std::optional<double> v = experiments::parse_plain_decimal(s);
        if (!v) return "'" + s + "' is not a number (a plain decimal is expected)";
        if (!(*v > 0.0)) return "must be a positive number, got " + s;
        return "";
      },
      "POSITIVE");
}

/// A number in [lo, hi].
inline CLI::Validator number_in(double lo, double hi) {
  return CLI::Validator(
      [lo, hi](std::string& s) -> std::string {
        const std::optional<double> parsed = experiments::parse_plain_decimal(s);
        if (!parsed) return "'" + s + "' is not a number (a plain decimal is expected)";
        const double v = *parsed;
        if (!(v >= lo && v <= hi))
          return "must lie in [" + CLI::detail::to_string(lo) + ", " + CLI::detail::to_string(hi) +
                 "], got " + s;
        return "";
      },
      "in [" + CLI::detail::to_string(lo) + ", " + CLI::detail::to_string(hi) + "]");
}

}  // namespace reposetwin::cli
