#include "experiments/io/psd_file.hpp"

#include "experiments/io/numbers.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "experiments/io/csv.hpp"
#include "experiments/io/files.hpp"
#include "experiments/io/format.hpp"
#include "experiments/io/suggest.hpp"
#include "experiments/io/toml_tables.hpp"
#include "experiments/io/toml_reader.hpp"

namespace reposetwin::experiments {

bool is_csv_sheet(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".csv";
}

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
  s << ": ";
  if (key.empty()) {
    s << where;
    return s.str();
  }
  // Each key of a list ("sieve_mm / passing_percent") as the user writes it: where.key.
  std::size_t from = 0;
  for (;;) {
    const std::size_t bar = key.find(" / ", from);
    s << where << '.' << key.substr(from, bar == std::string::npos ? bar : bar - from);
    if (bar == std::string::npos) break;
    s << " / ";
    from = bar + 3;
  }
  return s.str();
}

// Sieve openings a grading can have [mm]: a micrometre to ten metres; beyond them a value is a
// typo (a unit slip of 10^3 or an exponent), and would make a time step or a grain count absurd.
constexpr double kMinSieveMm = 1e-3;
constexpr double kMaxSieveMm = 1e4;

std::string sieve_range_text(double mm) {
  std::ostringstream s;
  s << "= " << mm << " mm is outside [" << kMinSieveMm << ", " << kMaxSieveMm
    << "] mm (sieve openings in millimetres)";
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
  out = *number_of(*node);
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
    if (!std::isfinite(*number_of(item))) {
      bad(locate(source, where, key + "[" + std::to_string(i) + "]", &item),
          show(item) + " must be finite");
    }
    values.push_back(*number_of(item));
  }
  return values;
}

// The table and the cuts are checked by the engine's own rules; `table_at` and `cuts_at` name
// where they were written (keys or columns) in its messages.
void check_psd(const PsdFile& f, const std::string& table_at, const std::string& cuts_at) {
  try {
    sim::validate_sieve_table(f.spec.table);
  } catch (const std::invalid_argument& e) {
    bad(table_at, e.what());
  }
  try {
    sim::resolve_psd(f.spec);
  } catch (const std::invalid_argument& e) {
    bad(cuts_at, e.what());
  }
}

std::string trimmed(const std::string& s) {
  const auto first = s.find_first_not_of(" \t");
  if (first == std::string::npos) return "";
  return s.substr(first, s.find_last_not_of(" \t") - first + 1);
}

// A table listed coarsest first, read finest first: sizes strictly decreasing are reversed with
// their values. Returns whether it did.
bool finest_first(sim::SieveTable& t) {
  if (t.size.size() < 2) return false;
  for (std::size_t i = 1; i < t.size.size(); ++i)
    if (!(t.size[i] < t.size[i - 1])) return false;
  std::reverse(t.size.begin(), t.size.end());
  std::reverse(t.passing.begin(), t.passing.end());
  return true;
}

void add_note(PsdFile& f, const std::string& note) {
  f.note += (f.note.empty() ? "" : "; ") + note;
}

// The value columns a CSV sieve sheet may give beside sieve_mm.
enum class SheetValues { kPassing, kRetained, kCumulativeRetained };
constexpr std::array<std::string_view, 4> kCsvColumns = {
    "sieve_mm", "passing_percent", "retained_percent", "cumulative_retained_percent"};

// Percent retained (on each sieve, or cumulative) as cumulative percent passing, on a table
// already finest first. Passing at a sieve is 100 minus what it and the coarser sieves retain.
void to_passing(PsdFile& f, SheetValues kind, const std::string& path) {
  std::vector<double>& v = f.spec.table.passing;
  if (kind == SheetValues::kCumulativeRetained) {
    for (double& x : v) x = 100.0 - x;
    add_note(f, "cumulative percent retained converted to percent passing (100 - retained)");
    return;
  }
  double above = 0.0;
  for (std::size_t i = v.size(); i-- > 0;) {
    if (!(v[i] >= 0.0)) bad(path, "retained_percent = " + shortest_text(v[i]) + " is negative");
    above += v[i];
    v[i] = 100.0 - above;
  }
  if (above > 100.0 + 0.5)
    bad(path, "retained_percent sums to " + shortest_text(above) +
                  " % over the sieves, above 100 %: not percent retained on each sieve (a "
                  "cumulative column is cumulative_retained_percent)");
  add_note(f, "percent retained on each sieve converted to cumulative percent passing (passing "
              "at a sieve = 100 - what it and the coarser sieves retain; " +
              shortest_text(100.0 - above) + " % passes the finest sieve)");
}

