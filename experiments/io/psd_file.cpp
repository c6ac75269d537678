#include "experiments/io/psd_file.hpp"

#include <array>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "experiments/io/toml_tables.hpp"

namespace reposetwin::experiments {
namespace {

constexpr std::array<std::string_view, 9> kKeys = {
    "name",     "provenance", "assumption",          "sieve_mm", "passing_percent", "d_max_mm",
    "d_min_mm", "fines",      "interval_sd_fraction"};

// The node as TOML text (strings quoted), for messages.
std::string show(const toml::node& node) {
  std::ostringstream s;
  node.visit([&](auto&& n) { s << n; });
  std::string text = s.str();
  constexpr std::size_t kMax = 80;
  if (text.size() > kMax) text = text.substr(0, kMax) + "...";
  return text;
}

// "file:line: [psd].key"
std::string locate(const std::string& source, const std::string& where, const std::string& key,
                   const toml::node* node) {
  // A stream, since GCC 12 warns falsely (-Wrestrict) on ":" + std::to_string(line).
  std::ostringstream s;
  s << source;
  if (node != nullptr && node->source().begin.line > 0) s << ':' << node->source().begin.line;
  s << ": [" << where << ']';
  if (!key.empty()) s << '.' << key;
  return s.str();
}

[[noreturn]] void bad(const std::string& at, const std::string& message) {
  throw std::invalid_argument(at + ": " + message);
}

std::string read_string(const toml::table& t, const std::string& key, const std::string& source,
                        const std::string& where) {
  const toml::node* node = t.get(key);
  if (node == nullptr) return {};
  if (!node->is_string()) {
    bad(locate(source, where, key, node), show(*node) + " must be a string");
  }
  return std::string(*node->value<std::string_view>());
}

bool read_number(const toml::table& t, const std::string& key, const std::string& source,
                 const std::string& where, double& out) {
  const toml::node* node = t.get(key);
  if (node == nullptr) return false;
  if (!node->is_number()) {
    bad(locate(source, where, key, node), show(*node) + " must be a number");
  }
  out = *node->value<double>();
  if (!std::isfinite(out)) bad(locate(source, where, key, node), show(*node) + " must be finite");
  return true;
}

std::vector<double> read_numbers(const toml::table& t, const std::string& key,
                                 const std::string& source, const std::string& where) {
  const toml::node* node = t.get(key);
  if (node == nullptr) {
    bad(locate(source, where, key, nullptr), "is missing (an array of numbers is required)");
  }
  const toml::array* array = node->as_array();
  if (array == nullptr) {
    bad(locate(source, where, key, node), show(*node) + " must be an array of numbers");
  }
  std::vector<double> values;
  for (std::size_t i = 0; i < array->size(); ++i) {
    const toml::node& item = *array->get(i);
    if (!item.is_number()) {
      bad(locate(source, where, key + "[" + std::to_string(i) + "]", &item),
          show(item) + " must be a number");
    }
    if (!std::isfinite(*item.value<double>())) {
      bad(locate(source, where, key + "[" + std::to_string(i) + "]", &item),
          show(item) + " must be finite");
    }
    values.push_back(*item.value<double>());
  }
  return values;
}

}  // namespace

PsdFile parse_psd_table(const toml::table& t, const std::string& source, const std::string& where) {
  for (const auto& [key, node] : t) {
    bool known = false;
    for (std::string_view k : kKeys) known = known || key.str() == k;
    if (!known) {
      std::string allowed;
      for (std::string_view k : kKeys) allowed += (allowed.empty() ? "" : ", ") + std::string(k);
      bad(locate(source, where, std::string(key.str()), &node),
          "unknown key (value " + show(node) + "); allowed keys: " + allowed);
    }
  }

  PsdFile f;
  f.source = source;
  f.name = read_string(t, "name", source, where);
  f.provenance = read_string(t, "provenance", source, where);
  f.assumption = read_string(t, "assumption", source, where);

  const std::vector<double> sieve_mm = read_numbers(t, "sieve_mm", source, where);
  const std::vector<double> passing = read_numbers(t, "passing_percent", source, where);
  for (double d : sieve_mm) f.spec.table.size.push_back(d * 1e-3);
  f.spec.table.passing = passing;

  double value = 0.0;
  if (read_number(t, "d_max_mm", source, where, value)) {
    if (!(value > 0.0)) {
      bad(locate(source, where, "d_max_mm", t.get("d_max_mm")),
          show(*t.get("d_max_mm")) + " must be positive");
    }
    f.spec.d_max = value * 1e-3;
  }
  if (read_number(t, "d_min_mm", source, where, value)) {
    if (!(value > 0.0)) {
      bad(locate(source, where, "d_min_mm", t.get("d_min_mm")),
          show(*t.get("d_min_mm")) + " must be positive");
    }
    f.spec.d_min = value * 1e-3;
  }
  if (read_number(t, "interval_sd_fraction", source, where, value)) {
    f.spec.interval_sd_fraction = value;
  }
  if (const toml::node* node = t.get("fines")) {
    const std::string fines = read_string(t, "fines", source, where);
    if (fines == "renormalise") {
      f.spec.fines = sim::FinesPolicy::kRenormalise;
    } else if (fines == "drop") {
      f.spec.fines = sim::FinesPolicy::kDrop;
    } else {
      bad(locate(source, where, "fines", node),
          show(*node) + " is not a fines policy (\"renormalise\" or \"drop\")");
    }
  }

  // The table and the cuts are checked by the engine's own rules; name the keys they concern.
  try {
    sim::validate_sieve_table(f.spec.table);
  } catch (const std::invalid_argument& e) {
    bad(locate(source, where, "sieve_mm / passing_percent", nullptr), e.what());
  }
  try {
    sim::resolve_psd(f.spec);
  } catch (const std::invalid_argument& e) {
    bad(locate(source, where, "d_max_mm / d_min_mm / interval_sd_fraction", nullptr), e.what());
  }
  return f;
}

PsdFile read_psd_file(const std::string& path) {
  toml::table root;
  try {
    root = toml::parse_file(path);
  } catch (const toml::parse_error& e) {
    const auto& at = e.source().begin;
    std::ostringstream m;
    m << path;
    if (at.line > 0) m << ':' << at.line << ':' << at.column;
    m << ": cannot read the sieve-table file: " << e.description();
    throw std::runtime_error(m.str());
  }
  for (const auto& [key, node] : root) {
    if (key.str() != "psd") {
      bad(locate(path, std::string(key.str()), "", &node),
          "unknown top-level key; a sieve-table file holds only the [psd] table");
    }
  }
  const toml::table* psd = root["psd"].as_table();
  if (psd == nullptr) {
    bad(path + ": [psd]", root.contains("psd") ? "must be a table" : "is missing");
  }
  return parse_psd_table(*psd, path, "psd");
}

}  // namespace reposetwin::experiments
