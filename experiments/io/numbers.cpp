#include "experiments/io/numbers.hpp"

#include <charconv>
#include <cmath>
#include <regex>
#include <set>

#include "experiments/io/format.hpp"
#include "experiments/io/input_error.hpp"

namespace reposetwin::experiments {

namespace {

// The one spelling of a plain decimal.
const std::regex kPlainDecimal(R"([+-]?([0-9]+(\.[0-9]*)?|\.[0-9]+)([eE][+-]?[0-9]+)?)");

std::string shown(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  return significant(v);
}

}  // namespace

std::optional<double> parse_plain_decimal(std::string_view text) {
  if (!std::regex_match(text.begin(), text.end(), kPlainDecimal)) return std::nullopt;
  // from_chars reads no leading '+'; the sign is checked by the pattern above.
  const std::string_view digits = text.front() == '+' ? text.substr(1) : text;
  double v = 0.0;
  const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), v);
  if (ec != std::errc() || end != digits.data() + digits.size() || !std::isfinite(v))
    return std::nullopt;  // out of range ("1e999"), never infinity
  return v;
}

double plain_decimal(std::string_view text, const std::string& where) {
  if (const std::optional<double> v = parse_plain_decimal(text)) return *v;
  throw InputError(where + ": \"" + std::string(text) +
                   "\" is not a number (a plain decimal is expected: digits, an optional point "
                   "and exponent; no hex, inf, nan or out-of-range value)");
}

std::optional<std::uint64_t> parse_seed(std::string_view text) {
  if (text.empty() || text.find_first_not_of("0123456789") != std::string_view::npos)
    return std::nullopt;
  std::uint64_t v = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || end != text.data() + text.size() || v > kMaxSeed) return std::nullopt;
  return v;
}

std::vector<std::uint64_t> parse_seed_list(std::string_view text, const std::string& option) {
  std::vector<std::uint64_t> seeds;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = text.find(',', start);
    const std::string_view item = text.substr(
        start, comma == std::string_view::npos ? std::string_view::npos : comma - start);
    const std::optional<std::uint64_t> seed = parse_seed(item);
    if (!seed)
      throw InputError(option + " " + std::string(text) + ": \"" + std::string(item) +
                           "\" is not a seed (an integer 0.." + std::to_string(kMaxSeed) +
                           ", digits only)",
                       option);
    seeds.push_back(*seed);
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  check_distinct_seeds(seeds, option + " " + std::string(text));
  return seeds;
}

void check_distinct_seeds(const std::vector<std::uint64_t>& seeds, const std::string& where) {
  std::set<std::uint64_t> seen;
  for (std::uint64_t s : seeds)
    if (!seen.insert(s).second)
      throw InputError(where + ": seed " + std::to_string(s) +
                       " is given twice; each seed is one independent pile, so a repeat would "
                       "count one pile twice");
}

double positive_finite(double value, const std::string& where) {
  if (!(std::isfinite(value) && value > 0.0))
    throw InputError(where + " = " + shown(value) + ": must be a finite number > 0");
  return value;
}

}  // namespace reposetwin::experiments
