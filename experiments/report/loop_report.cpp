// The loop's HTML page: tables from loop.json and gnuplot plots of the residuals against each
// condition, before and after the chosen effects. Reads loop.json only (never simulates).
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "experiments/loop/loop.hpp"
#include "experiments/io/provenance.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::string esc(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '<') o += "&lt;";
    else if (c == '>') o += "&gt;";
    else if (c == '&') o += "&amp;";
    else o += c;
  }
  return o;
}

std::string f3(const json& v) {
  if (!v.is_number()) return "-";
  char b[32];
  std::snprintf(b, sizeof b, "%.3g", v.get<double>());
  return b;
}

// Runs gnuplot on a script; returns whether the PNG was made (a missing gnuplot is not fatal).
bool gnuplot(const fs::path& script, const fs::path& png) {
  const std::string cmd = "gnuplot \"" + script.string() + "\" > /dev/null 2>&1";
  return std::system(cmd.c_str()) == 0 && fs::exists(png);
}

}  // namespace

void write_loop_html(const json& loop, const std::string& out_dir) {
  const fs::path dir = fs::path(out_dir) / "plots";
  fs::create_directories(dir);
  const json& tests = loop.at("tests");
  const json& before = loop.at("baseline").at("residuals");
  const json& after = loop.at("final").at("residuals");
  std::set<std::string> conditions;
  for (const json& t : tests)
    for (const auto& [k, v] : t.at("conditions").items()) conditions.insert(k);
  std::ostringstream plots;
  for (const std::string& c : conditions) {
    std::string safe = c;
    for (char& ch : safe)
      if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
    const fs::path data = dir / ("residual_" + safe + ".dat");
    const fs::path png = dir / ("residual_" + safe + ".png");
    const fs::path gp = dir / ("residual_" + safe + ".gp");
    std::ostringstream d;
    d << "# " << c << " residual_before_deg residual_after_deg sigma_deg role(1=calibrate)\n";
    for (std::size_t i = 0; i < tests.size(); ++i) {
      if (!tests[i]["conditions"].contains(c)) continue;
      d << tests[i]["conditions"][c].get<double>() << " " << before[i]["residual_deg"] << " "
        << after[i]["residual_deg"] << " " << before[i]["sigma_deg"] << " "
        << (tests[i]["role"] == "calibrate" ? 1 : 0) << "\n";
    }
    write_file_atomic(data.string(), d.str());
    std::ostringstream g;
    g << "set terminal pngcairo size 640,420\nset output '" << png.string() << "'\n"
      << "set xlabel '" << c << "' noenhanced\nset ylabel 'measured - predicted angle [deg]'\n"
      << "set key outside top center horizontal\nset grid\nset offsets graph 0.05, graph 0.05, "
         "graph 0.05, graph 0.05\nset xzeroaxis lt -1\n"
      << "plot '" << data.string() << "' u ($1):2:4 w yerrorbars pt 7 lc rgb '#c0392b' t 'before', "
      << "'' u ($1):3:4 w yerrorbars pt 5 lc rgb '#2471a3' t 'after'\n";
    write_file_atomic(gp.string(), g.str());
    if (gnuplot(gp, png))
      plots << "<figure><img src='plots/" << png.filename().string() << "'><figcaption>Residual "
            << "against " << esc(c) << " (error bars: seed noise of one residual)</figcaption>"
            << "</figure>\n";
  }

  std::ostringstream h;
  const json& sum = loop.at("summary");
  h << "<!doctype html><html><head><meta charset='utf-8'><title>ReposeTwin loop</title>"
    << "<style>body{font-family:sans-serif;max-width:1100px;margin:auto}table{border-collapse:"
       "collapse}td,th{border:1px solid #ccc;padding:3px 7px;text-align:right}th{background:#eee}"
       "td.l{text-align:left}figure{display:inline-block;margin:6px}</style></head><body>\n";
  h << "<h1>Closing the loop</h1><p>Data: " << esc(loop["provenance"]["data"].get<std::string>())
    << "<br>Code " << esc(loop["provenance"]["code_version"].get<std::string>()) << ", finished "
    << esc(loop["provenance"]["finished"].get<std::string>()) << "</p>\n";
  h << "<h2>Error before and after</h2><table><tr><th></th><th>before (mu_r only)</th>"
    << "<th>after</th></tr><tr><td class=l>RMSE calibration tests [deg]</td><td>"
    << f3(sum["rmse_calibrate_before_deg"]) << "</td><td>" << f3(sum["rmse_calibrate_after_deg"])
    << "</td></tr><tr><td class=l>RMSE held-out tests [deg]</td><td>"
    << f3(sum["rmse_validate_before_deg"]) << "</td><td>" << f3(sum["rmse_validate_after_deg"])
    << "</td></tr></table>\n";
  h << "<p>Baseline mu_r = " << f3(loop["baseline"]["mu_r"]) << " &plusmn; "
    << f3(loop["baseline"]["mu_r_se"]) << "; seed spread of one pile "
    << f3(loop["baseline"]["seed_sd_deg"]) << " deg.</p>\n";
  h << "<h2>Chosen effects</h2>";
  if (loop["final"]["effects"].empty()) h << "<p>None: no candidate beat the seed noise.</p>";
  else {
    h << "<table><tr><th>effect</th><th>kind</th><th>value</th><th>&plusmn; se</th><th>units"
      << "</th><th>mu_r</th></tr>";
    for (const json& c : loop["final"]["effects"])
      h << "<tr><td class=l>" << esc(c["name"]) << "</td><td class=l>" << esc(c["kind"])
        << "</td><td>" << f3(c["value"]) << "</td><td>" << f3(c["value_se"]) << "</td><td class=l>"
        << esc(c["units"]) << "</td><td>" << f3(c["mu_r"]) << "</td></tr>";
    h << "</table>";
  }
  h << "<p>Rule: " << esc(loop["rule"]["text"].get<std::string>()) << " (min_t "
    << f3(loop["rule"]["min_t"]) << ", margin " << f3(loop["rule"]["loo_margin_deg"])
    << " deg).</p>\n";
  for (const json& it : loop["iterations"]) {
    h << "<h3>Iteration " << it["iteration"] << " (mu_r " << f3(it["mu_r"]) << "; mu_r-only LOO "
      << f3(it["null"]["loo_rmse_mu_only_deg"]) << " deg)</h3><table><tr><th>candidate</th>"
      << "<th>c</th><th>se</th><th>|c|/se</th><th>LOO RMSE</th><th>LOO gain</th>"
      << "<th>explained</th><th>accepted</th></tr>";
    for (const json& c : it["candidates"])
      h << "<tr><td class=l>" << esc(c["name"]) << "</td><td>" << f3(c["coef"]) << "</td><td>"
        << f3(c["coef_se"]) << "</td><td>" << f3(c["t"]) << "</td><td>" << f3(c["loo_rmse_deg"])
        << "</td><td>" << f3(c["loo_gain_deg"]) << "</td><td>" << f3(c["explained"])
        << "</td><td>" << (c["accepted"].get<bool>() ? "yes" : "no") << "</td></tr>";
    h << "</table>\n";
    if (it.contains("stopped")) h << "<p>Stopped: " << esc(it["stopped"]) << ".</p>\n";
  }
  // Pours that jammed in the baseline (repeated with new seeds; a lab reports none).
  std::string jams;
  for (const json& c : loop["baseline"].value("curves", json::array())) {
    int n = 0;
    for (const json& x : c["clogged_pours"]) n += x.get<int>();
    if (n > 0) jams += "<li>" + esc(c["id"]) + ": " + std::to_string(n) + "</li>";
  }
  if (!jams.empty())
    h << "<p>Baseline pours that formed no pile and were repeated with new seeds (the lab "
         "reports none):</p><ul>"
      << jams << "</ul>\n";
  if (!loop["unavailable_candidates"].empty()) {
    h << "<p>Unavailable candidates:</p><ul>";
    for (const json& u : loop["unavailable_candidates"])
      h << "<li>" << esc(u["name"]) << ": " << esc(u["why"]) << "</li>";
    h << "</ul>";
  }
  h << "<h2>Residuals</h2>" << plots.str();
  h << "<table><tr><th>test</th><th>role</th><th>measured</th><th>before</th><th>after</th>"
    << "<th>residual before</th><th>residual after</th><th>sigma</th></tr>";
  for (std::size_t i = 0; i < tests.size(); ++i)
    h << "<tr><td class=l>" << esc(tests[i]["id"]) << "</td><td class=l>" << esc(tests[i]["role"])
      << "</td><td>" << f3(tests[i]["angle_deg"]) << "</td><td>" << f3(before[i]["predicted_deg"])
      << "</td><td>" << f3(after[i]["predicted_deg"]) << "</td><td>"
      << f3(before[i]["residual_deg"]) << "</td><td>" << f3(after[i]["residual_deg"])
      << "</td><td>" << f3(before[i]["sigma_deg"]) << "</td></tr>";
  h << "</table></body></html>\n";
  write_file_atomic((fs::path(out_dir) / "index.html").string(), h.str());
}

}  // namespace reposetwin::experiments
