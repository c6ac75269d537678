#include "experiments/loop/sheet_campaign.hpp"

#include <filesystem>
#include <map>
#include <sstream>

#include "experiments/calibration/campaign_target.hpp"
#include "experiments/io/format.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/overrides.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;
namespace {

std::string absolute(const std::string& path) {
  return fs::absolute(fs::path(path)).lexically_normal().string();
}

// A TOML string literal of `text`, quoted and escaped.
std::string quote(const std::string& text) { return string_override("k", text).value; }

// The sheet's one calibration row; InputError when there is none or more than one.
const LabTest& calibration_row(const LabData& data) {
  const LabTest* found = nullptr;
  for (const LabTest& t : data.tests) {
    if (t.role != Role::kCalibrate) continue;
    if (found)
      throw InputError(data.file + " line " + std::to_string(t.line) + " (test " + t.id +
                       "), column role: \"calibrate\" again: the calibration is made on one test "
                       "(line " + std::to_string(found->line) + ", test " + found->id +
                       "); mark the others \"validate\" to predict them");
    found = &t;
  }
  if (!found)
    throw InputError(data.file + ": no row has role \"calibrate\" (the test to calibrate on)");
  return *found;
}

// A prediction row must set every condition the calibration row sets (see the design note).
void check_conditions(const LabData& data, const LabTest& cal) {
  for (const LabTest& t : data.tests) {
    if (&t == &cal) continue;
    for (std::size_t i = 0; i < cal.overrides.size(); ++i) {
      bool set = false;
      for (const auto& [k, v] : t.overrides) set = set || k == cal.overrides[i].first;
      if (!set)
        throw InputError(data.file + " line " + std::to_string(t.line) + " (test " + t.id +
                         "), column " + cal.override_columns[i] +
                         ": \"\" is empty, but the calibration test " + cal.id + " (line " +
                         std::to_string(cal.line) + ") sets it to " + cal.overrides[i].second +
                         ": fill it (a test does not take another test's conditions)");
    }
  }
}

// The overrides of a test, as an inline TOML table.
std::string overrides_table(const std::vector<std::pair<std::string, std::string>>& ov) {
  std::string s = "{ ";
  for (std::size_t i = 0; i < ov.size(); ++i)
    s += (i ? ", " : "") + quote(ov[i].first) + " = " + ov[i].second;
  return s + " }";
}

// The calibration target: the row's photos and their scale, or its typed angle.
std::string target_lines(const LabTest& cal) {
  std::ostringstream t;
  if (cal.photos.empty()) {
    t << "target_deg = " << toml_float(cal.angle_deg, 17) << "\n";
    return t.str();
  }
  t << "target_photos = [";
  for (std::size_t i = 0; i < cal.photos.size(); ++i) t << (i ? ", " : "") << quote(cal.photos[i]);
  t << "]\n";
  if (!cal.photo_scale.camera_json.empty())
    t << "target_photo_camera = " << quote(absolute(cal.photo_scale.camera_json)) << "\n";
  if (cal.photo_scale.mm_per_px)
    t << "target_mm_per_px = " << toml_float(*cal.photo_scale.mm_per_px, 17) << "\n";
  return t.str();
}

std::string campaign_text(const SheetCalibrationRequest& r, const LabData& data,
                          const LabTest& cal, const std::string& name,
                          const std::vector<std::pair<std::string, std::string>>& common) {
  std::vector<std::pair<std::string, std::string>> top = common;
  top.insert(top.end(), cal.overrides.begin(), cal.overrides.end());
  std::ostringstream t;
  t << "# Made by `reposetwin calibrate --tests --sieve --scene` from the lab's sheets; rerun it\n"
    << "# as `reposetwin calibrate` on this file. Paths are absolute.\n"
    << "name = " << quote(name) << "\n"
    << "description = "
    << quote("calibration on test " + cal.id + " of the test sheet " + data.file +
             (r.sieve_sheet.empty() ? "" : ", sieve sheet " + absolute(r.sieve_sheet)))
    << "\n"
    << "scene = " << quote(cal.scene_path) << "\n";
  if (!top.empty()) t << "overrides = " << overrides_table(top) << "\n";
  t << "\n[calibration]\n"
    << target_lines(cal) << "mu_r_range = [" << toml_float(r.mu_r_lo, 17) << ", "
    << toml_float(r.mu_r_hi, 17) << "]\n"
    << "angle = " << quote(angle_measure_name(r.angle)) << "\n"
    << "method = \"bracket\"\n"
    << "ends_first = true\n"
    << "seeds_per_point = 2\n"
    << "max_simulations = 8\n";
  for (const LabTest& p : data.tests) {
    if (&p == &cal) continue;
    std::vector<std::pair<std::string, std::string>> own = common;
    own.insert(own.end(), p.overrides.begin(), p.overrides.end());
    t << "\n[[predict]]\n"
      << "name = " << quote(p.id) << "\n"
      << "scene = " << quote(p.scene_path) << "\n"
      << "measured_deg = " << toml_float(p.angle_deg, 17) << "\n";
    if (!own.empty()) t << "overrides = " << overrides_table(own) << "\n";
  }
  return t.str();
}

}  // namespace

SheetCampaign sheet_campaign(const SheetCalibrationRequest& r) {
  if (!fs::is_regular_file(r.scene))
    throw InputError("--scene \"" + r.scene + "\": the base scene file does not exist");
  if (!fs::is_regular_file(r.tests_csv))
    throw InputError("--tests \"" + r.tests_csv + "\": the test sheet does not exist");
  if (!r.sieve_sheet.empty() && !fs::is_regular_file(r.sieve_sheet))
    throw InputError("--sieve \"" + r.sieve_sheet + "\": the sieve sheet does not exist");
  LabSheetForm form;
  form.base_scene = absolute(r.scene);
  form.role_required = false;
  if (!r.sieve_sheet.empty()) {
    form.common.emplace_back("sample.psd_file", quote(absolute(r.sieve_sheet)));
    form.common_origin = "--sieve " + r.sieve_sheet;
  }
  SheetCampaign out;
  out.tests = read_lab_csv(r.tests_csv, form);
  const LabTest& cal = calibration_row(out.tests);
  check_conditions(out.tests, cal);
  const std::string name = sanitize_name(fs::path(out.tests.file).stem().string());
  out.text = campaign_text(r, out.tests, cal, name, form.common);
  out.campaign = parse_campaign(out.text, r.campaign_file);
  if (out.campaign.calibration)
    measure_target_photos(*out.campaign.calibration, out.campaign.file);
  return out;
}

}  // namespace reposetwin::experiments
