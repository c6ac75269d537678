// paper_comparison (report.hpp): our calibrations and predictions beside the paper's Table 3,
// and its section of the page. Stages: read the calibration folders and the paper's CSVs, make
// one row per calibration, per prediction and per paper sample not run here, join each row to
// the paper by sample, sort, and caption with both mu_r conventions.
#include "experiments/report/paper_comparison.hpp"

#include "experiments/io/numbers.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include "experiments/calibration/calibration_file.hpp"
#include "experiments/io/csv.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/report/format.hpp"
#include "experiments/report/gnuplot.hpp"
#include "experiments/report/html.hpp"
#include "experiments/report/report.hpp"
#include "experiments/report/templates.hpp"
#include "sim/contact.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::optional<json> read_json_if_present(const fs::path& p) {
  std::error_code ec;
  if (!fs::is_regular_file(p, ec)) return std::nullopt;
  return read_json_file(p.string());
}

json num_or_null(const json& j, const char* key) {
  return j.contains(key) && j[key].is_number() ? j[key] : json();
}

// The calibration folders' result files, with where to look for the paper's CSVs.
struct CalibrationFolders {
  std::vector<std::string> dirs;
  std::vector<CalibrationRecord> calibrations;  // calibration.json of each folder
  std::vector<json> predictions;   // predictions.json of each folder, or null
  std::vector<fs::path> hints;     // folders of their campaign files
};

CalibrationFolders read_calibration_folders(const std::vector<std::string>& dirs) {
  CalibrationFolders f;
  f.dirs = dirs;
  for (const std::string& d : dirs) {
    const fs::path file = fs::path(d) / "calibration.json";
    std::error_code ec;
    if (!fs::is_regular_file(file, ec))
      throw InputError(d + ": no calibration.json (not a calibration folder)");
    f.calibrations.push_back(read_calibration_record(file.string()));
    const auto p = read_json_if_present(fs::path(d) / "predictions.json");
    f.predictions.push_back(p ? *p : json());
    f.hints.push_back(fs::path(f.calibrations.back().campaign).parent_path());
  }
  return f;
}

// The paper's CSV folder: given, or data/paper found upwards from each hint (and the cwd).
std::string find_paper_dir(const std::string& given, const std::vector<fs::path>& hints) {
  if (!given.empty()) {
    if (!fs::is_regular_file(fs::path(given) / "table3_calibration.csv"))
      throw InputError(given + ": paper data folder without table3_calibration.csv");
    return given;
  }
  std::vector<fs::path> starts = hints;
  starts.push_back(fs::current_path());
  for (fs::path p : starts) {
    p = fs::absolute(p).lexically_normal();
    for (;;) {
      if (fs::is_regular_file(p / "data" / "paper" / "table3_calibration.csv"))
        return (p / "data" / "paper").string();
      if (!p.has_parent_path() || p.parent_path() == p) break;
      p = p.parent_path();
    }
  }
  return "";
}

// Tables 1 and 3 of the paper, rows keyed by sample number.
struct PaperTables {
  std::string dir;  // "" = not found
  std::string t1_file, t3_file;
  std::map<int, json> t1, t3;
  std::string t3_notes;  // Table 3's comment lines, joined
};

std::map<int, json> by_sample(const std::vector<json>& rows, const std::string& file) {
  std::map<int, json> out;
  for (const json& r : rows) {
    const std::string s = r.value("sample", std::string());
    try {
      out[std::stoi(s)] = r;
    } catch (const std::exception&) {
      throw InputError(file + ": field 'sample' = \"" + s + "\" is not a sample number");
    }
  }
  return out;
}

PaperTables read_paper_tables(const std::string& dir) {
  PaperTables t;
  t.dir = dir;
  if (dir.empty()) return t;
  t.t1_file = (fs::path(dir) / "table1_lab_tests.csv").string();
  t.t3_file = (fs::path(dir) / "table3_calibration.csv").string();
  t.t1 = by_sample(read_paper_csv(t.t1_file), t.t1_file);
  t.t3 = by_sample(read_paper_csv(t.t3_file), t.t3_file);
  for (const std::string& n : read_csv_file(t.t3_file).comments) t.t3_notes += n;
  while (!t.t3_notes.empty() && (t.t3_notes.back() == ' ' || t.t3_notes.back() == '.'))
    t.t3_notes.pop_back();
  return t;
}

double csv_number(const json& row, const std::string& field, const std::string& file) {
  const std::string v = row.value(field, std::string());
  return plain_decimal(v, file + ": field '" + field + "'");
}

