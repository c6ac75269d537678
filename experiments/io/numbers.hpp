// The one reader of numbers and seeds written by a person: in sheets (CSV), in option lists
// (--seeds, --mu-grid) and in checks of scales and tolerances.
//
// Design note. A number that is not what it looks like biases a result without a word:
// std::stod reads "0x1A" as 26, "inf" and "nan" as themselves, "1e999" as infinity and "12abc"
// as 12 when the caller forgets to check what was used; seeds read through a double merge two
// large seeds into one (2^53 + 1 is 2^53), and a repeated seed counts one pile twice, which
// shrinks a spread by the square root of the repeats. So every such reader goes through the
// few functions below, which accept exactly one spelling each:
//  - a plain decimal: an optional sign, digits with an optional point, an optional decimal
//    exponent, finite after conversion (no hex, no inf or nan, no overflow, no spaces inside);
//  - a seed: decimal digits only, read as an integer (never through a double), within 0..2^63-1
//    (what a TOML integer can hold, so a seed given on a command line can also be written in a
//    campaign file);
//  - a seed list: seeds separated by commas, each once;
//  - a scale or a tolerance: finite and > 0.
// Each refusal is an InputError naming where the text was (file and line, or the option), the
// text as written, and what was expected.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace reposetwin::experiments {

/// The value of a plain decimal (see the design note); nothing for any other text.
std::optional<double> parse_plain_decimal(std::string_view text);

/// The value of a plain decimal, or InputError `where: "text" is not a number (a plain
/// decimal is expected ...)`.
double plain_decimal(std::string_view text, const std::string& where);

/// The largest seed [-]: 2^63 - 1, a TOML integer's largest value.
inline constexpr std::uint64_t kMaxSeed = 0x7fffffffffffffffull;

/// The value of a seed (decimal digits, at most kMaxSeed); nothing for any other text.
std::optional<std::uint64_t> parse_seed(std::string_view text);

/// The seeds of a comma-separated list, each an exact integer in range and each once. Throws
/// InputError naming `option`, the list as written and the item at fault.
std::vector<std::uint64_t> parse_seed_list(std::string_view text, const std::string& option);

/// Throws InputError naming `where` and the first seed given twice.
void check_distinct_seeds(const std::vector<std::uint64_t>& seeds, const std::string& where);

/// `value` when it is finite and > 0; else InputError naming `where` and the value.
double positive_finite(double value, const std::string& where);

}  // namespace reposetwin::experiments
