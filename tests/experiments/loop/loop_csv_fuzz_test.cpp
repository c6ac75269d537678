// Loop CSV fuzz, by property: the loop's example sheet (data/loop/example.csv, five tiny-scene
// tests), with every column dropped and duplicated in turn, every pair of columns that set one
// scene key (mass_kg and mass_g, a named column and its set:KEY, ...), every cell replaced by
// junk (empty, words, NaN, infinities, signs, overflow, hex, a comma that splits the row, a
// quoted comma, padding) and rows cut or lengthened; each read as `reposetwin loop DATA.csv`
// reads it (read_lab_csv). The property, for every mutation:
//  - either it is refused with an InputError naming the file and the column (a cell or a
//    column), or the line (a row's shape), and no other exception type, no crash,
//  - or it is accepted with one test per data row, each complete and finite: a safe, unique id;
//    a base scene that exists and builds with the row's overrides; an angle in (0, 90); H and D
//    (when typed) finite and positive; a crest finite and >= 0; repeats from 1 to 1000; every
//    numeric condition finite and positive (each equal to its cell); and a column that sets a
//    scene key sets it alone.
// Deterministic: every mutation is enumerated; no randomness.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <typeinfo>
#include <vector>

#include "experiments/io/input_error.hpp"
#include "experiments/io/scene_overrides.hpp"
#include "experiments/loop/loop_data.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;

const fs::path kData = fs::path(REPOSETWIN_SOURCE_DIR) / "data/loop";

struct Sheet {
  std::vector<std::string> comments;            // the lines above the header
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;   // cells as written (no quoting applied)

  std::string text() const {
    std::string t;
    for (const std::string& c : comments) t += c + "\n";
    auto line = [](const std::vector<std::string>& cells) {
      std::string s;
      for (std::size_t i = 0; i < cells.size(); ++i) s += (i ? "," : "") + cells[i];
      return s + "\n";
    };
    t += line(header);
    for (const auto& r : rows) t += line(r);
    return t;
  }
  int header_line() const { return static_cast<int>(comments.size()) + 1; }
  int row_line(std::size_t r) const { return header_line() + 1 + static_cast<int>(r); }
};

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, ',')) out.push_back(cell);
  if (!line.empty() && line.back() == ',') out.push_back("");
  return out;
}

Sheet example() {
  std::ifstream in(kData / "example.csv");
  Sheet s;
  std::string line;
  while (std::getline(in, line)) {
    if (s.header.empty() && (line.empty() || line[0] == '#')) {
      s.comments.push_back(line);
    } else if (s.header.empty()) {
      s.header = split(line);
    } else if (!line.empty()) {
      s.rows.push_back(split(line));
      s.rows.back().resize(s.header.size());
    }
  }
  return s;
}

struct Case {
  std::string what;
  Sheet sheet;
  std::vector<std::string> names;  // a refusal names one of these (a column, "line N")
  std::vector<std::string> also;   // ... and every one of these (the other column of a pair)
  int at_least = 1;                // ... at least this many of `names`
};

