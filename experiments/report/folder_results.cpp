#include "experiments/report/folder_results.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <utility>

#include "experiments/calibration/calibration.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/report/format.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/pile/headline.hpp"
#include "experiments/pile/pile_record.hpp"
#include "experiments/pile/run_state.hpp"

namespace reposetwin::experiments::report {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// Adds one run's result to its case (made on first sight).
void add_result(FolderResults& f, const std::string& case_name, const json& overrides,
                const json& r, const std::string& run_dir, const std::string& record,
                const std::string& image_dir, const std::string& scene = "") {
  auto it = std::find_if(f.cases.begin(), f.cases.end(),
                         [&](const CaseRows& c) { return c.name == case_name; });
  if (it == f.cases.end()) {
    CaseRows made;
    made.name = case_name;
    made.scene = scene;
    made.overrides = overrides;
    f.cases.push_back(std::move(made));
    it = f.cases.end() - 1;
  }
  CaseRows& c = *it;
  const std::string reason = r.at("stop").at("reason").get<std::string>();
  c.stops.push_back(reason);
  c.run_dirs.push_back(run_dir);
  c.records.push_back(record);
  c.image_dirs.push_back(image_dir);
  c.provenance = r.at("provenance");
  // A run without a headline (a physics stop, a jam, a time limit before the pile settled, no
  // pile: pile/headline.hpp) is listed with its reason, and its angles never enter a mean or a
  // count of results.
  const json& pile = r.at("pile");
  if (const auto none = no_headline(stop_from_json(r.at("stop")), pile_measure_from_json(pile))) {
    ++c.without_pile[no_headline_word(none->reason)];
    return;
  }
  c.particle_deg.push_back(pile.value("theta_hd_deg", 0.0));
  c.slice_deg.push_back(pile.value("slice_angle_mean_deg", 0.0));
  if (r.contains("image")) {
    c.image_deg.push_back(r["image"].at("theta_deg").get<double>());
    if (r["image"].contains("flank_deg"))
      c.flank_deg.push_back(r["image"]["flank_deg"].get<double>());
  }
}

// Why a single run folder is incomplete, from its stage record; "" when it is complete.
std::string incomplete_reason(const fs::path& dir) {
  try {
    const std::optional<RunState> s = read_run_state(dir.string());
    if (!s)
      return "no stage record (run_state.json): the run was stopped before its result was "
             "recorded as simulated, or was made by a version that kept no stage record";
    if (s->complete()) return "";
    return "stopped after the stage " + std::string(run_stage_name(s->stage)) +
           "; missing: " + s->missing() + (s->note.empty() ? "" : " (" + s->note + ")");
  } catch (const RunStateError& e) {
    return e.what();
  }
}

// A single run folder: result.json, with the image measurement beside it when there is one.
// Only a complete stage record vouches for them: an incomplete run is listed by that reason,
// with no angle, whatever its files hold.
void read_single_run(FolderResults& f) {
  f.incomplete = incomplete_reason(f.dir);
  if (!f.incomplete.empty()) {
    json prov = json::object();
    std::string name = f.dir.filename().string();
    if (fs::is_regular_file(f.dir / "result.json")) {
      try {
        prov = read_json(f.dir / "result.json").at("provenance");
        name = prov.value("scene_name", name);
      } catch (const std::exception&) {  // a result cut short: the folder is incomplete anyway
      }
    }
    CaseRows c;
    c.name = name;
    c.stops = {"incomplete"};
    c.run_dirs = {"."};
    c.records = {"result.json"};
    c.image_dirs = {"images"};
    c.without_pile["incomplete"] = 1;
    c.provenance = prov;
    f.cases.push_back(std::move(c));
    if (f.title.empty()) f.title = name;
    return;
  }
  const json r = read_json(f.dir / "result.json");
  if (!r.contains("pile")) throw InputError(f.dir.string() + "/result.json: not a run result");
  json rr = r;
  if (fs::exists(f.dir / "images" / "measurement.json")) {
    const json m = read_json(f.dir / "images" / "measurement.json");
    rr["image"] = {{"theta_deg", m.at("theta_deg")}, {"flank_deg", m.at("flank_deg")}};
  }
  const std::string name = r["provenance"].value("scene_name", "run");
  add_result(f, name, json::object(), rr, ".", "result.json", "images");
  if (f.title.empty()) f.title = name;
}

// A campaign or calibration folder: every finished run below cases/, in path order.
void read_campaign_runs(FolderResults& f) {
  std::vector<fs::path> results;
  for (const auto& e : fs::recursive_directory_iterator(f.dir / "cases"))
    if (e.path().filename() == "result.json" &&
        e.path().parent_path().filename().string().rfind("seed_", 0) == 0)
      results.push_back(e.path());
  std::sort(results.begin(), results.end());
  for (const fs::path& p : results) {
    const json meta = read_json(p);
    if (!meta.contains("result")) continue;
    const json& spec = meta.at("spec");
    const json& res = meta.at("result");
    // The run and its photographs are where the case's record says (the pile service's store).
    const fs::path run = p.parent_path() / res.value("run_dir", std::string("run"));
    const bool named = res.contains("image") && res["image"].contains("images");
    const fs::path images = named ? p.parent_path() / res["image"]["images"].get<std::string>()
                                  : run / "images";
    const auto rel = [&](const fs::path& x) {
      return fs::relative(x.lexically_normal(), f.dir).string();
    };
    add_result(f, spec.at("case"), spec.value("overrides", json::object()), res, rel(run),
               rel(p), rel(images), spec.value("scene", std::string()));
  }
  if (fs::exists(f.dir / "campaign.json") && f.title.empty())
    f.title = read_json(f.dir / "campaign.json").value("campaign", "");
}

}  // namespace

