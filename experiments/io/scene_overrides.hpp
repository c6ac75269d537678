// Scenes with overrides: the one place a scene's TOML is parsed and edited.
//
// Design note. A run's scene is the file plus a list of io::Override (a campaign case, --set, a
// measured-data row, the loop's candidate effects), applied in order, then read by the strict
// scene parser into one SceneConfig. Applying them here, once, checks every override against the
// scene (a missing parent, a changed type and an unknown key are errors naming the origin, the
// key and the value) before anything runs. The few callers that need a single value by its key
// path (the loop's factor effects, the calibration's rolling model beside the calibrated key, the
// contact pair a pattern names) ask the document, so no code outside io/ reads TOML. The TOML
// tree itself stays behind a pointer, so the TOML library is not part of this header.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "experiments/io/overrides.hpp"
#include "experiments/io/scene.hpp"

namespace reposetwin::experiments {

class SceneDoc {
 public:
  /// Reads the scene file at `path` (the embedded quick scene when `path` is empty). Throws
  /// std::runtime_error for an unreadable file and InputError naming the file (and line) for a
  /// TOML syntax error.
  explicit SceneDoc(const std::string& path);
  /// The same, then apply(overrides, origin).
  SceneDoc(const std::string& path, std::span<const Override> overrides,
           std::string_view origin);
  ~SceneDoc();
  SceneDoc(SceneDoc&&) noexcept;
  SceneDoc& operator=(SceneDoc&&) noexcept;

  /// Applies `overrides` in order. Throws InputError naming `origin`, the key and the value for
  /// an override that is not TOML or does not apply (see io/overrides.hpp for the rules).
  void apply(std::span<const Override> overrides, std::string_view origin);

  /// Applies a command line's --set texts ("dotted.key=value"): a value that is not TOML is a
  /// word (a string), missing tables are created, and `sample.psd_file` takes the place of an
  /// inline [sample.psd] table, its path relative to the working directory (where the person
  /// typing it stands), not to the scene file. Throws InputError naming --set, the text and the
  /// file.
  void apply_command_line(std::span<const std::string> sets);

  /// Sets [scene] seed (a run's seed is given apart from its overrides); nothing when the file
  /// has no [scene] table, whose default seed then stands.
  void set_seed(std::uint64_t seed);
  /// Sets [output] frame_interval_s = 0 (final state only) when the file has an [output] table.
  void final_frame_only();

  /// The value at a dotted key path, when it is there and of that kind (an integer reads as a
  /// number).
  std::optional<double> number(std::string_view dotted_key) const;
  std::optional<std::string> string(std::string_view dotted_key) const;
  /// Whether the key path names anything (a table, an array or a value).
  bool has(std::string_view dotted_key) const;

  /// The scene read strictly (unknown keys refused; see io/scene.hpp).
  SceneConfig config() const;
  /// The same; an error about a key a --set changed says so, with the text as typed.
  SceneConfig config_after_command_line() const;
  /// The file name the document reports in messages ("<embedded>" for the quick scene).
  const std::string& file() const { return file_; }

 private:
  struct Tree;
  std::string file_;
  std::unique_ptr<Tree> tree_;
  std::vector<std::string> sets_;  // the --set texts applied, as typed
};

/// Loads a scene file (or the embedded quick scene when `path` is empty) and applies
/// "dotted.key=value" overrides (--set: a TOML value, 0.1, "epsd", true, [1, 2], or a bare word;
/// see SceneDoc::apply_command_line) before parsing. Throws InputError naming the file for a missing file and, with the key, for a bad
/// override.
SceneConfig load_scene(const std::string& path, const std::vector<std::string>& sets = {});

/// The same with typed overrides (a measured-data row, the loop's candidate effects).
SceneConfig load_scene(const std::string& path, std::span<const Override> overrides);

}  // namespace reposetwin::experiments
