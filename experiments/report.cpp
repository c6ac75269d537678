#include "experiments/report.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "experiments/provenance.hpp"
#include "experiments/toml_reader.hpp"
#include "vision/measure.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

struct Stats {
  int n = 0;
  double mean = 0.0, sd = 0.0;
};

Stats stats(const std::vector<double>& v) {
  Stats s;
  s.n = static_cast<int>(v.size());
  if (v.empty()) return s;
  for (double x : v) s.mean += x;
  s.mean /= s.n;
  if (s.n > 1) {
    for (double x : v) s.sd += (x - s.mean) * (x - s.mean);
    s.sd = std::sqrt(s.sd / (s.n - 1));
  }
  return s;
}

std::string html_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '&': out += "&amp;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
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
  json overrides;
  std::vector<double> image_deg, particle_deg, slice_deg;
  std::vector<std::string> stops;
  std::vector<std::string> run_dirs;  // relative to the report's source folder
  json provenance;
};

}  // namespace

json build_report(const std::string& dir_in, const ReportSettings& settings) {
  const fs::path dir(dir_in);
  std::map<std::string, CaseRows> cases;
  std::vector<std::string> order;
  json calibration;
  std::string title = settings.title;

  auto add_result = [&](const std::string& case_name, const json& overrides, const json& r,
                        const std::string& run_dir) {
    if (!cases.count(case_name)) {
      order.push_back(case_name);
      cases[case_name].name = case_name;
      cases[case_name].overrides = overrides;
    }
    CaseRows& c = cases[case_name];
    c.stops.push_back(r.at("stop").at("reason").get<std::string>());
    c.run_dirs.push_back(run_dir);
    c.provenance = r.at("provenance");
    const json& pile = r.at("pile");
    c.particle_deg.push_back(pile.value("theta_hd_deg", 0.0));
    c.slice_deg.push_back(pile.value("slice_angle_mean_deg", 0.0));
    if (r.contains("image")) c.image_deg.push_back(r["image"].at("theta_deg").get<double>());
  };

  if (fs::exists(dir / "result.json") && !fs::exists(dir / "campaign.json")) {  // one run
    const json r = json::parse(read_file((dir / "result.json").string()));
    if (!r.contains("pile")) throw InputError(dir_in + "/result.json: not a run result");
    json rr = r;
    if (fs::exists(dir / "images" / "measurement.json")) {
      const json m = json::parse(read_file((dir / "images" / "measurement.json").string()));
      rr["image"] = {{"theta_deg", m.at("theta_deg")}};
    }
    add_result(r["provenance"].value("scene_name", "run"), json::object(), rr, ".");
    if (title.empty()) title = r["provenance"].value("scene_name", "run");
  }
  // Campaign or calibration folders: every finished run below cases/.
  if (fs::exists(dir / "cases")) {
    std::vector<fs::path> results;
    for (const auto& e : fs::recursive_directory_iterator(dir / "cases"))
      if (e.path().filename() == "result.json" && e.path().parent_path().filename().string().rfind("seed_", 0) == 0)
        results.push_back(e.path());
    std::sort(results.begin(), results.end());
    for (const fs::path& p : results) {
      const json meta = json::parse(read_file(p.string()));
      if (!meta.contains("result")) continue;
      const json& spec = meta.at("spec");
      add_result(spec.at("case"), spec.value("overrides", json::object()), meta.at("result"),
                 fs::relative(p.parent_path() / "run", dir).string());
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
    const Stats im = stats(c.image_deg), pa = stats(c.particle_deg), sl = stats(c.slice_deg);
    summary["cases"].push_back({{"case", name},
                                {"runs", c.run_dirs.size()},
                                {"image_theta_mean_deg", im.mean},
                                {"image_theta_sd_deg", im.sd},
                                {"particle_theta_mean_deg", pa.mean},
                                {"particle_theta_sd_deg", pa.sd},
                                {"slice_angle_mean_deg", sl.mean},
                                {"overrides", c.overrides}});
    data << k++ << " " << im.mean << " " << im.sd << " " << pa.mean << " " << pa.sd << " \""
         << name << "\"\n";
  }
  bool plotted = false;
  if (!order.empty()) {
    write_file_atomic((out / "angles.dat").string(), data.str());
    plotted = gnuplot((out / "angles.gp").string(),
                      "set terminal pngcairo size 900,500\nset output '" +
                          (out / "angles.png").string() +
                          "'\nset ylabel 'angle of repose [deg]'\nset xtics rotate by -30\n"
                          "set key top left\nset offsets 0.5,0.5,2,2\nplot '" +
                          (out / "angles.dat").string() +
                          "' using 1:2:3:xtic(6) with yerrorbars pt 7 title 'image atan(2H/D) "
                          "(vision on renders)', '' using ($1+0.1):4:5 with yerrorbars pt 5 "
                          "title 'particles atan(2H/D)'\n");
  }
  bool calib_plot = false;
  if (!calibration.is_null() && calibration.contains("observations")) {
    std::ostringstream obs;
    for (const json& o : calibration["observations"])
      obs << o.value("mu_r", 0.0) << " " << o.value("angle_deg", 0.0) << "\n";
    write_file_atomic((out / "calibration.dat").string(), obs.str());
    std::string target = calibration.contains("target") ? fmt(calibration["target"].value("angle_deg", 0.0)) : "0";
    calib_plot = gnuplot((out / "calibration.gp").string(),
                         "set terminal pngcairo size 700,500\nset output '" +
                             (out / "calibration.png").string() +
                             "'\nset xlabel 'mu_r'\nset ylabel 'angle [deg]'\nset key top left\n"
                             "plot '" + (out / "calibration.dat").string() +
                             "' using 1:2 with points pt 7 title 'runs (one per seed)', " + target +
                             " with lines dt 2 title 'target'\n");
  }
  // The lab photo, measured by the same code as the renders.
  std::string lab_html;
  if (!settings.lab_photo.empty()) {
    const cv::Mat photo = cv::imread(settings.lab_photo, cv::IMREAD_COLOR);
    if (photo.empty()) throw InputError(settings.lab_photo + ": not an image");
    vision::ScaleSpec scale;
    if (settings.lab_mm_per_px > 0) scale.mm_per_px = settings.lab_mm_per_px;
    const vision::SideMeasurement m = vision::measure_side(photo, scale, {}, settings.lab_photo);
    cv::imwrite((out / "lab_photo.measured.png").string(), vision::draw_side_overlay(photo, m));
    lab_html = "<figure><img src='lab_photo.measured.png' width='640'><figcaption>lab photo: "
               "theta = " + fmt(m.theta_deg) + " &plusmn; " + fmt(m.sigma_theta_deg) +
               " deg</figcaption></figure>";
    summary["lab_photo"] = vision::to_json(m);
  }

  std::ostringstream h;
  h << "<!doctype html><html><head><meta charset='utf-8'><title>" << html_escape(title)
    << "</title><style>body{font-family:sans-serif;max-width:1100px;margin:auto}"
       "table{border-collapse:collapse}td,th{border:1px solid #aaa;padding:3px 6px;font-size:13px}"
       "figure{display:inline-block;margin:4px}</style></head><body>\n";
  h << "<h1>ReposeTwin report: " << html_escape(title) << "</h1>\n<p>Built " << utc_now()
    << " by " << code_version() << " from <code>" << html_escape(fs::absolute(dir).string())
    << "</code>.</p>\n";
  if (plotted) h << "<h2>Angles per case</h2><img src='angles.png'>\n";
  else if (!order.empty()) h << "<p>(gnuplot not available: no plot)</p>\n";
  if (!order.empty()) {
    h << "<h2>Cases</h2><table><tr><th>case</th><th>inputs (overrides)</th><th>runs</th>"
         "<th>image angle [deg] mean &plusmn; sd</th><th>particle atan(2H/D) [deg]</th>"
         "<th>slice (protractor) [deg]</th><th>stop reasons</th><th>provenance</th>"
         "<th>files</th></tr>\n";
    for (const std::string& name : order) {
      const CaseRows& c = cases[name];
      const Stats im = stats(c.image_deg), pa = stats(c.particle_deg), sl = stats(c.slice_deg);
      std::map<std::string, int> stops;
      for (const auto& s : c.stops) ++stops[s];
      std::string stop_text;
      for (const auto& [s, n] : stops) stop_text += s + " x" + std::to_string(n) + " ";
      const json& p = c.provenance;
      std::string files;
      for (const auto& d : c.run_dirs)
        files += "<a href='../" + d + "/series.pvd'>pvd</a> ";
      h << "<tr><td>" << html_escape(name) << "</td><td><code>" << html_escape(c.overrides.dump())
        << "</code></td><td>" << c.run_dirs.size() << "</td><td>"
        << (im.n ? fmt(im.mean) + " &plusmn; " + fmt(im.sd) : "-") << "</td><td>"
        << fmt(pa.mean) + " &plusmn; " + fmt(pa.sd) << "</td><td>" << fmt(sl.mean) << "</td><td>"
        << html_escape(stop_text) << "</td><td>dt " << p.value("time_step_s", 0.0) << " s, E "
        << p.value("softened_youngs_modulus_pa", json(0.0)).dump() << " Pa, "
        << html_escape(p.value("code_version", std::string("?"))) << "</td><td>" << files
        << "</td></tr>\n";
    }
    h << "</table>\n<h2>Renders with measurement overlays</h2>\n" << lab_html << "\n";
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
  h << "</body></html>\n";
  write_file_atomic((out / "index.html").string(), h.str());
  write_json_atomic((out / "summary.json").string(), summary);
  return summary;
}

}  // namespace reposetwin::experiments
