// The design file of a synthetic lab dataset (reposetwin loop-synth), read strictly.
//
// Design note. The file is TOML, so its reader lives at the file edge with the other readers; the
// loop (loop/loop_synth.hpp, which describes the format) turns the result into its SynthDesign.
// What the file may name (effect names, condition columns) belongs to the loop, so the loop
// passes it in as rules: io checks each name as it reads it and reports the file and the key.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace reposetwin::experiments {

/// One synthetic lab test.
struct SynthTest {
  std::string id;
  std::string role = "calibrate";
  std::map<std::string, double> conditions;  // numeric condition column (docs/loop.md) -> value
  std::map<std::string, std::string> labels;  // text condition column ("plate") -> value
};

/// The hidden true camera of the design's [camera] table.
struct SynthCamera {
  double distance_radii = 12.0;  // camera distance in pile radii [-]
  double noise_sd = 0.0;         // Gaussian image noise, grey levels [-]
  int width_px = 960;            // [px]
  int height_px = 720;           // [px]
  int side_views = 2;            // azimuths over 180 degrees [-]
  double height_m = 0.0;         // true camera height above the plate; the sidecars say 0 [m]
  bool aim_at_axis_foot = false;  // true camera pitched down at the axis foot, declared level
  double k1 = 0.0;               // true lens radial distortion; the sidecars say 0 [-]
};

/// A design file as read; every field not in the file keeps the value it had on input.
struct SynthDesignFile {
  std::string scene;  // absolute path of the base scene
  std::string mu_key;
  double mu_r = 0.0;
  std::vector<std::uint64_t> seeds;
  SynthCamera camera;
  std::vector<std::pair<std::string, double>> hidden;  // effect name -> value, in file order
  std::vector<SynthTest> tests;
};

/// What the file may name.
struct SynthDesignRules {
  std::function<void(const std::string&)> check_effect;  // throws std::invalid_argument
  std::set<std::string> numeric_columns;                 // numeric condition columns
  std::set<std::string> text_columns;                    // text condition columns ("plate")
};

/// Reads the design file at `path` over `defaults`. Throws InputError naming the file, the key
/// and the value for a missing scene, unknown keys, effects or columns, and bad values.
SynthDesignFile read_synth_design_file(const std::string& path, SynthDesignFile defaults,
                                       const SynthDesignRules& rules);

}  // namespace reposetwin::experiments
