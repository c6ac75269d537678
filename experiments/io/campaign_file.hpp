// The campaign file: what a campaign runs, read from TOML into plain structs.
//
// Design.
//  * A campaign file (TOML, strict: unknown keys are errors, reported before anything else so a
//    misspelt key is named rather than the value it stood for) names a base scene, seeds, and
//    either a list of [[case]] tables (each with dotted-key overrides) or one [sweep] over a key;
//    every case runs once per seed. Loading checks everything a run would trip on later (missing
//    scene files, overrides that do not apply to the scene) so a campaign fails at once, not
//    after hours. Every message names the file, the key and the value (InputError).
//  * Keys are read through TableReader (io/toml_reader.hpp), the one strict reader of scene and
//    campaign files; what TableReader cannot say (a seed list or count, an array of tables, an
//    override table) is read from the raw node beside it, with the same kind of message.
//
// File format (paths relative to the campaign file; every key below, nothing else):
//   name = "mass_sensitivity"                 # filesystem-safe
//   description = "..."                       # optional
//   paper = "Fig. 8"                          # optional: the paper item it reproduces
//   scene = "../../data/scenes/quick.toml"    # base scene
//   seeds = [1, 2, 3]                         # or a count: seeds = 3 means 1, 2, 3
//   overrides = { "sample.mass_kg" = 0.2 }    # optional, common to every case
//   [[case]]                                  # either cases ...
//   name = "m200"
//   description = "200 g"                     # optional
//   scene = "other.toml"                      # optional
//   overrides = { "sample.mass_kg" = 0.2 }    # quoted or bare dotted keys; a table value
//                                             # ("sample.shape" = { kind = ... }) is set whole
//   [sweep]                                   # ... or one sweep (case names <leaf>_<value>)
//   key = "sample.mass_kg"
//   values = [0.05, 0.2, 0.9]
//   name = "mass"                             # optional prefix instead of the key's leaf
//   [calibration]                             # optional, for the calibrate command
//   target_deg = 33.47                        # measured angle, in (0, 90)
//   target_sd_deg = 0.3                       # optional, its 1-sigma uncertainty
//   # or, instead of target_deg, the lab's side photos of the pile, measured with vision/ as the
//   # renders are (atan(2H/D) for image/particles, the flank angle for image_flank/slice; sd:
//   # the measurement's uncertainty of the mean unless target_sd_deg is given):
//   # target_photos = ["lab/side_0.png", "lab/side_90.png"]
//   # target_photo_camera = "lab/camera.json"  # optional scale: a camera sidecar, or
//   # target_mm_per_px = 0.21                  # mm per pixel at the pile axis, or STEM.json
//   #                                          # beside each photo, or the scale reference
//   mu_r_range = [0.02, 0.4]
//   key = "contacts.rock-rock.rolling_friction"  # optional (this is the default)
//   seeds_per_point = 3                       # optional, as are first_seed (1), tolerance_deg
//   max_simulations = 40                      # (0.5), bootstrap_replicates (2000), confirm
//   table1_sample = 3                         # optional: the paper's Table 1 sample (reports)
//   angle = "image"                           # optional: which simulated angle is matched
//                                             # (image, image_flank, particles, slice; below)
//   method = "bracket"                        # optional: "sequential" (default) or "bracket"
//                                             # (bracket_calibration.hpp: the seeds
//                                             # first_seed.. at every point, max_simulations
//                                             # pours, default 3 x seeds_per_point), with:
//   mu_r_start = 0.35                         # optional first point (default: mid-range)
//   ends_first = true                         # optional (false): both range ends first instead
//   slope_guess_deg = 26.0                    # optional d(angle)/d(mu_r) guess (25)
//   mu_r_tolerance = 0.02                     # optional stop tolerance on mu_r (0.02)
//   max_jam_rate = 0.5                        # optional: points jamming more are unusable
//   [[predict]]                               # optional, with [calibration]: other tests run at
//   name = "sample4"                          # the calibrated mu_r (filesystem-safe, unique)
//   scene = "s4.toml"                         # required: the other test's scene
//   measured_deg = 37.17                      # required: its measured angle, in (0, 90)
//   measured_sd_deg = 0.3                     # optional, its 1-sigma uncertainty
//   seeds = [1, 2, 3]                         # optional: list or count (default: the campaign's
//                                             # seeds, else seeds_per_point from first_seed)
//   overrides = { ... }                       # optional, on top of the common overrides
//   interval_ends = true                      # optional (true): also run the seeds at the ends
//                                             # of the calibrated mu_r's 95% interval
//   table1_sample = 4                         # optional: the paper's Table 1 sample (reports)
//   description = "..."                       # optional
// `calibration.angle` names the simulated angle compared with the measured one (AngleMeasure):
// "image" (default) is atan(2H/D) read by vision on the renders, as the lab photo is read;
// "image_flank" is the flank-line angle vision fits on the same renders (a protractor laid on the
// photo); "particles" and "slice" are atan(2H/D) and the protractor on centre slices from the
// particle positions (the latter is EDEM's simulated angle in the paper). Matching a flank angle
// to a lab atan(2H/D) assumes the lab pile is a full cone (its two angles equal): declare it.
// `calibration.key` may also be a list of keys that all take the calibrated value (e.g. rock-rock
// and rock-plate rolling friction); the first names the calibration runs.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "experiments/io/calibration_settings.hpp"
#include "experiments/io/overrides.hpp"

