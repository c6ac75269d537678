// The scene and PSD readers over already parsed TOML tables: io's own entry points behind
// parse_scene_text, read_psd_file and io/scene_doc.hpp; not for use outside io/ (the rest of the
// project passes file names, io::Override and typed configs).
#pragma once

#include <toml++/toml.h>

#include <string>

#include "experiments/io/psd_file.hpp"
#include "experiments/io/scene.hpp"

namespace reposetwin::experiments {

/// Parses an already loaded (and possibly overridden) TOML document.
SceneConfig parse_scene_table(const toml::table& doc, const std::string& file);

/// Parses a [psd] table, for instance one embedded in a scene file; `source` names that file in
/// messages and `where` the table's path in it (e.g. "psd"). Throws std::invalid_argument naming
/// the source, the field and the value for bad content.
PsdFile parse_psd_table(const toml::table& table, const std::string& source,
                        const std::string& where = "psd");

/// The [psd] table of a sieve-table file as TOML, for the resolved scene a run folder keeps: the
/// file's own table, or a CSV sheet's columns, name and notes written as one. Throws as
/// read_psd_file does.
toml::table psd_table_of_file(const std::string& path);

}  // namespace reposetwin::experiments
