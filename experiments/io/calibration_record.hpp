// The calibrated material: what a finished calibration hands to the commands after it.
//
// Design note. `reposetwin calibrate` writes calibration.json, most of which is the search's
// working (observations, jam rates, the fit) and differs between its two drivers. What a later
// command needs to rebuild the calibrated scene, and to say what it carries, is small and fixed:
// the base scene file (with the hash of its text, so an edited scene is caught), the calibration
// test's overrides in the order they were applied (the sieve sheet among them, as
// sample.psd_file), the calibrated keys, mu_r and its 95% interval, and the target it was fitted
// to. That is this record, written whole under calibration.json's key "material" by the one
// to_json and read back by the one from_json, which is strict within it: a missing key, an
// unknown key (with the nearest known one) or a value of the wrong type is an error naming the
// key and the value. The rest of calibration.json is the calibration's record
// (calibration/calibration_file.hpp), whose reader reads this one under "material" and whose
// read_calibrated_material() hands it to the export; it lives there because it needs the
// calibration's types, while this record stays here for export/, which sees io/ only. A
// calibration that reached no mu_r writes "material": null. Paths are absolute when written; a
// relative one (a record edited by hand) is read relative to the file's folder, as every path
// written in a file.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "experiments/io/overrides.hpp"

namespace reposetwin::experiments {

/// The calibrated material (see the design note).
struct CalibratedMaterial {
  std::string scene;                // the base scene file (absolute)
  std::string scene_fnv1a;          // FNV-1a of its text when it was calibrated (io/hash.hpp)
  std::vector<Override> overrides;  // the calibration test's, in order, without the keys below
  std::vector<std::string> keys;    // the calibrated scene keys, each set to mu_r
  double mu_r = 0.0;                // the calibrated value [-]
  double mu_r_lo = 0.0;             // its 95% interval [-]
  double mu_r_hi = 0.0;
  double target_deg = 0.0;  // the angle it was fitted to [deg]
  std::string angle;        // the twin's measure matched to it ("image", ...)
  std::string sieve_sheet;  // the file sample.psd_file names among the overrides; empty: the
                            // scene's own sieve table
  /// Every override a run of the calibrated material applies: the test's, then each key = mu_r.
  std::vector<Override> scene_overrides() const;
  bool operator==(const CalibratedMaterial&) const = default;
};

/// The record as calibration.json stores it.
nlohmann::json to_json(const CalibratedMaterial& m);

/// The record from its JSON (the value of calibration.json's "material"); `file` is the file it
/// is read from, for relative paths. Throws JsonFieldError (json_read.hpp) at the key, relative
/// to the record, for a missing, unknown or mistyped key; the reader of the whole file names the
/// file and puts "material" in front.
CalibratedMaterial calibrated_material_from_json(const nlohmann::json& j, const std::string& file);

/// The file a calibration folder keeps its record in.
inline constexpr const char* kCalibrationRecordFile = "calibration.json";

}  // namespace reposetwin::experiments
