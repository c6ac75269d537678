#include "experiments/report/report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <set>
#include <sstream>

#include "experiments/calibration/calibration.hpp"
#include "experiments/io/csv.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/io/input_error.hpp"
#include "sim/contact.hpp"
#include "vision/measure.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::string html_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '&':
        out += "&amp;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string fmt(double v, int digits = 2) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

/// Runs gnuplot on a script; returns false (and the report says so) if gnuplot is missing.
bool gnuplot(const std::string& script_path, const std::string& script) {
  write_file_atomic(script_path, script);
  const std::string cmd = "gnuplot '" + script_path + "' 2>&1";
  FILE* p = ::popen(cmd.c_str(), "r");
  if (!p) return false;
  char buf[256];
  std::string out;
  while (std::fgets(buf, sizeof buf, p)) out += buf;
  return ::pclose(p) == 0;
}

/// One case of the report: its runs' results.
struct CaseRows {
  std::string name;
  std::string scene;  // the scene file of its runs ("" for a single run)
  json overrides;
  std::vector<double> image_deg, flank_deg, particle_deg, slice_deg;
  std::vector<std::string> stops;
  std::vector<std::string> run_dirs;  // relative to the report's source folder
  json provenance;
};

std::optional<json> read_json_file(const fs::path& p) {
  std::error_code ec;
  if (!fs::is_regular_file(p, ec)) return std::nullopt;
  try {
    return json::parse(read_file(p.string()));
  } catch (const json::exception& e) {
    throw InputError(p.string() + ": not valid JSON (" + e.what() + ")");
  }
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

// Paper rows keyed by sample number.
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

double csv_number(const json& row, const std::string& field, const std::string& file) {
  const std::string v = row.value(field, std::string());
  try {
    std::size_t used = 0;
    const double d = std::stod(v, &used);
    if (used == v.size()) return d;
  } catch (const std::exception&) {
  }
  throw InputError(file + ": field '" + field + "' = \"" + v + "\" is not a number");
}

json num_or_null(const json& j, const char* key) {
  return j.contains(key) && j[key].is_number() ? j[key] : json();
}

std::string fmt_or_dash(const json& v, int digits = 2) {
  return v.is_number() ? fmt(v.get<double>(), digits) : std::string("-");
}

// The paper's numbers as printed (shortest form: 0.15, 3.35, 200), no digits added.
std::string paper_or_dash(const json& v) {
  if (!v.is_number()) return "-";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g", v.get<double>());
  return buf;
}

// Whether the mu_r interval of a comparison row is open at end i (0 low, 1 high).
bool open_end(const json& r, std::size_t i) {
  const json& o = r.value("interval_open", json());
  return o.is_array() && o.size() > i && o[i].is_boolean() && o[i].get<bool>();
}

// The paper comparison as an HTML table with its caption; the plot is made by the caller.
std::string comparison_html(const json& cmp, const std::string& plot_png) {
  std::ostringstream h;
  h << "<h2>Beside the paper's Table 3</h2>\n";
  if (!plot_png.empty())
    h << "<img src='" << plot_png << "' alt='measured against simulated angle'>\n";
  h << "<table><caption style='caption-side:bottom;text-align:left;max-width:1000px'>"
    << cmp.value("caption_html", std::string()) << "</caption>\n"
    << "<tr><th>sample</th><th>d_max [mm]</th><th>mass [g]</th><th>measured [deg] (Table 1)</th>"
       "<th>paper mu_r (EDEM)</th><th>paper angle [deg] (EDEM)</th><th>ours: how</th>"
       "<th>our mu_r [95% interval]</th><th>our angle [deg] mean &plusmn; seed sd</th>"
       "<th>|ours - measured| [deg]</th><th>simulations</th><th>source</th></tr>\n";
  for (const json& r : cmp["rows"]) {
    const bool pred = r.value("kind", std::string()) == "prediction";
    std::string mu = "-";
    if (r["mu_r"].is_number()) {
      mu = fmt(r["mu_r"].get<double>(), 3);
      if (r["mu_r_interval"].is_array())
        mu += " [" + std::string(open_end(r, 0) ? "&le;" : "") +
              fmt(r["mu_r_interval"][0].get<double>(), 3) + ", " +
              fmt(r["mu_r_interval"][1].get<double>(), 3) + std::string(open_end(r, 1) ? "+" : "") +
              "]";
    } else if (r.contains("status")) {
      mu = html_escape(r.value("status", std::string()));
    }
    std::string angle = "-";
    if (r["angle_mean_deg"].is_number()) {
      angle = fmt(r["angle_mean_deg"].get<double>()) + " &plusmn; " +
              fmt_or_dash(r["angle_seed_sd_deg"]) + " <small>(" +
              html_escape(r.value("angle_how", std::string())) +
              "; angle: " + html_escape(r.value("angle_measure", std::string("image"))) +
              ")</small>";
      if (r.contains("interval_effect_deg") && r["interval_effect_deg"].is_array())
        angle +=
            "<br><small>over the mu_r interval: " + fmt(r["interval_effect_deg"][0].get<double>()) +
            " to " + fmt(r["interval_effect_deg"][1].get<double>()) + "</small>";
    }
    std::string kind = html_escape(r.value("kind", std::string()));
    if (pred)
      kind =
          "<b>prediction</b> (calibrated on " + html_escape(r.value("from", std::string())) + ")";
    h << "<tr" << (pred ? " style='background:#eef'" : "") << "><td>"
      << (r["sample"].is_number() ? std::to_string(r["sample"].get<int>()) : "-") << "</td><td>"
      << paper_or_dash(r["paper_d_max_mm"]) << "</td><td>" << paper_or_dash(r["paper_mass_g"])
      << "</td><td>" << paper_or_dash(r["measured_deg"])
      << (r.contains("measured_note")
              ? "<br><small>" + html_escape(r["measured_note"].get<std::string>()) + "</small>"
              : std::string())
      << "</td><td>" << paper_or_dash(r["paper_mu_r"]) << " <small>"
      << html_escape(r.value("paper_how", std::string())) << "</small></td><td>"
      << paper_or_dash(r["paper_angle_deg"]) << "</td><td>" << kind << "</td><td>" << mu
      << "</td><td>" << angle << "</td><td>" << fmt_or_dash(r["abs_error_deg"]) << "</td><td>"
      << (r["simulations"].is_number() ? std::to_string(r["simulations"].get<int>()) : "-")
      << "</td><td><code>" << html_escape(r.value("source", std::string()))
      << "</code></td></tr>\n";
  }
  h << "</table>\n";
  return h.str();
}

// measured-against-simulated plot of the comparison; returns the PNG's name or "".
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
          << x << " " << r["angle_mean_deg"].get<double>() << " " << sd << " \"" << label << "\"\n";
    }
    if (r["paper_angle_deg"].is_number() && r["sample"].is_number() &&
        paper_done.insert(r["sample"].get<int>()).second) {
      const double y = r["paper_angle_deg"].get<double>();
      paper << x << " " << y << " \"" << label << "\"\n";
      extend(std::min(x, y), std::max(x, y));
    }
  }
  std::vector<std::string> parts;
  auto series = [&](const std::string& name, const std::string& data, const std::string& how) {
    if (data.empty()) return;
    write_file_atomic((out / name).string(), data);
    std::string part = "'";
    part += (out / name).string();
    part += "' ";
    part += how;
    parts.push_back(std::move(part));
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
  if (parts.empty()) return "";
  std::string plot = "plot ";
  for (const auto& p : parts) plot += p + ", ";
  plot += "x with lines dt 2 lc rgb 'gray' title 'simulated = measured'\n";
  const bool ok = gnuplot((out / "comparison.gp").string(),
                          "set terminal pngcairo size 650,720\nset output '" +
                              (out / "comparison.png").string() +
                              "'\nset xlabel 'measured angle, Table 1 [deg]'\n"
                              "set ylabel 'simulated angle [deg]'\nset key outside below\n"
                              "set size square\nset xrange [" +
                              fmt(lo - 1.0, 1) + ":" + fmt(hi + 1.0, 1) + "]\nset yrange [" +
                              fmt(lo - 1.0, 1) + ":" + fmt(hi + 1.0, 1) + "]\n" + plot);
  return ok ? "comparison.png" : "";
}

