// Command-line checks whose messages read as a person would write them ("must be a positive
// number, got -1"), where CLI11's own PositiveNumber prints its bounds as 300-digit numbers.
//
// Every number an option takes is checked here as text, before CLI11 converts it: CLI11 reads an
// integer with strtoll's base 0 ("010" is 8, "0x10" is 16) and a float with strtold ("inf",
// "0x1p3"), so a range check on the converted value lets those spellings through. Integers are
// decimal digits, floats plain decimals (experiments/io/numbers.hpp), for every option alike.
#pragma once

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdint>
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

/// Any finite number, a plain decimal.
inline CLI::Validator plain_number() {
  return CLI::Validator(
      [](std::string& s) -> std::string {
        if (!experiments::parse_plain_decimal(s))
          return "'" + s + "' is not a number (a plain decimal is expected)";
        return "";
      },
      "NUMBER");
}

/// A whole number, possibly negative, in decimal digits (a pixel coordinate).
inline CLI::Validator integer_number() {
  return CLI::Validator(
      [](std::string& s) -> std::string {
        const bool negative = !s.empty() && s.front() == '-';
        const std::optional<std::uint64_t> v =
            experiments::parse_seed(negative ? std::string_view(s).substr(1) : std::string_view(s));
        if (!v || *v > 1'000'000'000ull)
          return "'" + s + "' is not a whole number (decimal digits, at most 10^9)";
        s = (negative ? "-" : "") + std::to_string(*v);
        return "";
      },
      "INTEGER");
}

/// A finite number >= 0.
inline CLI::Validator non_negative_number() {
  return CLI::Validator(
      [](std::string& s) -> std::string {
        const std::optional<double> v = experiments::parse_plain_decimal(s);
        if (!v) return "'" + s + "' is not a number (a plain decimal is expected)";
        if (!(*v >= 0.0)) return "must be a number >= 0, got " + s;
        return "";
      },
      "NONNEGATIVE");
}

/// A whole number in [lo, hi] written in decimal digits (no sign, hex, octal or exponent).
inline CLI::Validator whole_number_in(std::int64_t lo, std::int64_t hi) {
  return CLI::Validator(
      [lo, hi](std::string& s) -> std::string {
        const std::optional<std::uint64_t> v = experiments::parse_seed(s);
        const std::string range = std::to_string(lo) + " to " + std::to_string(hi);
        if (!v) return "'" + s + "' is not a whole number from " + range + " (decimal digits)";
        if (*v < static_cast<std::uint64_t>(lo) || *v > static_cast<std::uint64_t>(hi))
          return "must be a whole number from " + range + ", got " + s;
        s = std::to_string(*v);  // "010" is ten, as typed, not strtoll's octal eight
        return "";
      },
      "in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
}

/// A seed: decimal digits, at most experiments::kMaxSeed.
inline CLI::Validator seed_number() {
  return CLI::Validator(
      [](std::string& s) -> std::string {
        const std::optional<std::uint64_t> v = experiments::parse_seed(s);
        if (!v) return "'" + s + "' is not a seed (decimal digits, at most 2^63 - 1)";
        s = std::to_string(*v);  // "010" is ten, as typed, not strtoull's octal eight
        return "";
      },
      "SEED");
}

/// The largest worker count a command accepts [-].
inline constexpr int kMaxWorkers = 1024;

/// --workers, the same option with the same check on every command that runs piles side by side.
inline CLI::Option* add_workers_option(CLI::App* cmd, int& workers, const std::string& help) {
  return cmd->add_option("--workers", workers, help)
      ->check(whole_number_in(1, kMaxWorkers))
      ->capture_default_str();
}

}  // namespace reposetwin::cli