std::string check(const fs::path& file, const Case& c) {
  { std::ofstream(file, std::ios::trunc) << c.sheet.text(); }
  std::optional<LabData> data;
  try {
    data = read_lab_csv(file.string());
  } catch (const InputError& e) {
    const std::string what = e.what();
    if (what.find(file.filename().string()) == std::string::npos)
      return "refused without the file: " + what;
    int named = 0;
    for (const std::string& n : c.names) named += what.find(n) != std::string::npos ? 1 : 0;
    if (!c.names.empty() && named < c.at_least)
      return "refused without naming " + std::to_string(c.at_least) + " of " + c.names.front() +
             "...: " + what;
    for (const std::string& n : c.also)
      if (what.find(n) == std::string::npos) return "refused without naming " + n + ": " + what;
    return "";
  } catch (const std::exception& e) {
    return std::string("another exception (") + typeid(e).name() + "): " + e.what();
  }
  if (data->tests.size() != c.sheet.rows.size())
    return "accepted with " + std::to_string(data->tests.size()) + " tests for " +
           std::to_string(c.sheet.rows.size()) + " rows";
  std::set<std::string> ids;
  for (const LabTest& t : data->tests) {
    const std::string at = "test " + t.id + ": ";
    if (t.id.empty() || !ids.insert(t.id).second) return at + "accepted with an empty or repeated id";
    if (t.id.find_first_of("/\\ ,") != std::string::npos) return at + "accepted with an unsafe id";
    if (!fs::is_regular_file(t.scene_path)) return at + "accepted without a scene file";
    if (!(std::isfinite(t.angle_deg) && t.angle_deg > 0 && t.angle_deg < 90))
      return at + "accepted with angle " + std::to_string(t.angle_deg);
    for (const auto& v : {t.height_mm, t.diameter_mm})
      if (v && !(std::isfinite(*v) && *v > 0)) return at + "accepted with H or D " + std::to_string(*v);
    if (t.crest_mm && !(std::isfinite(*t.crest_mm) && *t.crest_mm >= 0))
      return at + "accepted with crest " + std::to_string(*t.crest_mm);
    if (!(t.repeats >= 1 && t.repeats <= 1000)) return at + "accepted with repeats " + std::to_string(t.repeats);
    if (t.camera_height_m && !(std::isfinite(*t.camera_height_m) && *t.camera_height_m >= 0))
      return at + "accepted with camera height " + std::to_string(*t.camera_height_m);
    for (const auto& [column, v] : t.conditions)
      if (!std::isfinite(v)) return at + "accepted with condition " + column + " = " + std::to_string(v);
    std::set<std::string> keys;
    for (const auto& [key, value] : t.overrides)
      if (!keys.insert(key).second) return at + "accepted with two columns setting " + key;
    std::vector<std::string> sets;
    for (const auto& [key, value] : t.overrides) sets.push_back(key + "=" + value);
    try {
      (void)load_scene(t.scene_path, sets);
    } catch (const std::exception& e) {
      return at + "accepted, but its scene does not build: " + e.what();
    }
  }
  return "";
}

std::string line_of(const Sheet& s, std::size_t r) { return "line " + std::to_string(s.row_line(r)); }
// The same line as a parse error writes it: FILE:N.
std::string file_line_of(const Sheet& s, std::size_t r) {
  return "fuzz_data.csv:" + std::to_string(s.row_line(r));
}

