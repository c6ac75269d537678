#include "experiments/io/scene_overrides.hpp"

#include <filesystem>
#include <sstream>

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
  for (const std::string& s : sets) {
    const auto eq = s.find('=');
    if (eq == std::string::npos || eq == 0)
      throw InputError("--set \"" + s + "\": expected dotted.key=value");
    toml::table value_doc;
    try {
      value_doc = toml::parse("v = " + s.substr(eq + 1));
    } catch (const toml::parse_error& e) {
      throw InputError("--set \"" + s + "\": the value is not a TOML value (" +
                       std::string(e.description()) + ")");
    }
    try {
      apply_override(doc, s.substr(0, eq), *value_doc.get("v"), "--set");
    } catch (const std::invalid_argument& e) {
      throw InputError(file + ": " + e.what());
    }
  }
  return parse_scene_table(doc, file);
}

}  // namespace reposetwin::experiments
