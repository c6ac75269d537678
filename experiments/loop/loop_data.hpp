// Measured lab data for the loop (reposetwin loop): one CSV row per lab pile test.
//
// Design note. A lab test is the twin's scene plus a few conditions, so every condition column is
// turned into a dotted scene override (the same mechanism as `--set` and campaigns), applied to
// the row's base scene, and the scene is parsed at load time: a test the engine cannot build
// fails here, naming the file, the row and the column, not an hour later inside a worker. Named
// columns cover the conditions a lab sheet records; `set:KEY` carries any other scene key. The
// measured values are either numbers typed from the lab sheet or the photographs themselves,
// which the loop measures with vision/ exactly as it measures the twin's renders (a photo needs
// a scale: its camera sidecar JSON, or mm_per_px, or the render convention's scale marker in the
// image). The photos' measurement replaces typed H, D and angle (the like-for-like value), but
// not a typed crest width: vision reads the crest on the photos only where the sheet gives none,
// since a lab that typed one measured its flat top another way (a calliper, a top photo) and
// says so. Full format: docs/loop.md.
#pragma once

#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "camera/camera.hpp"
#include "experiments/photos/lab_photos.hpp"

namespace reposetwin::experiments {

/// A lab test's part in the loop: mu_r is fitted on the calibration tests, and the validation
/// tests are held out, predicted.
enum class Role { kCalibrate, kValidate };
/// "calibrate" or "validate", as the CSV and loop.json write it.
const char* role_name(Role role);
/// The role `text` names; std::nullopt for any other text.
std::optional<Role> parse_role(const std::string& text);

/// One measured lab test.
struct LabTest {
  int line = 0;             // line of the CSV file (1-based), for messages
  std::string id;           // unique, filesystem-safe
  Role role = Role::kCalibrate;
  std::string scene_path;   // absolute path of the base scene
  std::vector<std::pair<std::string, std::string>> overrides;  // dotted key -> TOML value text
  std::vector<std::string> override_columns;  // the column each override came from (same order)
  std::map<std::string, double> conditions;   // numeric conditions by column (for plots)
  // Text conditions by column (a plate material, a set:KEY string such as a PSD file): the
  // page plots the residuals against them as categories.
  std::map<std::string, std::string> text_conditions;
  double angle_deg = 0.0;                     // measured angle of repose [deg], in (0, 90)
  std::optional<double> height_mm;            // measured H [mm]
  std::optional<double> diameter_mm;          // measured D [mm]
  std::optional<double> crest_mm;             // measured crest (flat top) width [mm], >= 0
  // Where crest_mm came from: "typed" (the crest_mm column, which wins over the photos) or
  // "photo" (vision's mean over the row's photos); empty when there is none.
  std::string crest_source;
  // The photo crest's uncertainty: the views' spread over sqrt(views) and each view's own
  // (vision's SideSummary::crest_width_m.sigma_mean) [mm]; absent for a typed crest.
  std::optional<double> crest_sigma_mm;
  std::optional<double> camera_height_m;      // declared camera height above the plate [m]
  int repeats = 1;                            // piles averaged into the measured values [-]
  std::vector<std::string> photos;            // absolute paths (side views), may be empty
  LabPhotoScale photo_scale;                  // how the photos' scale is known (the row's)
  nlohmann::json photo_measurement;           // what vision measured on the photos (if any)
  // The lab's declared side cameras of its photos (sidecars), distinct, in photo order: the
  // twin photographs its piles of this test with them (ImageVariant::lab_cameras). Empty: the
  // photos declare no camera (or there are none), and the twin frames its own.
  std::vector<camera::Camera> cameras;
  double reference_diameter_m = 0.0;          // dataset's typical grain d_ref, 0: own d50 [m]
};

/// A measured dataset.
struct LabData {
  std::string file;            // absolute path of the CSV
  std::vector<LabTest> tests;  // in file order
};

/// Which form of the lab's test sheet read_lab_csv reads: the loop's (every row names its scene
/// and role) or a calibration's (`reposetwin calibrate --tests`: the command gives the base
/// scene, and the role says which row is calibrated on, by default the first).
struct LabSheetForm {
  std::string base_scene;      // absolute path; empty: the `scene` column is required, else a
                               // row's empty or absent scene is this one
  bool role_required = true;   // false: without a role column the first row calibrates and
                               // the others are predicted (validate)
  std::vector<std::pair<std::string, std::string>> common;  // overrides of every row's scene
                                                           // before its own (the sieve sheet)
  std::string common_origin;  // where `common` came from, for errors ("--sieve FILE")
};

/// Reads a loop CSV (see docs/loop.md): checks every column, builds every test's scene (with
/// its overrides), measures the photos and sets every test's reference_diameter_m to the
/// dataset's typical grain (reference_grain_diameter of loop_effects.hpp). Throws InputError
/// (std::invalid_argument) whose message names the file, the line, the test id and the column:
/// missing required columns, unknown columns, non-numbers, an angle outside (0, 90), neither an
/// angle nor H and D nor a photo, an unknown role, duplicate ids, scene or override errors,
/// unreadable photos or photos without a usable scale.
LabData read_lab_csv(const std::string& path, const LabSheetForm& form = {});

/// The named condition columns and the scene key each one drives (with its unit conversion).
struct ConditionColumn {
  const char* column;  // CSV header
  const char* key;     // dotted scene key
  double factor;       // scene value = factor x CSV value (0: a string value)
  const char* unit;    // the CSV unit, for docs
};
const std::vector<ConditionColumn>& condition_columns();

/// The other columns of a test sheet (besides the condition columns and set:KEY), with their
/// meaning: the reader allows these and no others, and `reposetwin keys --campaign` lists them.
struct SheetColumn {
  const char* column;   // CSV header
  const char* meaning;  // one line, for docs
};
const std::vector<SheetColumn>& test_sheet_columns();

/// Every test-sheet column as a Markdown table (docs/calibration.md, `keys --campaign`).
std::string test_sheet_markdown();

nlohmann::json to_json(const LabTest& t);
/// A test back from its loop.json entry (the fields to_json writes; the CSV's override columns
/// and photo scale are not among them). Throws JsonFieldError (io/json_read.hpp) at the field.
LabTest lab_test_from_json(const nlohmann::json& j);
/// The role `j` names; JsonFieldError for a word other than "calibrate" or "validate".
Role role_from_json(const nlohmann::json& j);

}  // namespace reposetwin::experiments
