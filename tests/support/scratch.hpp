// Scratch folders and scene files for tests that run the pile test: a fresh folder per test
// under the system's temporary directory, and a scene read from text written into it (so the
// scene's relative paths and messages name a real file, as a user's would).
#pragma once

#include <stdlib.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include "experiments/io/scene.hpp"

namespace reposetwin::test_support {

/// An empty folder `<tmp>/reposetwin_test_<name>` (removed first if it exists).
inline std::filesystem::path temp_dir(const std::string& name) {
  const std::filesystem::path p =
      std::filesystem::temp_directory_path() / ("reposetwin_test_" + name);
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
  return p;
}

/// A new empty folder `<tmp>/reposetwin_<name>.XXXXXX` made by mkdtemp: its own, whatever else
/// runs at the same time; removed when the object goes.
class UniqueTempDir {
 public:
  explicit UniqueTempDir(const std::string& name) {
    std::string t =
        (std::filesystem::temp_directory_path() / ("reposetwin_" + name + ".XXXXXX")).string();
    if (!::mkdtemp(t.data())) throw std::runtime_error("mkdtemp " + t + " failed");
    path_ = t;
  }
  ~UniqueTempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  UniqueTempDir(const UniqueTempDir&) = delete;
  UniqueTempDir& operator=(const UniqueTempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

/// `text` written to `dir`/scene.toml and read by the strict scene parser.
inline experiments::SceneConfig scene_from(const std::string& text,
                                           const std::filesystem::path& dir) {
  const std::filesystem::path file = dir / "scene.toml";
  std::ofstream(file) << text;
  return experiments::parse_scene_file(file.string());
}

}  // namespace reposetwin::test_support
