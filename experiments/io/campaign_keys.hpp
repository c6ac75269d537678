// The reference of every campaign and calibration file key (`reposetwin keys --campaign`,
// docs/calibration.md): type, default, unit and meaning.
//
// Design note. The readers (io/campaign_file.cpp, io/campaign_calibration_file.cpp) take the
// keys they allow from this table (campaign_table_keys), so a key cannot be read without being
// documented, nor documented without being read; the defaults are those of the settings structs
// the readers start from (io/calibration_settings.hpp).
#pragma once

#include <set>
#include <string>
#include <vector>

#include "experiments/io/scene_keys.hpp"

namespace reposetwin::experiments {

/// Every key of a campaign file, by table: the top level, [[case]], [sweep], [calibration] and
/// [[predict]], in the order of a file. SceneKey's fields: the key is written with its table
/// ("calibration.mu_r_range", "case[].name").
const std::vector<SceneKey>& campaign_keys();

/// The leaf names allowed in one table of a campaign file ("" the top level, "case", "sweep",
/// "calibration", "predict").
std::set<std::string> campaign_table_keys(const std::string& table);

/// The reference as Markdown tables (the key part of docs/calibration.md).
std::string campaign_keys_markdown();

}  // namespace reposetwin::experiments
