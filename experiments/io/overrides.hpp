// Overrides of a scene file: a dotted key path and a value, applied before the scene is read.
//
// Why here and not in the engine: a campaign varies one or a few scene values per case
// ("contacts.rock-rock.rolling_friction" = 0.12, "sample.mass_kg" = 0.9), the command line sets
// them with --set and a measured-data row with its condition columns. Applying them to the scene
// file keeps one scene parser (strict, typed) as the only reader of scene files, so the engine
// only ever sees typed structs, never strings or key paths. The rules are deliberately strict so
// a typo cannot silently produce a different experiment: a parent on the path that the scene
// lacks is created only when the scene format has that table ("sample.shape.elongation" on a
// sphere scene makes its [sample.shape]; "rolling.sprng.k" is refused), and a value keeps its
// type (an integer may stand for a float, nothing else converts). A new leaf under an existing
// table is allowed, and a table value is one value: it replaces the table there or is inserted
// whole ("sample.shape" = { kind = "generated", elongation = 1.5, spheres = 4 }); the strict
// scene parser then rejects a key the scene format does not know. A numeric segment indexes an
// array ("walls.0.friction"). A command line's --set may create any missing table
// ("output.frame_interval_s" in a scene without [output]): the strict parser still refuses a
// table or key it does not know, and says the key came from --set.
//
// The value is kept as canonical TOML text ("0.10000000000000001", "'epsd'", "[ 1, 2 ]"): that is
// exactly what a user types and what a result file records, it round-trips every TOML value
// (floats to the bit), and it keeps TOML itself inside io/ (io/scene_doc.hpp applies them).
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

namespace reposetwin::experiments {

/// One override: the dotted key and the value in TOML syntax ("0.1", "\"epsd\"", "[1, 2]").
struct Override {
  std::string key;    // dotted key path, e.g. "contacts.rock-rock.rolling_friction"
  std::string value;  // TOML value text
  bool operator==(const Override&) const = default;
};

/// Splits "a.b.c" into {"a", "b", "c"}. Throws std::invalid_argument naming `origin` and the key
/// if the key is empty or has an empty segment ("a..b", ".a", "a.").
std::vector<std::string> split_dotted_key(std::string_view dotted_key,
                                          std::string_view origin = {});

/// Parses "dotted.key=value". Throws InputError naming `origin` (e.g. "--set") and the text when
/// the '=' or the key is missing.
Override parse_override(std::string_view text, std::string_view origin);

/// An override from a value as a person types it on a command line or in a CSV column: a TOML
/// value ("0.1", "'epsd'", "[1, 2]") as it is, and any other text as a string ("cdt",
/// "data/my psd.toml"), so string keys take bare words. Throws InputError naming `origin` when
/// the text is empty or starts like a TOML value it is not (an open quote or bracket).
Override typed_override(std::string key, std::string_view text, std::string_view origin);

/// An override setting `key` to the float `v`, its text read back to the same bits.
Override number_override(std::string key, double v);

/// An override setting `key` to the TOML string `text` (quoted and escaped as TOML needs).
Override string_override(std::string key, std::string_view text);

/// Whether `text` is one TOML value (a number, a quoted string, a boolean, an array, ...).
bool is_toml_value(std::string_view text);

/// Sets `o` in `list`, which is kept sorted by key with each key once: a later value for the same
/// key replaces the earlier one, and a whole table ("sample") is applied before its members
/// ("sample.mass_kg"). Campaign runs keep their overrides this way.
void set_override(std::vector<Override>& list, Override o);

/// `list` as a JSON object of key -> value (TOML numbers, strings, booleans, arrays and tables as
/// JSON), as result files record a run's overrides.
nlohmann::json overrides_to_json(const std::vector<Override>& list);

}  // namespace reposetwin::experiments
