// Pieces shared by the campaign file's readers (campaign_file.cpp for the cases and predictions,
// campaign_calibration_file.cpp for [calibration]); not for use outside io/.
//
// Messages keep one shape, "FILE: key 'KEY' = VALUE: why", so a user sees where, what and why;
// the typed reads themselves go through TableReader and keep its shape.
#pragma once

#include <toml++/toml.h>

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "experiments/io/campaign_file.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/toml_reader.hpp"

namespace reposetwin::experiments::campaign_file {

/// An error naming the file, the key and (unless empty) the value.
InputError bad(const std::string& file, const std::string& key, const std::string& value,
               const std::string& why);
/// A TOML value as the user wrote it, for messages.
std::string value_text(const toml::node& n);

/// A required string; "missing (a string is required)" names the key otherwise.
std::string required_string(TableReader& t, const std::string& key);
std::optional<double> optional_number(TableReader& t, const std::string& key);
std::optional<std::int64_t> optional_integer(TableReader& t, const std::string& key);
/// An optional table1_sample: the paper's Table 1 sample number, 1..4.
std::optional<int> read_table1_sample(TableReader& t);

/// Scene files parsed once per campaign file, to check every override against its scene.
class SceneCache {
 public:
  /// The parsed scene at `path` (absolute); InputError naming it when it is not TOML.
  const toml::table& get(const std::string& path);

 private:
  std::map<std::string, toml::table> scenes_;
};

/// Stage 4 of parse_campaign: the [calibration] table, with its keys checked against the base
/// scene and, for target_photos, the lab photos recorded (not yet measured).
CampaignCalibration read_calibration_table(TableReader& t, const Campaign& c, SceneCache& scenes);

}  // namespace reposetwin::experiments::campaign_file