void refuse_part_folder(const fs::path& dir) {
  std::error_code ec;
  const fs::path d = fs::absolute(dir, ec).lexically_normal();
  const fs::path d_clean = d.filename().empty() ? d.parent_path() : d;
  const auto is_file = [&](const fs::path& p) { return fs::is_regular_file(p, ec); };
  std::string store_entry;
  if (d_clean.filename() == "run" && is_file(d_clean.parent_path() / "request.json"))
    store_entry = d_clean.parent_path().string();
  else if (is_file(d_clean / "request.json") && fs::is_directory(d_clean / "run", ec))
    store_entry = d_clean.string();
  if (!store_entry.empty())
    throw InputError(dir.string() + ": a pile of a pile store (entry " + store_entry +
                     "), not a folder of `reposetwin run`: its photographs, headline and stage "
                     "record are kept by the campaign, calibration or loop that asked for it; "
                     "report that folder instead");
  const std::string leaf = d_clean.filename().string();
  const fs::path cases = d_clean.parent_path().parent_path();
  if (leaf.rfind("seed_", 0) != 0 || cases.filename() != "cases" ||
      !is_file(d_clean / "result.json"))
    return;
  nlohmann::json record;
  try {
    record = read_json_file((d_clean / "result.json").string());
  } catch (const std::exception&) {
    return;  // not a case record; the folder's own reader names what is wrong with it
  }
  if (record.is_object() && record.contains("spec"))
    throw InputError(dir.string() + ": one seed's record of the case '" +
                     d_clean.parent_path().filename().string() + "' of the campaign in " +
                     cases.parent_path().string() +
                     ", not a run folder; report the campaign: "
                     "reposetwin report " +
                     cases.parent_path().string());
}

bool is_calibration_dir(const fs::path& d) { return fs::is_regular_file(d / "calibration.json"); }

bool is_run_dir(const fs::path& d) {
  std::error_code ec;
  if (fs::exists(d / "campaign.json", ec)) return false;
  for (const char* f : {"result.json", kRunStateFile, "checkpoint.bin", "controller.json"})
    if (fs::exists(d / f, ec)) return true;
  return false;
}

bool holds_results(const fs::path& d) {
  return is_run_dir(d) || fs::is_directory(d / "cases") ||
         is_calibration_dir(d) || fs::is_regular_file(d / "campaign.json");
}

