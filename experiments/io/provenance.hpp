// Provenance and safe result files.
//
// Every result file says how it was made (scene, seed, time step, softened stiffness, code
// version), and results are never lost: files are written to a temporary name in the same folder
// and renamed into place, so a reader sees either the old file or the whole new one.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace reposetwin::experiments {

/// The code version: project version plus `git describe` when the build ran.
std::string code_version();

/// UTC time now, ISO 8601 ("2026-11-22T01:02:03Z").
std::string utc_now();

/// Writes `text` to `path` atomically (temporary file + rename). Throws std::runtime_error
/// naming the path on failure. Creates missing parent folders.
void write_file_atomic(const std::string& path, const std::string& text);

/// Writes JSON (indented) atomically.
void write_json_atomic(const std::string& path, const nlohmann::json& j);

/// Reads a whole text file; throws std::runtime_error naming the path if it cannot.
std::string read_file(const std::string& path);

}  // namespace reposetwin::experiments
