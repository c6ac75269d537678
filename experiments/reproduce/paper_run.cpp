// Running the paper's index item by item (paper_index.hpp says why it is built this way).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <optional>
#include <set>

#include "experiments/calibration/calibrate_campaign.hpp"
#include "experiments/calibration/calibration_file.hpp"
#include "experiments/calibration/campaign_target.hpp"
#include "experiments/io/format.hpp"
#include "experiments/io/hash.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/reproduce/paper_index.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;
namespace {

constexpr const char* kProvenanceFile = "provenance.json";
constexpr const char* kPaperFile = "paper.json";

// OUT/<item>/provenance.json: how the item's results were made. Every attempt (a start of the
// item by `reposetwin paper`) is kept with its code version, so a folder resumed by other code
// says so (made_by_one_version false) instead of hiding it.
nlohmann::json read_provenance(const fs::path& dir, const PaperIndex& index,
                               const PaperItem& item) {
  std::error_code ec;
  nlohmann::json p;
  if (fs::is_regular_file(dir / kProvenanceFile, ec)) {
    try {
      p = read_json_file((dir / kProvenanceFile).string());
    } catch (const std::exception&) {
      p = nlohmann::json();
    }
  }
  if (!p.is_object()) p = nlohmann::json::object();
  p["item"] = item.name;
  p["paper"] = item.paper;
  p["index_file"] = index.file;
  p["file"] = item.file;
  p["file_hash"] = fnv1a_hex(read_file(item.file));
  if (!p.contains("attempts")) p["attempts"] = nlohmann::json::array();
  return p;
}

void write_provenance(const fs::path& dir, nlohmann::json& p) {
  std::set<std::string> versions;
  for (const auto& a : p["attempts"]) versions.insert(a.value("code_version", std::string()));
  p["code_versions"] = versions;
  p["made_by_one_version"] = versions.size() == 1;
  bool clean = true;
  for (const auto& v : versions) clean = clean && !code_commit(v).dirty;
  p["all_clean"] = clean;
  write_json_atomic((dir / kProvenanceFile).string(), p);
}

// When a reused calibration found no mu_r (its target out of reach, or its budget spent), the
// model's best answer is still the usable point whose fitted angle came closest to the target;
// an item declaring `if_not_calibrated = "closest_point"` predicts there, and the record says
// it is not a calibrated value. Nothing when the calibration has no usable point at all.
std::optional<CalibrationRecord> closest_point(CalibrationRecord cal, const std::string& from) {
  const double target = cal.target.angle_deg;
  const FitPoint* best = nullptr;
  for (const FitPoint& q : cal.fit.points)
    if (!best || std::abs(q.fitted_deg - target) < std::abs(best->fitted_deg - target)) best = &q;
  if (!best) return std::nullopt;
  const double mu = best->mu_r;
  cal.not_calibrated = NotCalibrated{
      cal.status, cal.message,
      "the usable point of " + from + " closest to the target " + shortest_text(target) +
          " deg (fitted " + shortest_text(best->fitted_deg) + " deg); not a calibrated value"};
  // A point, not an interval: it stands with none of a calibration's own (its fitted angle).
  cal.mu_r = mu;
  cal.mu_r_lo = cal.mu_r_hi = mu;
  cal.fitted_angle_deg.reset();
  cal.fitted_angle_halfwidth_deg = 0.0;
  return cal;
}

// Runs one item into `dir`; returns its outcome in a word for the provenance record.
std::string run_item(const PaperItem& item, const fs::path& dir, const CaseFn& case_fn,
                     const RunnerSettings& runner) {
  const Campaign c = load_campaign(item.file);
  if (!item.calibrated_by.empty()) {
    // The calibration of an earlier item, taken as it is (predict-only checks it is this one's).
    const fs::path src = dir.parent_path() / item.calibrated_by / "calibration.json";
    std::error_code ec;
    if (!fs::is_regular_file(src, ec))
      return "failed: " + item.calibrated_by + " has no finished calibration (" + src.string() +
             ")";
    CalibrationRecord cal = read_calibration_record(src.string());
    if (!cal.mu_r) {
      const auto closest =
          item.closest_if_not_calibrated ? closest_point(cal, item.calibrated_by) : std::nullopt;
      if (!closest) return "cannot reach";
      cal = *closest;
    }
    if (!fs::is_regular_file(dir / "calibration.json", ec)) {
      cal.copied_from = src.string();
      if (!runner.rank || runner.rank->rank == 0)
        write_json_atomic((dir / "calibration.json").string(), to_json(cal));
    }
    calibrate_and_predict(c, dir.string(), c.calibration->angle, case_fn, runner, true);
    return "finished";
  }
  if (item.kind == PaperItemKind::kCampaign) {
    const CampaignSummary s = run_campaign(c, dir.string(), case_fn, runner);
    return s.failed > 0 ? "failed" : "finished";
  }
  const CalibrateOutcome o =
      calibrate_and_predict(c, dir.string(), c.calibration->angle, case_fn, runner);
  return o.reached ? "finished" : "cannot reach";
}

std::vector<const PaperItem*> selected(const PaperIndex& index,
                                       const std::vector<std::string>& only) {
  std::vector<const PaperItem*> out;
  for (const std::string& name : only) {
    bool found = false;
    for (const PaperItem& i : index.items) found = found || i.name == name;
    if (!found) {
      std::string names;
      for (const PaperItem& i : index.items) names += (names.empty() ? "" : ", ") + i.name;
      throw InputError(index.file + ": no item named '" + name + "' (items: " + names + ")");
    }
  }
  for (const PaperItem& i : index.items)
    if (only.empty() || std::find(only.begin(), only.end(), i.name) != only.end())
      out.push_back(&i);
  return out;
}

}  // namespace