std::vector<Case> mutations() {
  const Sheet base = example();
  std::vector<Case> out;
  const std::size_t ncol = base.header.size();
  const std::string header_line = "line " + std::to_string(base.header_line());
  // Columns dropped and duplicated.
  for (std::size_t c = 0; c < ncol; ++c) {
    Case drop{"drop " + base.header[c], base, {base.header[c], header_line}, {}};
    drop.sheet.header.erase(drop.sheet.header.begin() + static_cast<long>(c));
    for (auto& r : drop.sheet.rows) r.erase(r.begin() + static_cast<long>(c));
    out.push_back(drop);
    Case dup{"duplicate " + base.header[c], base, {base.header[c]}, {}};
    dup.sheet.header.push_back(base.header[c]);
    for (std::size_t r = 0; r < dup.sheet.rows.size(); ++r) dup.sheet.rows[r].push_back(base.rows[r][c]);
    out.push_back(dup);
  }
  // Two columns setting one scene key: a named condition column and set:KEY, or two named ones.
  for (const ConditionColumn& a : condition_columns()) {
    std::vector<std::string> rivals = {std::string("set:") + a.key};
    for (const ConditionColumn& b : condition_columns())
      if (std::string(a.key) == b.key && std::string(a.column) != b.column) rivals.push_back(b.column);
    for (const std::string& rival : rivals) {
      Case k{"columns " + std::string(a.column) + " and " + rival, base, {a.column}, {rival}};
      const bool has_a = std::find(base.header.begin(), base.header.end(), a.column) != base.header.end();
      if (!has_a) {
        k.sheet.header.push_back(a.column);
        for (auto& r : k.sheet.rows) r.push_back(a.factor == 0.0 ? "plate" : "0.02");
      }
      k.sheet.header.push_back(rival);
      for (auto& r : k.sheet.rows)
        r.push_back(rival.rfind("set:", 0) == 0 ? (a.factor == 0.0 ? "plate" : "0.02")
                                                : (a.factor == 0.0 ? "plate" : "20"));
      // The refusal names two of the columns that set the key (the sheet may already hold a
      // third, which then conflicts first).
      k.names.clear();
      k.also.clear();
      for (const std::string& h : k.sheet.header) {
        std::string key = h.rfind("set:", 0) == 0 ? h.substr(4) : std::string();
        for (const ConditionColumn& c : condition_columns())
          if (h == c.column) key = c.key;
        if (key == a.key) k.names.push_back(h);
      }
      k.at_least = 2;
      out.push_back(k);
    }
  }
  // Junk in every cell.
  const std::vector<std::string> junk = {"",     "abc",  "nan",  "NaN",    "inf",   "-inf",
                                         "-1",   "0",    "-0",   "1e300",  "1e-300", "1e400",
                                         "0x10", "5abc", " 5 ",  "\"a,b\"", "1,5",   "\"",
                                         "../x", "1e5",  "31.5", "calibrate"};
  for (std::size_t r = 0; r < base.rows.size(); ++r)
    for (std::size_t c = 0; c < ncol; ++c)
      for (const std::string& j : junk) {
        Case k{line_of(base, r) + " " + base.header[c] + " = [" + j + "]", base,
               {base.header[c]}, {line_of(base, r)}};
        k.sheet.rows[r][c] = j;
        // A cell that changes the row's shape is a row error: the line suffices.
        if (j == "1,5" || j == "\"")
          k = {k.what, k.sheet, {line_of(base, r), file_line_of(base, r)}, {}};
        out.push_back(k);
      }
  // Rows cut and lengthened, blank and repeated.
  for (std::size_t r = 0; r < base.rows.size(); ++r) {
    Case cut{"cut " + line_of(base, r), base, {line_of(base, r)}, {}};
    cut.sheet.rows[r].pop_back();
    cut.sheet.rows[r].pop_back();
    out.push_back(cut);
    Case longer{"lengthen " + line_of(base, r), base, {line_of(base, r)}, {}};
    longer.sheet.rows[r].push_back("extra");
    out.push_back(longer);
    Case twice{"repeat " + line_of(base, r), base, {"appears twice", "id"}, {}};
    twice.sheet.rows.push_back(base.rows[r]);
    out.push_back(twice);
  }
  Case empty_rows{"no rows", base, {"no test rows"}, {}};
  empty_rows.sheet.rows.clear();
  out.push_back(empty_rows);
  Case unknown{"unknown column", base, {"W_cm"}, {}};
  unknown.sheet.header[4] = "W_cm";
  out.push_back(unknown);
  return out;
}

TEST(LoopCsvFuzz, EveryColumnDroppedDuplicatedConflictingAndEveryCellJunk) {
  const fs::path dir = fs::temp_directory_path() / "reposetwin_loop_csv_fuzz";
  fs::remove_all(dir);
  fs::create_directories(dir);
  fs::copy_file(kData / "tiny_scene.toml", dir / "tiny_scene.toml");
  const fs::path file = dir / "fuzz_data.csv";
  const std::vector<Case> cases = mutations();
  ASSERT_GT(cases.size(), 1300u);
  ASSERT_EQ(check(file, {"the example", example(), {}, {}}), "");
  int broken = 0;
  for (const Case& c : cases) {
    const std::string why = check(file, c);
    if (!why.empty() && ++broken <= 40) ADD_FAILURE() << c.what << ": " << why.substr(0, 400);
  }
  EXPECT_EQ(broken, 0) << "of " << cases.size() << " mutations";
}

}  // namespace
}  // namespace reposetwin::experiments
