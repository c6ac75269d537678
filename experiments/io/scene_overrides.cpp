#include "experiments/io/scene_overrides.hpp"

#include <filesystem>

#include "experiments/io/overrides.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/io/toml_reader.hpp"

namespace reposetwin::experiments {

SceneConfig load_scene(const std::string& path, const std::vector<std::string>& sets) {
  const std::string file = path.empty() ? "<embedded>" : path;
  if (!path.empty() && !std::filesystem::exists(path))
    throw InputError(path + ": scene file does not exist");
  const std::string text = path.empty() ? embedded_quick_scene() : read_file(path);
  toml::table doc = parse_toml(text, file);
  std::vector<Override> overrides;
  for (const std::string& s : sets) overrides.push_back(parse_override(s, "--set"));
  try {
    apply_overrides(doc, overrides, "--set");
  } catch (const InputError& e) {
    throw InputError(file + ": " + e.what());
  }
  return parse_scene_table(doc, file);
}

}  // namespace reposetwin::experiments
