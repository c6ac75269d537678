// The settings of a mu_r calibration, as a campaign file's [calibration] table gives them.
//
// Design note. These are plain records with SI defaults and their bounds: the file edge
// (io/campaign_calibration_file.cpp) reads them from TOML and checks them, and the drivers in
// calibration/ (calibration.hpp, bracket_calibration.hpp, whose design notes say what each knob
// does) take them. They live here, not beside the drivers, so that io depends on nothing above
// it: a reader fills the record, the driver runs it.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

namespace reposetwin::experiments {

/// The measured angle to match, with its own 1-sigma uncertainty (0 when unknown).
struct Target {
  double angle_deg = 0.0;  // [deg], must lie in (0, 90)
  double sd_deg = 0.0;     // 1-sigma uncertainty of the measured angle [deg], >= 0
  bool operator==(const Target&) const = default;
};

/// Settings of the bootstrap that gives the uncertainty intervals.
struct BootstrapSettings {
  int replicates = 2000;           // number of bootstrap replicates
  std::uint64_t rng_seed = 12345;  // seed of the bootstrap's random stream
};

/// Settings of the sequential calibration driver (calibration/calibration.hpp).
struct CalibrationSettings {
  double mu_r_lo = 0.0;          // low end of the mu_r range [-], >= 0
  double mu_r_hi = 0.5;          // high end of the mu_r range [-], > mu_r_lo
  int seeds_per_point = 3;       // runs per mu_r point (seeds first_seed, first_seed + 1, ...)
  std::uint64_t first_seed = 1;  // first run seed at every point
  double tolerance_deg = 0.5;    // angle tolerance of the calibration [deg], > 0 (95% level)
  int max_simulations = 40;      // budget of simulate() calls, confirmation included
  bool confirm_bracket = true;   // finish with fresh seeds at the bracket points (calibration.hpp,
                                 // "Confirmation")
  BootstrapSettings bootstrap;
};

/// Settings of the bracketing driver (calibration/bracket_calibration.hpp).
struct BracketSettings {
  double mu_r_lo = 0.0;                       // low end of the mu_r range [-], >= 0
  double mu_r_hi = 0.5;                       // high end of the mu_r range [-], > mu_r_lo
  std::optional<double> mu_r_start;           // first point [-]; nothing = middle of the range
  bool ends_first = false;                    // run both ends of the range first (instead of
                                              // mu_r_start): a target out of reach is then
                                              // known after those two points
  double slope_guess_deg = 25.0;              // expected d(angle)/d(mu_r) [deg per unit mu_r], > 0
  std::vector<std::uint64_t> seeds = {1, 2};  // the seeds run at every point, >= 2 distinct
  double mu_r_tolerance = 0.02;               // stop when the uncertainty of mu_r is below [-], > 0
  int max_runs = 6;                           // budget of pours, jams included, >= 2 x seeds
  double max_jam_rate = 0.5;                  // a point with a higher jam rate is beyond the usable
                                              // range [-], in [0, 1)
  BootstrapSettings bootstrap;                // the 95% interval of the final fit
};

/// Checks a target: angle in (0, 90) and sd >= 0. Throws std::invalid_argument otherwise.
void validate_target(const Target& target);

/// Checks bracket settings; std::invalid_argument naming the field and value.
void validate_bracket_settings(const BracketSettings& s);

}  // namespace reposetwin::experiments