// A sieve sheet as CSV (psd_file.hpp's second form): the header names the two columns, each
// row one sieve.
PsdFile read_psd_csv(const std::string& path) {
  const CsvTable csv = read_csv_file(path);
  const std::string at = path + ":" + std::to_string(csv.header_line);
  if (csv.header.empty())
    bad(path, "is empty; a sieve sheet's header is " + std::string(kCsvHeader));
  int sieve = -1, passing = -1;
  SheetValues kind = SheetValues::kPassing;
  std::string value_name = "passing_percent";
  for (std::size_t i = 0; i < csv.header.size(); ++i) {
    const std::string name = trimmed(csv.header[i]);
    int* column = name == "sieve_mm" ? &sieve : nullptr;
    for (std::size_t k = 1; k < kCsvColumns.size(); ++k)
      if (name == kCsvColumns[k]) {
        if (passing >= 0)
          bad(at, "columns \"" + value_name + "\" and \"" + name +
                      "\" both give the sieves' values; keep one");
        column = &passing;
        kind = static_cast<SheetValues>(k - 1);
        value_name = name;
      }
    if (column == nullptr)
      bad(at, "column " + std::to_string(i + 1) + " \"" + name +
                  "\" is not a sieve-sheet column" + did_you_mean(name, kCsvColumns, "\"") +
                  "; the header must be " + kCsvHeader +
                  " (sieve opening in mm, cumulative percent passing by mass), or sieve_mm with "
                  "retained_percent or cumulative_retained_percent");
    if (*column >= 0 && column == &sieve) bad(at, "column \"" + name + "\" is named twice");
    *column = static_cast<int>(i);
  }
  if (sieve < 0 || passing < 0)
    bad(at, std::string("the header lacks \"") + (sieve < 0 ? "sieve_mm" : "passing_percent") +
                "\"; it must be " + kCsvHeader);
  PsdFile f;
  f.source = path;
  f.name = std::filesystem::path(path).stem().string();
  f.provenance = "sieve sheet " + path;
  for (const std::string& c : csv.comments)
    f.provenance += (f.provenance.empty() ? "" : "; ") + trimmed(c);
  for (const CsvRecord& row : csv.rows) {
    const std::string line = path + ":" + std::to_string(row.line);
    if (row.fields.size() != csv.header.size())
      bad(line, std::to_string(row.fields.size()) + " fields, the header has " +
                    std::to_string(csv.header.size()));
    const auto number = [&](int column, const char* name) {
      const std::string text = trimmed(row.fields[static_cast<std::size_t>(column)]);
      const std::optional<double> v = parse_plain_decimal(text);
      if (!v)
        bad(line, std::string(name) + " = \"" + text +
                      "\" is not a number (a plain decimal is expected: no hex, inf, nan or "
                      "out-of-range value)");
      return *v;
    };
    const double mm = number(sieve, "sieve_mm");
    if (!(mm >= kMinSieveMm && mm <= kMaxSieveMm))
      bad(line, "sieve_mm " + sieve_range_text(mm));
    f.spec.table.size.push_back(1e-3 * mm);
    f.spec.table.passing.push_back(number(passing, value_name.c_str()));
  }
  if (csv.rows.empty()) bad(path, "has a header and no sieves");
  if (finest_first(f.spec.table)) add_note(f, "listed coarsest first; read finest first");
  if (kind != SheetValues::kPassing) to_passing(f, kind, path);
  check_psd(f, path + ": columns sieve_mm / " + value_name,
            path + ": the sheet's sizes against the scene's sample.d_min_mm / d_max_mm");
  return f;
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
          "unknown key (value " + show(node) + ")" + did_you_mean(std::string(key.str()), kKeys) +
              "; allowed keys: " + allowed);
    }
  }

  PsdFile f;
  f.source = source;
  f.name = read_string(t, "name", source, where);
  f.provenance = read_string(t, "provenance", source, where);
  f.assumption = read_string(t, "assumption", source, where);

  const std::vector<double> sieve_mm = read_numbers(t, "sieve_mm", source, where);
  for (std::size_t i = 0; i < sieve_mm.size(); ++i)
    if (!(sieve_mm[i] >= kMinSieveMm && sieve_mm[i] <= kMaxSieveMm))
      bad(locate(source, where, "sieve_mm[" + std::to_string(i) + "]", nullptr),
          sieve_range_text(sieve_mm[i]));
  const std::vector<double> passing = read_numbers(t, "passing_percent", source, where);
  for (double d : sieve_mm) f.spec.table.size.push_back(d * 1e-3);
  f.spec.table.passing = passing;
  if (f.spec.table.size.size() == passing.size() && finest_first(f.spec.table))
    add_note(f, "listed coarsest first; read finest first");

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
    if (!(value > 0.0 && value <= 1.0)) {
      bad(locate(source, where, "interval_sd_fraction", t.get("interval_sd_fraction")),
          show(*t.get("interval_sd_fraction")) + " must lie in (0, 1]");
    }
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

  check_psd(f, locate(source, where, "sieve_mm / passing_percent", nullptr),
            locate(source, where, "d_max_mm / d_min_mm / interval_sd_fraction", nullptr));
  return f;
}

namespace {
// A sieve sheet is a few dozen lines; a file far larger is not one.
constexpr std::uintmax_t kMaxSieveSheetBytes = std::uintmax_t{16} << 20;
}  // namespace

toml::table psd_table_of_file(const std::string& path) {
  if (!is_csv_sheet(path)) {
    const PsdFile checked = read_psd_file(path);  // the same errors as the run's reader
    (void)checked;
    return *toml::parse(read_file(path, kMaxSieveSheetBytes), path)["psd"].as_table();
  }
  const PsdFile f = read_psd_csv(path);
  toml::array sieve, passing;
  for (double d : f.spec.table.size) sieve.push_back(1e3 * d);
  for (double p : f.spec.table.passing) passing.push_back(p);
  return toml::table{{"name", f.name},
                     {"provenance", f.note.empty() ? f.provenance
                                                   : f.provenance + "; read: " + f.note},
                     {"sieve_mm", std::move(sieve)},
                     {"passing_percent", std::move(passing)}};
}

PsdFile read_psd_file(const std::string& path) {
  if (is_csv_sheet(path)) return read_psd_csv(path);
  toml::table root;
  // Read through the file layer: a FIFO or a device named as a sieve sheet is refused before a
  // byte is read, not waited on.
  const std::string text = read_file(path, kMaxSieveSheetBytes);
  try {
    root = toml::parse(text, path);
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
