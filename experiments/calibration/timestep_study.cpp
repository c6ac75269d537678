#include "experiments/calibration/campaign_target.hpp"
#include "experiments/calibration/timestep_study.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>

#include "experiments/campaign/case_runner.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/io/input_error.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;
using nlohmann::json;

double largest_stable_dt(const std::vector<std::pair<double, double>>& dt_angle,
                         double tolerance_deg) {
  if (dt_angle.empty()) throw InputError("time-step study: no points");
  std::vector<std::pair<double, double>> p = dt_angle;
  std::sort(p.begin(), p.end());
  const double reference = p.front().second;
  double stable = p.front().first;
  for (const auto& [dt, angle] : p) {
    if (std::abs(angle - reference) > tolerance_deg) break;
    stable = dt;
  }
  return stable;
}

Campaign timestep_campaign(const std::string& scene_path, const std::string& out_dir,
                           const TimestepStudySettings& s, std::string* text) {
  if (s.rayleigh_fractions.empty()) throw InputError("timestep: the list of fractions is empty");
  for (double f : s.rayleigh_fractions)
    if (!(f > 0)) throw InputError("timestep: fraction " + std::to_string(f) + " must be positive");
  if (!fs::exists(scene_path)) throw InputError(scene_path + ": scene file does not exist");
  // The study as a campaign file (kept in the folder, so the study is resumable and reportable).
  std::ostringstream c;
  c << "name = \"timestep_study\"\npaper = \"Fig. 5\"\nscene = \""
    << fs::absolute(scene_path).string() << "\"\nseeds = [";
  for (std::size_t i = 0; i < s.seeds.size(); ++i) c << (i ? ", " : "") << s.seeds[i];
  c << "]\n[sweep]\nkey = \"numerics.rayleigh_fraction\"\nname = \"dt_fraction\"\nvalues = [";
  for (std::size_t i = 0; i < s.rayleigh_fractions.size(); ++i)
    c << (i ? ", " : "") << s.rayleigh_fractions[i];
  c << "]\n";
  if (text) *text = c.str();
  return parse_campaign(c.str(), (fs::path(out_dir) / "timestep_campaign.toml").string());
}

json run_timestep_study(const std::string& scene_path, const std::string& out_dir,
                        const TimestepStudySettings& s, CampaignSummary* summary) {
  std::string text;
  (void)timestep_campaign(scene_path, out_dir, s, &text);
  fs::create_directories(out_dir);
  const std::string campaign_file = (fs::path(out_dir) / "timestep_campaign.toml").string();
  write_file_atomic(campaign_file, text);
  const Campaign campaign = load_campaign(campaign_file);
  CaseRunSettings cs;
  cs.images = s.images;
  const CampaignSummary ran = run_campaign(campaign, out_dir, pile_case_fn(cs), s.runner);
  if (summary) *summary = ran;

  // A run without a headline (not settled, jammed, ...) has no angle: it is counted by its
  // reason beside the point, never averaged in.
  std::map<std::string, std::vector<double>> angles;
  std::map<std::string, std::map<std::string, int>> without_angle;
  std::map<std::string, double> dt_of;
  for (const CaseSpec& run : campaign.runs) {
    const auto r = read_run_result(out_dir, run);
    if (!r) continue;
    dt_of[run.case_name] = r->at("result").at("provenance").at("time_step_s");
    const PileStatus outcome = case_outcome(r->at("result"));
    if (outcome != PileStatus::kPile) {
      ++without_angle[run.case_name][pile_status_word(outcome)];
      continue;
    }
    angles[run.case_name].push_back(
        case_angle_deg(*r, s.images ? AngleMeasure::kImage : AngleMeasure::kParticles));
  }
  json points = json::array();
  std::vector<std::pair<double, double>> dt_angle;
  for (const auto& [name, a] : angles) {
    double mean = 0, sd = 0;
    for (double x : a) mean += x;
    mean /= a.size();
    for (double x : a) sd += (x - mean) * (x - mean);
    sd = a.size() > 1 ? std::sqrt(sd / (a.size() - 1)) : 0.0;
    points.push_back({{"case", name},
                      {"time_step_s", dt_of[name]},
                      {"angle_mean_deg", mean},
                      {"angle_sd_deg", sd},
                      {"runs", a.size()},
                      {"without_angle", without_angle[name]}});
    dt_angle.emplace_back(dt_of[name], mean);
  }
  std::sort(points.begin(), points.end(),
            [](const json& a, const json& b) { return a["time_step_s"] < b["time_step_s"]; });
  json out = {{"scene", scene_path},
              {"angle", s.images ? "vision on renders" : "particle positions atan(2H/D)"},
              {"tolerance_deg", s.tolerance_deg},
              {"points", points},
              {"code_version", code_version()},
              {"created_utc", utc_now()}};
  if (!dt_angle.empty()) out["largest_stable_time_step_s"] = largest_stable_dt(dt_angle, s.tolerance_deg);
  write_json_atomic((fs::path(out_dir) / "timestep_study.json").string(), out);
  return out;
}

}  // namespace reposetwin::experiments
