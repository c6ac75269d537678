// Overrides applied to a parsed TOML document: io's own machinery behind io/scene_doc.hpp and the
// campaign file's checks; not for use outside io/ (everything else passes io::Override and reads
// typed SceneConfig values).
#pragma once

#include <toml++/toml.h>

#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "experiments/io/overrides.hpp"

namespace reposetwin::experiments {

/// What an override does with a table on its path that the document does not have.
enum class MissingTables {
  kRefuse,       // every parent must exist
  kSceneTables,  // create a table the scene format has (io/scene_keys.hpp), refuse any other:
                 // a campaign case may give a sphere scene [sample.shape], and a misspelt
                 // table is still refused when the campaign loads, before any scene is parsed
  kCreate,       // create any table (--set: the strict scene parser judges it afterwards)
};

/// Sets the value at `dotted_key` in `doc` to a copy of `value` (a table value replaces the
/// table there, or is inserted whole). Throws std::invalid_argument naming `origin` (e.g.
/// "campaign.toml, case m200"), the key and the value when a parent on the path is missing (and
/// `missing` does not create it) or not a table/array, an array index is out of range, or the new
/// value's type differs from the existing value's type (an integer replacing a float is
/// converted to float). A missing array element is always an error.
void apply_override(toml::table& doc, std::string_view dotted_key, const toml::node& value,
                    std::string_view origin = {}, MissingTables missing = MissingTables::kRefuse);

/// Applies every entry of `overrides` (keys are dotted paths, e.g. { "sample.mass_kg" = 0.9 }) to
/// `doc` in key order, so a whole-table override ("sample") precedes its members
/// ("sample.mass_kg").
void apply_overrides(toml::table& doc, const toml::table& overrides, std::string_view origin = {});

/// Applies `overrides` to `doc` in order; each value text is parsed as TOML first. Throws
/// InputError naming `origin`, the key and the value when a value is not TOML or does not apply
/// (see apply_override). Every scene override (a campaign case, a calibration or loop run) goes
/// through here with the default, so the check when a campaign loads and the run itself agree.
void apply_overrides(toml::table& doc, const std::vector<Override>& overrides,
                     std::string_view origin,
                     MissingTables missing = MissingTables::kSceneTables);

/// Renders a TOML value in TOML syntax for error messages, case names and Override::value ("0.1",
/// "'x'", "[ 1, 2 ]"); floats are written to read back to the same bits.
std::string toml_value_text(const toml::node& value);

/// An Override from a parsed TOML value.
Override override_of(std::string key, const toml::node& value);

/// A TOML value as JSON (dates and times as their text).
nlohmann::json toml_to_json(const toml::node& n);

}  // namespace reposetwin::experiments