// A folder is a calibration folder when it holds calibration.json.
bool is_calibration_dir(const fs::path& d) { return fs::is_regular_file(d / "calibration.json"); }

bool holds_results(const fs::path& d) {
  return fs::is_regular_file(d / "result.json") || fs::is_directory(d / "cases") ||
         is_calibration_dir(d) || fs::is_regular_file(d / "campaign.json");
}

// The lab photo measured by the same code as the renders, shown beside a render overlay.
std::string lab_photo_html(const ReportSettings& settings, const fs::path& out,
                           const fs::path& render_overlay, const std::string& render_caption,
                           json& summary) {
  if (settings.lab_photo.empty()) return "";
  const cv::Mat photo = cv::imread(settings.lab_photo, cv::IMREAD_COLOR);
  if (photo.empty()) throw InputError(settings.lab_photo + ": not an image");
  vision::ScaleSpec scale;
  if (settings.lab_mm_per_px > 0) scale.mm_per_px = settings.lab_mm_per_px;
  const vision::SideMeasurement m = vision::measure_side(photo, scale, {}, settings.lab_photo);
  cv::imwrite((out / "lab_photo.measured.png").string(), vision::draw_side_overlay(photo, m));
  std::ostringstream h;
  h << "<h2>Lab photo beside the simulated render</h2>\n"
    << "<figure><img src='lab_photo.measured.png' width='480'><figcaption>lab photo "
    << html_escape(fs::path(settings.lab_photo).filename().string())
    << ": theta = atan(2H/D) = " << fmt(m.theta_deg) << " &plusmn; " << fmt(m.sigma_theta_deg)
    << " deg (vision, as the renders)</figcaption></figure>\n";
  summary["lab_photo"] = vision::to_json(m);
  if (!render_overlay.empty() && fs::exists(render_overlay)) {
    fs::copy_file(render_overlay, out / "render_beside_lab.png",
                  fs::copy_options::overwrite_existing);
    h << "<figure><img src='render_beside_lab.png' width='480'><figcaption>"
      << html_escape(render_caption) << "</figcaption></figure>\n";
    summary["lab_photo_render"] = render_caption;
  } else {
    h << "<p>(no simulated render with a measurement overlay in this folder)</p>\n";
  }
  return h.str();
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

json paper_comparison(const std::vector<std::string>& dirs, const std::string& paper_dir_in) {
  std::vector<json> cals, preds;
  std::vector<fs::path> hints;
  for (const std::string& d : dirs) {
    const auto cal = read_json_file(fs::path(d) / "calibration.json");
    if (!cal) throw InputError(d + ": no calibration.json (not a calibration folder)");
    cals.push_back(*cal);
    const auto p = read_json_file(fs::path(d) / "predictions.json");
    preds.push_back(p ? *p : json());
    if (cal->contains("campaign") && (*cal)["campaign"].is_string())
      hints.push_back(fs::path((*cal)["campaign"].get<std::string>()).parent_path());
  }
  const std::string paper_dir = find_paper_dir(paper_dir_in, hints);
  std::map<int, json> t1, t3;
  std::vector<std::string> t3_notes;
  std::string t1_file, t3_file;
  if (!paper_dir.empty()) {
    t1_file = (fs::path(paper_dir) / "table1_lab_tests.csv").string();
    t3_file = (fs::path(paper_dir) / "table3_calibration.csv").string();
    t1 = by_sample(read_paper_csv(t1_file), t1_file);
    t3 = by_sample(read_paper_csv(t3_file), t3_file);
    t3_notes = read_csv_file(t3_file).comments;
  }

  json rows = json::array();
  std::set<int> covered;
  std::map<std::string, json> models;  // rolling model keyword -> its row of sim::kRollingModels
  auto with_paper = [&](json r, const json& sample) {
    r["sample"] = sample;
    for (const char* k : {"paper_d_max_mm", "paper_mass_g", "paper_mu_r", "paper_angle_deg"})
      r[k] = json();
    r["paper_how"] = "";
    if (sample.is_number()) {
      const int s = sample.get<int>();
      covered.insert(s);
      if (t1.count(s)) {
        r["paper_d_max_mm"] = csv_number(t1[s], "d_max_mm", t1_file);
        r["paper_mass_g"] = csv_number(t1[s], "mass_g", t1_file);
        const double measured = csv_number(t1[s], "theta_measured_deg", t1_file);
        if (r["measured_deg"].is_number() &&
            std::abs(r["measured_deg"].get<double>() - measured) > 0.005)
          r["measured_note"] = "the campaign matched " + fmt(r["measured_deg"].get<double>()) +
                               " deg, not Table 1's value";
        r["measured_deg"] = measured;
        r["measured_source"] = "Table 1";
      }
      if (t3.count(s)) {
        r["paper_mu_r"] = csv_number(t3[s], "mu_r", t3_file);
        r["paper_angle_deg"] = csv_number(t3[s], "theta_numerical_deg", t3_file);
        r["paper_how"] = t3[s].value("how", std::string());
      }
    }
    if (r["angle_mean_deg"].is_number() && r["measured_deg"].is_number())
      r["abs_error_deg"] =
          std::abs(r["angle_mean_deg"].get<double>() - r["measured_deg"].get<double>());
    else
      r["abs_error_deg"] = json();
    rows.push_back(r);
  };
  for (std::size_t i = 0; i < cals.size(); ++i) {
    const json& cal = cals[i];
    const json& pj = preds[i];
    const std::string from = cal.value("campaign_name", fs::path(dirs[i]).filename().string());
    if (cal.contains("rolling_model") && cal["rolling_model"].is_object())
      models[cal["rolling_model"].value("keyword", std::string("?"))] = cal["rolling_model"];
    const json sample = cal.value("table1_sample", json());
    json check;
    if (pj.is_object() && pj.contains("predictions"))
      for (const json& p : pj["predictions"])
        if (p.value("check", false) && check.is_null()) check = p;
    json r = {
        {"kind", "calibration"},
        {"source", dirs[i]},
        {"from", from},
        {"angle_measure", cal.value("angle", std::string("image"))},
        {"status", cal.value("status", std::string())},
        {"mu_r", num_or_null(cal, "mu_r")},
        {"mu_r_interval", cal.value("mu_r_interval", json())},
        {"interval_open", cal.value("interval_open", json::array({false, false}))},
        {"measured_deg", cal.contains("target") ? num_or_null(cal["target"], "angle_deg") : json()},
        {"measured_source", "campaign target"},
        {"simulations", cal.value("simulations", 0)},
        {"angle_mean_deg", json()},
        {"angle_seed_sd_deg", json()}};
    if (!check.is_null()) {
      r["angle_mean_deg"] = check["mean_deg"];
      r["angle_seed_sd_deg"] = check["seed_sd_deg"];
      r["angle_n"] = check["n"];
      r["angle_how"] = "runs at the calibrated mu_r, n = " + std::to_string(check.value("n", 0));
      int extra = check.value("n", 0);
      if (check.contains("interval_effect") &&
          check["interval_effect"].value("method", "") == "runs") {
        extra += check["interval_effect"]["at_low"].value("n", 0) +
                 check["interval_effect"]["at_high"].value("n", 0);
        r["interval_effect_deg"] = check["interval_effect"]["angle_range_deg"];
      }
      r["simulations"] = r["simulations"].get<int>() + extra;
    } else if (cal["mu_r"].is_number()) {
      r["angle_mean_deg"] = num_or_null(cal, "fitted_angle_deg");
      r["angle_seed_sd_deg"] =
          cal.contains("fit") ? num_or_null(cal["fit"], "noise_sd_deg") : json();
      r["angle_how"] = "fit at the calibrated mu_r, pooled seed sd";
    }
    with_paper(r, sample);
    if (pj.is_object() && pj.contains("predictions")) {
      for (const json& p : pj["predictions"]) {
        if (p.value("check", false)) continue;
        int n = p.value("n", 0);
        const json& e = p.value("interval_effect", json::object());
        if (e.value("method", "") == "runs")
          n += e["at_low"].value("n", 0) + e["at_high"].value("n", 0);
        json q = {
            {"kind", "prediction"},
            {"name", p.value("name", std::string())},
            {"angle_measure", cal.value("angle", std::string("image"))},
            {"source", dirs[i]},
            {"from", from},
            {"mu_r", num_or_null(p, "mu_r")},
            {"mu_r_interval", p.value("mu_r_interval", json())},
            {"interval_open", cal.value("interval_open", json::array({false, false}))},
            {"measured_deg", num_or_null(p, "measured_deg")},
            {"measured_source", "campaign [[predict]]"},
            {"angle_mean_deg", num_or_null(p, "mean_deg")},
            {"angle_seed_sd_deg", num_or_null(p, "seed_sd_deg")},
            {"angle_n", p.value("n", 0)},
            {"angle_how", "runs at the calibrated mu_r, n = " + std::to_string(p.value("n", 0))},
            {"interval_effect_deg", e.value("angle_range_deg", json())},
            {"interval_effect_method", e.value("method", std::string())},
            {"simulations", n}};
        with_paper(q, p.value("table1_sample", json()));
      }
    }
  }
  // The paper's rows we have no result for, so the table stays beside the whole of Table 3.
  for (const auto& [s, row] : t3) {
    if (covered.count(s)) continue;
    json r = {{"kind", "not run here"},
              {"source", ""},
              {"from", ""},
              {"mu_r", json()},
              {"mu_r_interval", json()},
              {"interval_open", json::array({false, false})},
              {"measured_deg", json()},
              {"angle_mean_deg", json()},
              {"angle_seed_sd_deg", json()},
              {"simulations", json()}};
    with_paper(r, s);
  }
  std::vector<json> sorted(rows.begin(), rows.end());
  auto rank = [](const json& r) {
    const std::string k = r.value("kind", std::string());
    return k == "calibration" ? 0 : k == "prediction" ? 1 : 2;
  };
  std::stable_sort(sorted.begin(), sorted.end(), [&](const json& a, const json& b) {
    const int sa = a["sample"].is_number() ? a["sample"].get<int>() : 1000;
    const int sb = b["sample"].is_number() ? b["sample"].get<int>() : 1000;
    if (sa != sb) return sa < sb;
    return rank(a) < rank(b);
  });

  // Caption: both mu_r conventions, ours from sim::kRollingModels, the paper's from its CSV.
  std::ostringstream cap;
  cap << "Our mu_r is that of the scene's rolling model; the paper's is EDEM's. ";
  json conventions = json::array();
  for (const auto& [kw, m] : models) {
    const sim::RollingModelInfo* info = sim::find_rolling_model(kw);
    const std::string torque =
        info ? std::string(info->torque) : m.value("torque", std::string("?"));
    const std::string radius =
        info ? std::string(info->radius) : m.value("radius", std::string("?"));
    cap << "Ours (<code>" << html_escape(kw) << "</code>): " << html_escape(torque)
        << "; lever arm " << html_escape(radius) << ". ";
    if (radius.find("R*") != std::string::npos)
      cap << "For equal spheres R* = R/2, half EDEM's lever arm R, so the same torque cap needs "
             "about twice EDEM's mu_r. ";
    conventions.push_back({{"keyword", kw}, {"torque", torque}, {"radius", radius}});
  }
  if (!t3_notes.empty()) {
    cap << "Paper (from " << html_escape(t3_file) << "):";
    std::string notes;
    for (const auto& n : t3_notes) notes += n;
    while (!notes.empty() && (notes.back() == ' ' || notes.back() == '.')) notes.pop_back();
    cap << html_escape(notes) << ". ";
  } else {
    cap << "Paper: EDEM, lever arm R = contact-to-centre distance (paper data not found: give "
           "--paper-data). ";
  }
  cap << "Angles: ours atan(2H/D) as measured (see each calibration's angle method), the paper's "
         "EDEM angle a protractor on a centre slice, the lab's atan(2H/D) from a photo. "
         "Predictions (shaded) run the other test at the calibrated mu_r; their mu_r interval "
         "effect is the angle range at the interval's ends. Simulations count every run used.";
  return {{"rows", sorted},
          {"paper_dir", paper_dir},
          {"conventions", conventions},
          {"caption_html", cap.str()}};
}

json build_report(const std::string& dir_in, const ReportSettings& settings) {
  const fs::path dir(dir_in);
  // A parent of several result folders: the comparison report over them.
  if (fs::is_directory(dir) && !holds_results(dir)) {
    std::vector<std::string> subs;
    for (const auto& e : fs::directory_iterator(dir))
      if (e.is_directory() && holds_results(e.path())) subs.push_back(e.path().string());
    std::sort(subs.begin(), subs.end());
    if (!subs.empty()) return build_report(subs, dir_in, settings);
  }
  std::map<std::string, CaseRows> cases;
  std::vector<std::string> order;
  json calibration;
  std::string title = settings.title;

  auto add_result = [&](const std::string& case_name, const json& overrides, const json& r,
                        const std::string& run_dir, const std::string& scene = "") {
    if (!cases.count(case_name)) {
      order.push_back(case_name);
      cases[case_name].name = case_name;
      cases[case_name].overrides = overrides;
      cases[case_name].scene = scene;
    }
    CaseRows& c = cases[case_name];
    const std::string reason = r.at("stop").at("reason").get<std::string>();
    c.stops.push_back(reason);
    c.run_dirs.push_back(run_dir);
    c.provenance = r.at("provenance");
    // A run stopped by a physics failure (overlap, NaN, escape) has no valid pile: it is listed
    // with its stop reason but its angles never enter a mean.
    if (reason.rfind("physics", 0) == 0) return;
    const json& pile = r.at("pile");
    c.particle_deg.push_back(pile.value("theta_hd_deg", 0.0));
    c.slice_deg.push_back(pile.value("slice_angle_mean_deg", 0.0));
    if (r.contains("image")) {
      c.image_deg.push_back(r["image"].at("theta_deg").get<double>());
      if (r["image"].contains("flank_deg"))
        c.flank_deg.push_back(r["image"]["flank_deg"].get<double>());
    }
  };

  if (fs::exists(dir / "result.json") && !fs::exists(dir / "campaign.json")) {  // one run
    const json r = json::parse(read_file((dir / "result.json").string()));
    if (!r.contains("pile")) throw InputError(dir_in + "/result.json: not a run result");
    json rr = r;
    if (fs::exists(dir / "images" / "measurement.json")) {
      const json m = json::parse(read_file((dir / "images" / "measurement.json").string()));
      rr["image"] = {{"theta_deg", m.at("theta_deg")}, {"flank_deg", m.at("flank_deg")}};
    }
    add_result(r["provenance"].value("scene_name", "run"), json::object(), rr, ".");
    if (title.empty()) title = r["provenance"].value("scene_name", "run");
  }
  // Campaign or calibration folders: every finished run below cases/.
  if (fs::exists(dir / "cases")) {
    std::vector<fs::path> results;
    for (const auto& e : fs::recursive_directory_iterator(dir / "cases"))
      if (e.path().filename() == "result.json" &&
          e.path().parent_path().filename().string().rfind("seed_", 0) == 0)
        results.push_back(e.path());
    std::sort(results.begin(), results.end());
    for (const fs::path& p : results) {
      const json meta = json::parse(read_file(p.string()));
      if (!meta.contains("result")) continue;
      const json& spec = meta.at("spec");
      add_result(spec.at("case"), spec.value("overrides", json::object()), meta.at("result"),
                 fs::relative(p.parent_path() / "run", dir).string(),
                 spec.value("scene", std::string()));
    }
    if (fs::exists(dir / "campaign.json") && title.empty())
      title = json::parse(read_file((dir / "campaign.json").string())).value("campaign", "");
  }
  if (fs::exists(dir / "calibration.json"))
    calibration = json::parse(read_file((dir / "calibration.json").string()));
  if (cases.empty() && calibration.is_null())
    throw InputError(dir_in + ": no run, campaign or calibration results to report");
  if (title.empty()) title = dir.filename().string();

  const fs::path out = dir / "report";
  fs::create_directories(out);
  json summary = {{"title", title}, {"cases", json::array()}};
  std::ostringstream data;  // index x image_mean image_sd particle_mean particle_sd
  int k = 0;
  for (const std::string& name : order) {
    const CaseRows& c = cases[name];
    const SampleStats im = sample_stats(c.image_deg), pa = sample_stats(c.particle_deg),
                      sl = sample_stats(c.slice_deg), fl = sample_stats(c.flank_deg);
    summary["cases"].push_back({{"case", name},
                                {"runs", c.run_dirs.size()},
                                {"image_theta_mean_deg", im.mean},
                                {"image_theta_sd_deg", im.sd},
                                {"image_flank_mean_deg", fl.n ? json(fl.mean) : json()},
                                {"image_flank_sd_deg", fl.n ? json(fl.sd) : json()},
                                {"particle_theta_mean_deg", pa.mean},
                                {"particle_theta_sd_deg", pa.sd},
                                {"slice_angle_mean_deg", sl.mean},
                                {"overrides", c.overrides}});
    data << k++ << " " << im.mean << " " << im.sd << " " << pa.mean << " " << pa.sd << " \"" << name
         << "\" " << (fl.n ? fl.mean : NAN) << " " << (fl.n ? fl.sd : NAN) << "\n";
  }
  bool plotted = false;
  if (!order.empty()) {
    write_file_atomic((out / "angles.dat").string(), data.str());
    plotted =
        gnuplot((out / "angles.gp").string(),
                "set terminal pngcairo size 900,500 noenhanced\nset output '" +
                    (out / "angles.png").string() +
                    "'\nset ylabel 'angle of repose [deg]'\nset xtics rotate by -30\n"
                    "set key top left\nset offsets 0.5,0.5,2,2\nplot '" +
                    (out / "angles.dat").string() +
                    "' using 1:2:3:xtic(6) with yerrorbars pt 7 title 'image atan(2H/D) "
                    "(vision on renders)', '' using ($1+0.1):4:5 with yerrorbars pt 5 "
                    "title 'particles atan(2H/D)', '' using ($1+0.2):7:8 with yerrorbars pt 9 "
                    "title 'image flank angle (vision on renders)'\n");
  }
  bool calib_plot = false;
  if (!calibration.is_null() && calibration.contains("observations")) {
    std::ostringstream obs;
    for (const json& o : calibration["observations"])
      obs << o.value("mu_r", 0.0) << " " << o.value("angle_deg", 0.0) << "\n";
    write_file_atomic((out / "calibration.dat").string(), obs.str());
    std::string target =
        calibration.contains("target") ? fmt(calibration["target"].value("angle_deg", 0.0)) : "0";
    calib_plot = gnuplot((out / "calibration.gp").string(),
                         "set terminal pngcairo size 700,500\nset output '" +
                             (out / "calibration.png").string() +
                             "'\nset xlabel 'mu_r'\nset ylabel 'angle [deg]'\nset key top left\n"
                             "plot '" +
                             (out / "calibration.dat").string() +
                             "' using 1:2 with points pt 7 title 'runs (one per seed)', " + target +
                             " with lines dt 2 title 'target'\n");
  }
  // The render shown beside the lab photo: for a calibration, the run of the calibration scene
  // nearest the calibrated mu_r (a check run at it when there is one); otherwise the first case
  // with a measured render.
  fs::path beside;
  std::string beside_caption;
  auto overlay_of = [&](const CaseRows& c) -> fs::path {
    for (const auto& d : c.run_dirs) {
      const fs::path p = dir / d / "images" / "side_az000.measured.png";
      if (fs::exists(p)) return p;
    }
    return {};
  };
  if (calibration.is_object() && calibration.contains("mu_r") && calibration["mu_r"].is_number()) {
    const double mu = calibration["mu_r"].get<double>();
    const std::string key = calibration.value("key", std::string());
    const std::string scene = calibration.value("scene", std::string());
    double best = std::numeric_limits<double>::infinity();
    for (const std::string& name : order) {
      const CaseRows& c = cases[name];
      if (!c.overrides.contains(key) || !c.overrides[key].is_number()) continue;
      if (!scene.empty() && !c.scene.empty() && c.scene != scene) continue;
      const fs::path p = overlay_of(c);
      if (p.empty()) continue;
      const double d = std::abs(c.overrides[key].get<double>() - mu);
      const bool check_run = name.rfind("predict_", 0) == 0;  // a run at mu_r itself, preferred
      if (d < best || (d == best && check_run)) {
        best = d;
        beside = p;
        beside_caption = "simulated: " + name + " (" + key + " = " +
                         fmt(c.overrides[key].get<double>(), 4) + ", calibrated mu_r " +
                         fmt(mu, 4) + "), azimuth 0";
      }
    }
  }
  for (std::size_t i = 0; beside.empty() && i < order.size(); ++i) {
    beside = overlay_of(cases[order[i]]);
    if (!beside.empty())
      beside_caption = "simulated: " + order[i] + " (first run with a render), azimuth 0";
  }
  const std::string lab_html = lab_photo_html(settings, out, beside, beside_caption, summary);

  // The paper comparison for a calibration folder.
  std::string comparison;
  if (is_calibration_dir(dir)) {
    const json cmp = paper_comparison({dir_in}, settings.paper_dir);
    comparison = comparison_html(cmp, comparison_plot(cmp, out));
    summary["paper_comparison"] = cmp;
  }

  std::ostringstream h;
  h << "<!doctype html><html><head><meta charset='utf-8'><title>" << html_escape(title)
    << "</title><style>body{font-family:sans-serif;max-width:1100px;margin:auto}"
       "table{border-collapse:collapse}td,th{border:1px solid #aaa;padding:3px 6px;font-size:13px}"
       "figure{display:inline-block;margin:4px}</style></head><body>\n";
  h << "<h1>ReposeTwin report: " << html_escape(title) << "</h1>\n<p>Built " << utc_now() << " by "
    << code_version() << " from <code>" << html_escape(fs::absolute(dir).string())
    << "</code>.</p>\n";
  h << lab_html << comparison;
  if (plotted)
    h << "<h2>Angles per case</h2><img src='angles.png'>\n";
  else if (!order.empty())
    h << "<p>(gnuplot not available: no plot)</p>\n";
  if (!order.empty()) {
    h << "<h2>Cases</h2><table><tr><th>case</th><th>inputs (overrides)</th><th>runs</th>"
         "<th>image angle [deg] mean &plusmn; sd (runs stopped by a physics failure left out)</th>"
         "<th>image flank angle [deg]</th><th>particle atan(2H/D) [deg]</th>"
         "<th>slice (protractor) [deg]</th><th>stop reasons</th><th>provenance</th>"
         "<th>files</th></tr>\n";
    for (const std::string& name : order) {
      const CaseRows& c = cases[name];
      const SampleStats im = sample_stats(c.image_deg), pa = sample_stats(c.particle_deg),
                        sl = sample_stats(c.slice_deg), fl = sample_stats(c.flank_deg);
      std::map<std::string, int> stops;
      for (const auto& s : c.stops) ++stops[s];
      std::string stop_text;
      for (const auto& [s, n] : stops) stop_text += s + " x" + std::to_string(n) + " ";
      const json& p = c.provenance;
      std::string files;
      for (const auto& d : c.run_dirs) files += "<a href='../" + d + "/series.pvd'>pvd</a> ";
      h << "<tr><td>" << html_escape(name) << "</td><td><code>" << html_escape(c.overrides.dump())
        << "</code></td><td>" << c.run_dirs.size() << "</td><td>"
        << (im.n ? fmt(im.mean) + " &plusmn; " + fmt(im.sd) : "-") << "</td><td>"
        << (fl.n ? fmt(fl.mean) + " &plusmn; " + fmt(fl.sd) : "-") << "</td><td>"
        << fmt(pa.mean) + " &plusmn; " + fmt(pa.sd) << "</td><td>" << fmt(sl.mean) << "</td><td>"
        << html_escape(stop_text) << "</td><td>dt " << p.value("time_step_s", 0.0) << " s, E "
        << p.value("softened_youngs_modulus_pa", json(0.0)).dump() << " Pa, "
        << html_escape(p.value("code_version", std::string("?"))) << "</td><td>" << files
        << "</td></tr>\n";
    }
    h << "</table>\n<h2>Renders with measurement overlays</h2>\n";
    for (const std::string& name : order) {
      const CaseRows& c = cases[name];
      const fs::path overlay = dir / c.run_dirs.front() / "images" / "side_az000.measured.png";
      if (!fs::exists(overlay)) continue;
      const std::string local = name + "_side.png";
      fs::copy_file(overlay, out / local, fs::copy_options::overwrite_existing);
      h << "<figure><img src='" << html_escape(local) << "' width='480'><figcaption>"
        << html_escape(name) << " (first run, azimuth 0)</figcaption></figure>\n";
    }
  }
  if (!calibration.is_null()) {
    h << "<h2>Calibration</h2>";
    if (calib_plot) h << "<img src='calibration.png'>";
    h << "<pre>" << html_escape(calibration.dump(2)) << "</pre>\n";
    summary["calibration"] = calibration;
  }
  if (const auto pj = read_json_file(dir / "predictions.json")) {
    h << "<h2>Predictions at the calibrated mu_r</h2><pre>" << html_escape(pj->dump(2))
      << "</pre>\n";
    summary["predictions"] = *pj;
  }
  h << "</body></html>\n";
  write_file_atomic((out / "index.html").string(), h.str());
  write_json_atomic((out / "summary.json").string(), summary);
  return summary;
}

json build_report(const std::vector<std::string>& dirs, const std::string& out_dir,
                  const ReportSettings& settings) {
  if (dirs.empty()) throw InputError("report: no folders given");
  if (dirs.size() == 1 && (out_dir.empty() || fs::equivalent(dirs[0], out_dir)) &&
      holds_results(dirs[0]))
    return build_report(dirs[0], settings);
  const fs::path out = fs::path(out_dir) / "report";
  fs::create_directories(out);
  std::vector<std::string> cal_dirs;
  json summary = {
      {"title", settings.title.empty() ? std::string("paper comparison") : settings.title},
      {"folders", json::array()}};
  std::ostringstream links;
  ReportSettings sub = settings;
  // Each folder's own report shows the lab photo beside its render; this page shows it alone.
  sub.title.clear();
  for (const std::string& d : dirs) {
    if (!holds_results(d))
      throw InputError(d + ": no run, campaign or calibration results to report");
    const json s = build_report(d, sub);
    if (is_calibration_dir(d)) cal_dirs.push_back(d);
    const fs::path page = fs::absolute(fs::path(d) / "report" / "index.html");
    links << "<li><a href='" << html_escape(fs::relative(page, fs::absolute(out)).string()) << "'>"
          << html_escape(d) << "</a> (" << html_escape(s.value("title", std::string()))
          << ")</li>\n";
    summary["folders"].push_back({{"dir", d}, {"title", s.value("title", std::string())}});
  }
  std::string lab_html = lab_photo_html(settings, out, {}, "", summary);
  std::string comparison;
  if (!cal_dirs.empty()) {
    const json cmp = paper_comparison(cal_dirs, settings.paper_dir);
    comparison = comparison_html(cmp, comparison_plot(cmp, out));
    summary["paper_comparison"] = cmp;
  }
  const std::string title = summary["title"].get<std::string>();
  std::ostringstream h;
  h << "<!doctype html><html><head><meta charset='utf-8'><title>" << html_escape(title)
    << "</title><style>body{font-family:sans-serif;max-width:1200px;margin:auto}"
       "table{border-collapse:collapse}td,th{border:1px solid #aaa;padding:3px 6px;font-size:13px}"
       "figure{display:inline-block;margin:4px}</style></head><body>\n";
  h << "<h1>ReposeTwin report: " << html_escape(title) << "</h1>\n<p>Built " << utc_now() << " by "
    << code_version() << " from " << dirs.size() << " folder(s).</p>\n";
  h << comparison << lab_html;
  h << "<h2>Folders</h2><ul>\n" << links.str() << "</ul>\n</body></html>\n";
  write_file_atomic((out / "index.html").string(), h.str());
  write_json_atomic((out / "summary.json").string(), summary);
  return summary;
}

}  // namespace reposetwin::experiments
