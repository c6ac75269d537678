// Dotted-key overrides of a scene file, applied to the parsed TOML before the scene is read.
//
// Why here and not in the engine: a campaign varies one or a few scene values per case
// ("contacts.rock-rock.rolling_friction" = 0.12, "sample.mass_kg" = 0.9). Applying them to the
// TOML table keeps one scene parser (strict, typed) as the only reader of scene files, so the
// engine only ever sees typed structs, never strings or key paths. The rules are deliberately
// strict so a typo cannot silently produce a different experiment: every parent on the path must
// already exist, and a value keeps its type (an integer may stand for a float, nothing else
// converts). A new leaf under an existing table is allowed; the strict scene parser then rejects
// it if the scene format does not know it. A numeric segment indexes an array
// ("walls.0.friction").
#pragma once

#include <toml++/toml.h>

#include <string>
#include <string_view>
#include <vector>

namespace reposetwin::experiments {

/// Splits "a.b.c" into {"a", "b", "c"}. Throws std::invalid_argument naming `origin` and the key
/// if the key is empty or has an empty segment ("a..b", ".a", "a.").
std::vector<std::string> split_dotted_key(std::string_view dotted_key,
                                          std::string_view origin = {});

/// Sets the value at `dotted_key` in `doc` to a copy of `value`. Throws std::invalid_argument
/// naming `origin` (e.g. "campaign.toml, case m200"), the key and the value when a parent on the
/// path is missing or not a table/array, an array index is out of range, or the new value's type
/// differs from the existing value's type (an integer replacing a float is converted to float).
void apply_override(toml::table& doc, std::string_view dotted_key, const toml::node& value,
                    std::string_view origin = {});

/// Applies every entry of `overrides` (keys are dotted paths, e.g. { "sample.mass_kg" = 0.9 }) to
/// `doc` in key order, so a whole-table override ("sample") precedes its members
/// ("sample.mass_kg").
void apply_overrides(toml::table& doc, const toml::table& overrides, std::string_view origin = {});

/// One override as a user writes it on a command line or in a measured-data row: the dotted key
/// and the value in TOML syntax ("0.1", "\"epsd\"", "[1, 2]").
struct Override {
  std::string key;    // dotted key path, e.g. "contacts.rock-rock.rolling_friction"
  std::string value;  // TOML value text
};

/// Parses "dotted.key=value". Throws InputError naming `origin` (e.g. "--set") and the text when
/// the '=' or the key is missing.
Override parse_override(std::string_view text, std::string_view origin);

/// Applies `overrides` to `doc` in order; each value text is parsed as TOML first. Throws
/// InputError naming `origin`, the key and the value when a value is not TOML or does not apply
/// (see apply_override).
void apply_overrides(toml::table& doc, const std::vector<Override>& overrides,
                     std::string_view origin);

/// Renders a TOML value in TOML syntax for error messages and case names ("0.1", "\"x\"", "[1,
/// 2]").
std::string toml_value_text(const toml::node& value);

}  // namespace reposetwin::experiments