// Joins a row to the paper by its Table 1 sample number (the paper's d_max, mass, measured
// angle, mu_r and EDEM angle) and adds |ours - measured|.
json join_paper(json r, const json& sample, const PaperTables& paper) {
  r["sample"] = sample;
  for (const char* k : {"paper_d_max_mm", "paper_mass_g", "paper_mu_r", "paper_angle_deg"})
    r[k] = json();
  r["paper_how"] = "";
  if (sample.is_number()) {
    const int s = sample.get<int>();
    if (const auto t1 = paper.t1.find(s); t1 != paper.t1.end()) {
      r["paper_d_max_mm"] = csv_number(t1->second, "d_max_mm", paper.t1_file);
      r["paper_mass_g"] = csv_number(t1->second, "mass_g", paper.t1_file);
      const double measured = csv_number(t1->second, "theta_measured_deg", paper.t1_file);
      if (r["measured_deg"].is_number() &&
          std::abs(r["measured_deg"].get<double>() - measured) > 0.005)
        r["measured_note"] = "the campaign matched " +
                             report::fixed(r["measured_deg"].get<double>()) +
                             " deg, not Table 1's value";
      r["measured_deg"] = measured;
      r["measured_source"] = "Table 1";
    }
    if (const auto t3 = paper.t3.find(s); t3 != paper.t3.end()) {
      r["paper_mu_r"] = csv_number(t3->second, "mu_r", paper.t3_file);
      r["paper_angle_deg"] = csv_number(t3->second, "theta_numerical_deg", paper.t3_file);
      r["paper_how"] = t3->second.value("how", std::string());
    }
  }
  if (r["angle_mean_deg"].is_number() && r["measured_deg"].is_number())
    r["abs_error_deg"] =
        std::abs(r["angle_mean_deg"].get<double>() - r["measured_deg"].get<double>());
  else
    r["abs_error_deg"] = json();
  return r;
}

// Runs of an interval effect measured by simulation ("runs"), else 0.
int interval_runs(const json& effect) {
  if (!effect.is_object() || effect.value("method", "") != "runs") return 0;
  return effect["at_low"].value("n", 0) + effect["at_high"].value("n", 0);
}

// A calibration's row: its angle from the check runs at the calibrated mu_r when the campaign
// ran them, else the fit's value there with the pooled seed sd.
// The calibration's measure as the rows name it: "image" when it was not recorded.
std::string angle_word(const CalibrationRecord& cal) {
  return angle_measure_name(cal.angle.value_or(AngleMeasure::kImage));
}

json interval_open(const CalibrationRecord& cal) {
  return json::array({cal.interval_open_low, cal.interval_open_high});
}

json calibration_row(const CalibrationRecord& cal, const json& pj, const std::string& dir,
                     const std::string& from) {
  json check;
  if (pj.is_object() && pj.contains("predictions"))
    for (const json& p : pj["predictions"])
      if (p.value("check", false) && check.is_null()) check = p;
  json r = {{"kind", "calibration"},
            {"source", dir},
            {"from", from},
            {"angle_measure", angle_word(cal)},
            {"status", to_string(cal.status)},
            {"mu_r", cal.mu_r ? json(*cal.mu_r) : json()},
            {"mu_r_interval", cal.mu_r ? json::array({cal.mu_r_lo, cal.mu_r_hi}) : json()},
            {"interval_open", interval_open(cal)},
            {"measured_deg", cal.target.angle_deg},
            {"measured_source", "campaign target"},
            {"simulations", cal.simulations},
            {"angle_mean_deg", json()},
            {"angle_seed_sd_deg", json()}};
  if (!check.is_null()) {
    r["angle_mean_deg"] = check["mean_deg"];
    r["angle_seed_sd_deg"] = check["seed_sd_deg"];
    r["angle_n"] = check["n"];
    r["angle_how"] = "runs at the calibrated mu_r, n = " + std::to_string(check.value("n", 0));
    const json& e = check.value("interval_effect", json());
    if (e.is_object() && e.value("method", "") == "runs")
      r["interval_effect_deg"] = e["angle_range_deg"];
    r["simulations"] = r["simulations"].get<int>() + check.value("n", 0) + interval_runs(e);
  } else if (cal.mu_r) {
    const auto finite_or_null = [](std::optional<double> x) {
      return x && std::isfinite(*x) ? json(*x) : json();
    };
    r["angle_mean_deg"] = finite_or_null(cal.fitted_angle_deg);
    r["angle_seed_sd_deg"] = finite_or_null(cal.fit.noise_sd_deg);
    r["angle_how"] = "fit at the calibrated mu_r, pooled seed sd";
  }
  return r;
}