json read_json(const fs::path& p) { return read_json_file(p.string()); }

FolderResults read_folder_results(const std::string& dir, const std::string& title) {
  refuse_part_folder(dir);
  FolderResults f;
  f.dir = dir;
  f.title = title;
  if (is_run_dir(f.dir)) read_single_run(f);
  if (fs::exists(f.dir / "cases")) read_campaign_runs(f);
  if (fs::exists(f.dir / "calibration.json"))
    f.calibration = read_calibration_record((f.dir / "calibration.json").string());
  if (fs::is_regular_file(f.dir / "predictions.json"))
    f.predictions = read_json(f.dir / "predictions.json");
  if (f.cases.empty() && !f.calibration)
    throw InputError(dir + ": no run, campaign or calibration results to report");
  if (f.title.empty()) f.title = f.dir.filename().string();
  return f;
}

CaseStats case_stats(const CaseRows& c) {
  return {sample_stats(c.image_deg), sample_stats(c.particle_deg), sample_stats(c.slice_deg),
          sample_stats(c.flank_deg)};
}

bool same_test_as_calibration(const FolderResults& f, const CaseRows& c) {
  const std::vector<std::string> keys =
      f.calibration ? f.calibration->keys : std::vector<std::string>{};
  const auto conditions = [&keys](const json& overrides) {
    json o = overrides.is_object() ? overrides : json::object();
    for (const std::string& k : keys) o.erase(k);
    return o;
  };
  for (const CaseRows& r : f.cases)
    if (r.name.rfind("calib_", 0) == 0) return conditions(r.overrides) == conditions(c.overrides);
  return true;
}

std::string angles_plot_data(const FolderResults& f) {
  std::vector<std::pair<std::string, json>> named;
  for (const CaseRows& c : f.cases) named.emplace_back(c.name, c.overrides);
  const std::vector<std::string> labels = case_labels(named);
  const auto mean = [](const SampleStats& s) { return s.n ? s.mean : NAN; };
  const auto sd = [](const SampleStats& s) { return s.n ? s.sd : NAN; };
  std::ostringstream data;
  for (std::size_t k = 0; k < f.cases.size(); ++k) {
    const CaseRows& c = f.cases[k];
    const CaseStats s = case_stats(c);
    std::string label = labels[k];
    if (s.image.n + s.particle.n + s.flank.n == 0) {
      std::string why;
      for (const auto& [reason, n] : c.without_pile)
        why += (why.empty() ? "" : ", ") + std::to_string(n) + " " + reason;
      label += " (no angle" + (why.empty() ? std::string() : ": " + why) + ")";
    }
    // A label is one quoted gnuplot string.
    std::erase(label, '"');
    data << k << " " << mean(s.image) << " " << sd(s.image) << " " << mean(s.particle) << " "
         << sd(s.particle) << " \"" << label << "\" " << mean(s.flank) << " " << sd(s.flank)
         << "\n";
  }
  return data.str();
}

json case_summary(const FolderResults& f) {
  json summary = {{"title", f.title}, {"cases", json::array()}};
  for (const CaseRows& c : f.cases) {
    const CaseStats s = case_stats(c);
    int without = 0;
    for (const auto& [reason, n] : c.without_pile) without += n;
    summary["cases"].push_back({{"case", c.name},
                                {"runs", c.run_dirs.size()},
                                {"piles", static_cast<int>(c.run_dirs.size()) - without},
                                {"without_pile", c.without_pile},
                                {"image_runs", s.image.n},
                                {"image_theta_mean_deg", s.image.mean},
                                {"image_theta_sd_deg", s.image.sd},
                                {"image_flank_mean_deg", s.flank.n ? json(s.flank.mean) : json()},
                                {"image_flank_sd_deg", s.flank.n ? json(s.flank.sd) : json()},
                                {"particle_theta_mean_deg", s.particle.mean},
                                {"particle_theta_sd_deg", s.particle.sd},
                                {"slice_angle_mean_deg", s.slice.mean},
                                {"overrides", c.overrides}});
  }
  return summary;
}

}  // namespace reposetwin::experiments::report