nlohmann::json paper_listing(const PaperIndex& index, const std::string& out_dir) {
  nlohmann::json items = nlohmann::json::array();
  double total = 0.0;
  int runs = 0;
  for (const PaperItem& item : index.items) {
    const ItemPlan plan = plan_item(item);
    const ItemStatus st = item_status(item, (fs::path(out_dir) / item.name).string());
    nlohmann::json j = to_json(item, plan);
    j["status"] = st.state;
    j["status_detail"] = st.detail;
    j["finished_runs"] = st.finished;
    j["results"] = item.name;
    items.push_back(j);
    total += plan.cpu_hours;
    runs += plan.runs;
  }
  return {{"index", index.file},
          {"title", index.title},
          {"budget_cpu_hours", index.budget_cpu_hours},
          {"planned_cpu_hours", total},
          {"planned_runs", runs},
          {"within_budget", total <= index.budget_cpu_hours},
          {"code_version", code_version()},
          {"updated_utc", utc_now()},
          {"items", items}};
}

nlohmann::json run_paper(const PaperIndex& index, const std::string& out_dir, const CaseFn& case_fn,
                         const RunnerSettings& runner, const PaperRunOptions& options) {
  const std::vector<const PaperItem*> todo = selected(index, options.only);
  fs::create_directories(out_dir);
  // Under MPI every rank runs every item (the runs spread over the ranks); rank 0 writes the
  // records.
  const bool writer = !runner.rank || runner.rank->rank == 0;
  int failures = 0;
  for (const PaperItem* item : todo) {
    const fs::path dir = fs::path(out_dir) / item->name;
    const ItemStatus st = item_status(*item, dir.string());
    if (item->kind == PaperItemKind::kDerived) continue;
    if (st.state == "done" || st.state == "cannot reach") {
      if (runner.progress)
        std::cerr << "[paper] " << item->name << ": " << st.state << ", kept (" << st.detail
                  << ")\n";
      continue;
    }
    if (runner.progress) std::cerr << "[paper] " << item->name << ": " << st.state << ", running\n";
    fs::create_directories(dir);
    nlohmann::json prov = read_provenance(dir, index, *item);
    const CodeCommit cc = code_commit(code_version());
    nlohmann::json attempt = {{"code_version", code_version()},
                              {"commit", cc.commit},
                              {"dirty", cc.dirty},
                              {"started_utc", utc_now()}};
    prov["attempts"].push_back(attempt);
    if (writer) write_provenance(dir, prov);
    std::string outcome;
    try {
      outcome = run_item(*item, dir, case_fn, runner);
    } catch (const std::exception& e) {
      outcome = std::string("failed: ") + e.what();
      if (runner.progress) std::cerr << "[paper] " << item->name << ": " << outcome << "\n";
    }
    if (outcome.rfind("failed", 0) == 0) ++failures;
    prov["attempts"].back()["finished_utc"] = utc_now();
    prov["attempts"].back()["outcome"] = outcome;
    if (writer) write_provenance(dir, prov);
  }
  nlohmann::json listing = paper_listing(index, out_dir);
  listing["failed_items_this_call"] = failures;
  if (writer) write_json_atomic((fs::path(out_dir) / kPaperFile).string(), listing);
  return listing;
}

}  // namespace reposetwin::experiments