// A prediction's row: the other test run at the calibrated mu_r.
json prediction_row(const json& p, const CalibrationRecord& cal, const std::string& dir,
                    const std::string& from) {
  const json& e = p.value("interval_effect", json::object());
  return {{"kind", "prediction"},
          {"name", p.value("name", std::string())},
          {"angle_measure", angle_word(cal)},
          {"source", dir},
          {"from", from},
          {"mu_r", num_or_null(p, "mu_r")},
          {"mu_r_interval", p.value("mu_r_interval", json())},
          {"interval_open", interval_open(cal)},
          {"measured_deg", num_or_null(p, "measured_deg")},
          {"measured_source", "campaign [[predict]]"},
          {"angle_mean_deg", num_or_null(p, "mean_deg")},
          {"angle_seed_sd_deg", num_or_null(p, "seed_sd_deg")},
          {"angle_n", p.value("n", 0)},
          {"angle_how", "runs at the calibrated mu_r, n = " + std::to_string(p.value("n", 0))},
          {"interval_effect_deg", e.value("angle_range_deg", json())},
          {"interval_effect_method", e.value("method", std::string())},
          {"simulations", p.value("n", 0) + interval_runs(e)}};
}

// A paper sample we have no result for, so the table stays beside the whole of Table 3.
json not_run_row() {
  return {{"kind", "not run here"},
          {"source", ""},
          {"from", ""},
          {"mu_r", json()},
          {"mu_r_interval", json()},
          {"interval_open", json::array({false, false})},
          {"measured_deg", json()},
          {"angle_mean_deg", json()},
          {"angle_seed_sd_deg", json()},
          {"simulations", json()}};
}

// By sample, then calibration before prediction before the paper's rows not run here.
std::vector<json> sorted_rows(std::vector<json> rows) {
  auto rank = [](const json& r) {
    const std::string k = r.value("kind", std::string());
    return k == "calibration" ? 0 : k == "prediction" ? 1 : 2;
  };
  auto sample = [](const json& r) { return r["sample"].is_number() ? r["sample"].get<int>() : 1000; };
  std::stable_sort(rows.begin(), rows.end(), [&](const json& a, const json& b) {
    if (sample(a) != sample(b)) return sample(a) < sample(b);
    return rank(a) < rank(b);
  });
  return rows;
}

// Our mu_r conventions, one per rolling model the calibrations used, as sim::kRollingModels
// words them (the calibration's own record when the model is unknown to this build).
json rolling_conventions(const std::vector<CalibrationRecord>& calibrations) {
  std::map<std::string, RollingModelRecord> models;
  for (const CalibrationRecord& cal : calibrations)
    models[cal.rolling_model.keyword] = cal.rolling_model;
  const auto or_unknown = [](const std::string& s) { return s.empty() ? std::string("?") : s; };
  json conventions = json::array();
  for (const auto& [kw, m] : models) {
    const sim::RollingModelInfo* info = sim::find_rolling_model(kw);
    conventions.push_back({{"keyword", kw},
                           {"torque", info ? std::string(info->torque) : or_unknown(m.torque)},
                           {"radius", info ? std::string(info->radius) : or_unknown(m.radius)}});
  }
  return conventions;
}

// The caption: both mu_r conventions, ours and the paper's (from its CSV's own notes).
std::string caption_html(const json& conventions, const PaperTables& paper) {
  report::mustache::data d;
  report::mustache::data list(report::mustache::data::type::list);
  for (const json& c : conventions) {
    report::mustache::data x;
    for (const char* k : {"keyword", "torque", "radius"}) x.set(k, c[k].get<std::string>());
    // For equal spheres R* = R/2: the same torque cap needs about twice EDEM's mu_r.
    x.set("twice", c["radius"].get<std::string>().find("R*") != std::string::npos);
    list.push_back(x);
  }
  d.set("conventions", list);
  if (paper.t3_notes.empty()) {
    d.set("notes", false);
  } else {
    report::mustache::data notes;
    // The file as the repository names it, not the path on the machine that built the page.
    const fs::path t3(paper.t3_file);
    notes.set("file", (t3.parent_path().parent_path().filename() / t3.parent_path().filename() /
                       t3.filename())
                          .string());
    notes.set("text", paper.t3_notes);
    d.set("notes", notes);
  }
  return report::render(report::templates::kComparisonCaption, d);
}

}  // namespace