namespace reposetwin::experiments {

/// One run of a campaign: a case (scene + overrides) with one seed.
struct CaseSpec {
  std::size_t index = 0;   // position in the campaign's run list (used for MPI distribution)
  std::string case_name;   // unique, filesystem-safe
  std::uint64_t seed = 0;  // run seed
  std::string scene_path;  // absolute path of the scene file
  std::string scene_hash;  // FNV-1a 64 of the scene file's text (hex), to detect edited inputs
  std::vector<Override> overrides;  // sorted by key, applied to the scene before parsing
  /// The run's folder relative to the campaign output folder ("cases/<case>/seed_<n>").
  std::string relative_dir() const;
  /// A short id for messages ("<case>/seed_<n>").
  std::string id() const;
};

/// Which simulated angle a calibration or a prediction compares with the measured one.
enum class AngleMeasure {
  kImage,       // vision on the renders: atan(2H/D), as the lab photo is read
  kImageFlank,  // vision on the renders: mean flank-line angle over the views
  kParticles,   // particle positions: atan(2H/D)
  kSlice,       // particle positions: protractor on slices through the pile centre (EDEM's)
};

/// The file name of a measure ("image", "image_flank", "particles", "slice").
std::string angle_measure_name(AngleMeasure m);
/// A sentence saying how the measure is taken, for result files and reports.
std::string angle_measure_method(AngleMeasure m);
/// Parses a measure's name; std::invalid_argument naming `where` and the value otherwise.
AngleMeasure parse_angle_measure(const std::string& name, const std::string& where);
/// True when the measure is read from renders (the runs must be photographed).
inline bool angle_measure_needs_images(AngleMeasure m) {
  return m == AngleMeasure::kImage || m == AngleMeasure::kImageFlank;
}

/// How the calibrate command searches mu_r.
enum class CalibrationMethod {
  kSequential,  // calibration.hpp: range ends, safeguarded secant, confirmation seeds
  kBracket,     // bracket_calibration.hpp: bracketing, common random numbers, few runs
};

/// calibration.target_photos as the file gives them: the lab's side photos and their scale, with
/// the text that names each key in a message. Recorded here, measured by calibration/
/// (campaign_target.hpp, measure_target_photos) when the campaign is loaded.
struct TargetPhotoFiles {
  std::vector<std::string> photos;  // absolute paths, in file order
  std::string camera_json;          // target_photo_camera: a camera sidecar for every photo, or
                                    // empty (relative to the campaign file's folder when given so)
  std::optional<double> mm_per_px;  // target_mm_per_px [mm/px] as written (checked when measured)
  std::optional<double> sd_deg;     // target_sd_deg [deg]: replaces the measurement's when given
  std::string photos_at;     // "FILE: key 'calibration.target_photos'"
  std::string camera_at;     // "FILE: key 'calibration.target_photo_camera'"
  std::string mm_per_px_at;  // "FILE: key 'calibration.target_mm_per_px'"
};

/// The [calibration] table of a campaign file, for the calibrate command.
struct CampaignCalibration {
  std::string key = "contacts.rock-rock.rolling_friction";  // dotted scene key that is varied
  std::vector<std::string> keys;     // every key set to mu_r (keys.front() == key); empty = {key}
  Target target;                     // measured angle to match
  CalibrationSettings settings;      // mu_r range, seeds per point, tolerance, budget
  CalibrationMethod method = CalibrationMethod::kSequential;
  BracketSettings bracket;           // method = "bracket": the same range, seeds and budget
                                     // as `settings`, plus its own keys
  std::optional<int> table1_sample;  // the paper's Table 1 sample it calibrates on (reports)
  AngleMeasure angle = AngleMeasure::kImage;  // the simulated angle matched to the target
  std::optional<TargetPhotoFiles> target_photo_files;  // the target is measured on these photos
                                                      // (absent: target_deg typed in)
  nlohmann::json target_photos;  // their measurement, set with `target` by measure_target_photos
                                 // (null: target_deg typed in, or not measured yet)
};

/// One [[predict]] entry: another test, run at the calibrated mu_r with its own seeds.
struct PredictionCase {
  std::string name;                  // filesystem-safe, unique among the predictions
  std::string description;           // free text (optional)
  std::string scene_path;            // absolute path of the test's scene
  std::string scene_hash;            // FNV-1a 64 of the scene file's text (hex)
  std::vector<Override> overrides;   // the campaign's common overrides, then the entry's own
  Target measured;                   // the test's measured angle and its 1-sigma uncertainty
  std::vector<std::uint64_t> seeds;  // run seeds
  bool interval_ends = true;         // also run the seeds at both ends of the mu_r interval
  std::optional<int> table1_sample;  // the paper's Table 1 sample it predicts (reports)
};

/// A parsed campaign file.
struct Campaign {
  std::string name;         // filesystem-safe
  std::string description;  // free text (optional)
  std::string paper;        // the paper item it reproduces, e.g. "Fig. 8" (optional)
  std::string file;         // absolute path of the campaign file
  std::string scene_path;   // absolute path of the base scene
  std::vector<std::uint64_t> seeds;
  std::vector<Override> overrides;  // the file's top-level overrides, common to every run
  std::vector<CaseSpec> runs;  // cases x seeds, in file order then seed order
  std::optional<CampaignCalibration> calibration;
  std::vector<PredictionCase> predictions;  // [[predict]] entries (only with [calibration])
};

/// Reads a campaign file. Throws InputError (or std::runtime_error for unreadable files) whose
/// message names the file, the key and the value: unknown keys, wrong types, missing or
/// unreadable scenes, duplicate or unsafe case names, overrides that do not apply to the scene.
/// Target photos are recorded, not measured: the commands load a campaign through
/// load_campaign() (calibration/campaign_target.hpp), which measures them too.
Campaign read_campaign_file(const std::string& path);

/// Parses campaign text; `path` names it in messages and anchors relative scene paths.
Campaign parse_campaign(std::string_view text, const std::string& path);

/// Whether a name is safe as a folder name: [A-Za-z0-9][A-Za-z0-9._-]*, at most 100 characters.
bool is_safe_name(std::string_view name);

/// `text` with every character is_safe_name does not allow replaced by '_' (for run names made
/// from keys and values).
std::string sanitize_name(std::string_view text);

}  // namespace reposetwin::experiments
