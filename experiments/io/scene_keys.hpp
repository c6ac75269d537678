// The reference of every scene key: type, default, unit and meaning (`reposetwin keys`,
// docs/scene.md).
//
// Design note. The reference is one table next to the parser, and its defaults are read from
// the same default-constructed settings structs the parser starts from, so a changed default
// cannot leave the reference behind. That it is complete is a test, not a promise:
// tests/experiments/io/scene_keys_test.cpp records every key the parser looks up while it reads
// scenes that use every table (TableReader's key recorder) and every key the PSD reader allows,
// and fails for one the reference lacks. Keys under a table of user-chosen names are written
// with a placeholder: materials.<name>.density_kg_m3, contacts.<a>-<b>.friction, and the k-th
// grain shape of a mix as sample.shapes[<k>].elongation. The table is built from one function per
// scene table, in the order of a scene file.
#pragma once

#include <string>
#include <vector>

namespace reposetwin::experiments {

struct SceneKey {
  std::string key;           // dotted, with <name> / <a>-<b> placeholders
  std::string type;          // "string", "number", "integer", "array of numbers", "table", ...
  std::string default_text;  // "required", "-" (optional, no default) or the default value
  std::string unit;          // SI unit, or "-"
  std::string meaning;       // one line
};

/// Every scene key, in the order of a scene file.
const std::vector<SceneKey>& scene_keys();

/// The reference key of a dotted key as written in a scene ("materials.rock.poisson_ratio" ->
/// "materials.<name>.poisson_ratio", "sample.shapes[1].spheres" and the override form
/// "sample.shapes.1.spheres" -> "sample.shapes[<k>].spheres"); the key itself when no placeholder
/// applies.
std::string scene_key_pattern(const std::string& dotted);

/// Whether a dotted key path names a table a scene can have ("sample.shape", "output",
/// "contacts.rock-plate"): some reference key lies under it. An override may create such a table
/// where a scene has none (io/toml_edit.hpp, MissingTables::kSceneTables).
bool is_scene_table(const std::string& dotted);

/// The reference as a Markdown page (docs/scene.md is this text).
std::string scene_keys_markdown();

}  // namespace reposetwin::experiments