std::vector<json> read_paper_csv(const std::string& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw InputError(path + ": cannot read the paper's CSV file");
  const CsvTable t = read_csv_file(path);
  if (t.header.empty()) throw InputError(path + ": no header line");
  std::vector<json> rows;
  for (const CsvRecord& r : t.rows) {
    if (r.fields.size() != t.header.size())
      throw InputError(path + ":" + std::to_string(r.line) + ": " +
                       std::to_string(r.fields.size()) + " fields, the header has " +
                       std::to_string(t.header.size()));
    json row = json::object();
    for (std::size_t i = 0; i < r.fields.size(); ++i) row[t.header[i]] = r.fields[i];
    rows.push_back(row);
  }
  return rows;
}

json paper_comparison(const std::vector<std::string>& dirs, const std::string& paper_dir) {
  const CalibrationFolders folders = read_calibration_folders(dirs);
  const PaperTables paper = read_paper_tables(find_paper_dir(paper_dir, folders.hints));
  std::vector<json> rows;
  std::set<int> covered;
  auto add = [&](const json& r, const json& sample) {
    if (sample.is_number()) covered.insert(sample.get<int>());
    rows.push_back(join_paper(r, sample, paper));
  };
  for (std::size_t i = 0; i < dirs.size(); ++i) {
    const CalibrationRecord& cal = folders.calibrations[i];
    const json& pj = folders.predictions[i];
    const std::string& from = cal.campaign_name;
    add(calibration_row(cal, pj, dirs[i], from),
        cal.table1_sample ? json(*cal.table1_sample) : json());
    if (!pj.is_object() || !pj.contains("predictions")) continue;
    for (const json& p : pj["predictions"])
      if (!p.value("check", false))
        add(prediction_row(p, cal, dirs[i], from), p.value("table1_sample", json()));
  }
  for (const auto& [s, row] : paper.t3)
    if (!covered.count(s)) add(not_run_row(), s);
  const json conventions = rolling_conventions(folders.calibrations);
  return {{"rows", sorted_rows(std::move(rows))},
          {"paper_dir", paper.dir},
          {"conventions", conventions},
          {"caption_html", caption_html(conventions, paper)}};
}

// The comparison's section of the campaign report: its table rows and the measured-against-
// simulated plot, made from the rows paper_comparison built above.

namespace report {
namespace {

std::string int_or_dash(const json& v) {
  return v.is_number() ? std::to_string(v.get<int>()) : std::string("-");
}

// Our mu_r with its 95% interval ("<=" / "+" at an end the search left open), or the status.
Cell our_mu_r(const json& r) {
  if (!r["mu_r"].is_number())
    return r.contains("status") ? Cell(r.value("status", std::string())) : Cell("-");
  std::string mu = fixed(r["mu_r"].get<double>(), 3);
  if (r["mu_r_interval"].is_array())
    mu += " [" + std::string(interval_open_at(r, 0) ? "\u2264" : "") +
          fixed(r["mu_r_interval"][0].get<double>(), 3) + ", " +
          fixed(r["mu_r_interval"][1].get<double>(), 3) + (interval_open_at(r, 1) ? "+" : "") + "]";
  return mu;
}

// Our angle: mean ± seed sd, how it was obtained, and the mu_r interval's effect.
Cell our_angle(const json& r) {
  if (!r["angle_mean_deg"].is_number()) return "-";
  Cell c(fixed(r["angle_mean_deg"].get<double>()) + " \u00b1 " +
         fixed_or_dash(r["angle_seed_sd_deg"]));
  c.small = "(" + r.value("angle_how", std::string()) +
            "; angle: " + r.value("angle_measure", std::string("image")) + ")";
  if (r.contains("interval_effect_deg") && r["interval_effect_deg"].is_array())
    c.note = "over the mu_r interval: " + fixed(r["interval_effect_deg"][0].get<double>()) +
             " to " + fixed(r["interval_effect_deg"][1].get<double>());
  return c;
}

TableRow comparison_row(const json& r) {
  const bool pred = r.value("kind", std::string()) == "prediction";
  Cell kind(r.value("kind", std::string()));
  if (pred) {
    kind.bold = "prediction";
    kind.text = "(calibrated on " + r.value("from", std::string()) + ")";
  }
  Cell measured(as_printed(r["measured_deg"]));
  if (r.contains("measured_note")) measured.note = r["measured_note"].get<std::string>();
  Cell paper_mu(as_printed(r["paper_mu_r"]));
  paper_mu.small = r.value("paper_how", std::string());
  Cell source;
  source.code = fs::path(r.value("source", std::string())).lexically_normal().filename().string();
  if (source.code.empty())  // a folder given with a trailing slash
    source.code =
        fs::path(r.value("source", std::string())).lexically_normal().parent_path().filename().string();
  return {{int_or_dash(r["sample"]), as_printed(r["paper_d_max_mm"]),
           as_printed(r["paper_mass_g"]), measured, paper_mu, as_printed(r["paper_angle_deg"]),
           kind, our_mu_r(r), our_angle(r), fixed_or_dash(r["abs_error_deg"]),
           int_or_dash(r["simulations"]), source},
          pred};
}

Table comparison_table(const json& cmp) {
  Table t;
  t.caption_html = cmp.value("caption_html", std::string());
  t.header = {"sample",
              "d_max [mm]",
              "mass [g]",
              "measured [deg] (Table 1)",
              "paper mu_r (EDEM)",
              "paper angle [deg] (EDEM)",
              "ours: how",
              "our mu_r [95% interval]",
              "our angle [deg] mean \u00b1 seed sd",
              "|ours - measured| [deg]",
              "simulations",
              "source"};
  for (const json& r : cmp["rows"]) t.rows.push_back(comparison_row(r));
  return t;
}

// The measured-against-simulated plot; returns the PNG's name, or "" when there is nothing to
// plot or gnuplot failed.
std::string comparison_plot(const json& cmp, const fs::path& out) {
  std::ostringstream cal, pred, paper;
  std::set<int> paper_done;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;  // common axis range [deg]
  auto extend = [&](double a, double b) {
    lo = std::min(lo, a);
    hi = std::max(hi, b);
  };
  for (const json& r : cmp["rows"]) {
    if (!r["measured_deg"].is_number()) continue;
    const double x = r["measured_deg"].get<double>();
    std::string label;  // "s<sample>" (built in steps: GCC 12 warns falsely on "s" + string)
    if (r["sample"].is_number()) label.append("s").append(std::to_string(r["sample"].get<int>()));
    if (r["angle_mean_deg"].is_number()) {
      const double sd =
          r["angle_seed_sd_deg"].is_number() ? r["angle_seed_sd_deg"].get<double>() : 0.0;
      const double y = r["angle_mean_deg"].get<double>();
      extend(std::min(x, y - sd), std::max(x, y + sd));
      (r.value("kind", std::string()) == "prediction" ? pred : cal)
          << x << " " << y << " " << sd << " \"" << label << "\"\n";
    }
    if (r["paper_angle_deg"].is_number() && r["sample"].is_number() &&
        paper_done.insert(r["sample"].get<int>()).second) {
      const double y = r["paper_angle_deg"].get<double>();
      paper << x << " " << y << " \"" << label << "\"\n";
      extend(std::min(x, y), std::max(x, y));
    }
  }
  std::string plot;
  auto series = [&](const std::string& name, const std::string& data, const std::string& how) {
    if (data.empty()) return;
    write_file_atomic((out / name).string(), data);
    plot += (plot.empty() ? "plot '" : ", '") + name + "' " + how;
  };
  series("comparison_calibration.dat", cal.str(),
         "using 1:2:3 with yerrorbars pt 7 lc rgb '#1f77b4' title 'ours: calibrated (mean +- seed "
         "sd)'");
  series("comparison_prediction.dat", pred.str(),
         "using 1:2:3 with yerrorbars pt 5 lc rgb '#d62728' title 'ours: predicted (mean +- seed "
         "sd)'");
  series(
      "comparison_paper.dat", paper.str(),
      "using 1:2 with points pt 4 ps 1.5 lc rgb '#2ca02c' title 'paper Table 3 (EDEM, one run)'");
  if (plot.empty()) return "";
  plot += ", x with lines dt 2 lc rgb 'gray' title 'simulated = measured'\n";
  const std::string range = "[" + fixed(lo - 1.0, 1) + ":" + fixed(hi + 1.0, 1) + "]";
  const fs::path png = out / "comparison.png";
  run_gnuplot(out / "comparison.gp",
              png_terminal(png, 650, 720) +
                  "set xlabel 'measured angle, Table 1 [deg]'\n"
                  "set ylabel 'simulated angle [deg]'\nset key outside below\n"
                  "set size square\nset xrange " + range + "\nset yrange " + range + "\n" +
                  plot,
              png);
  return "comparison.png";
}

}  // namespace

std::string comparison_section(const json& cmp, const fs::path& out) {
  mustache::data d;
  d.set("plot", text_or_false(comparison_plot(cmp, out)));
  d.set("comparison", to_data(comparison_table(cmp)));
  return render(templates::kComparison, d);
}

}  // namespace report
}  // namespace reposetwin::experiments
