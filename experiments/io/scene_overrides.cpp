#include "experiments/io/scene_overrides.hpp"

#include <filesystem>

#include "experiments/io/provenance.hpp"
#include "experiments/io/toml_edit.hpp"
#include "experiments/io/toml_reader.hpp"
#include "experiments/io/toml_tables.hpp"

namespace reposetwin::experiments {

struct SceneDoc::Tree {
  toml::table doc;
};

SceneDoc::SceneDoc(const std::string& path)
    : file_(path.empty() ? "<embedded>" : path), tree_(std::make_unique<Tree>()) {
  tree_->doc = parse_toml(path.empty() ? embedded_quick_scene() : read_file(path), file_);
}

SceneDoc::SceneDoc(const std::string& path, std::span<const Override> overrides,
                   std::string_view origin)
    : SceneDoc(path) {
  apply(overrides, origin);
}

void SceneDoc::apply(std::span<const Override> overrides, std::string_view origin) {
  apply_overrides(tree_->doc, std::vector<Override>(overrides.begin(), overrides.end()), origin);
}

SceneDoc::~SceneDoc() = default;
SceneDoc::SceneDoc(SceneDoc&&) noexcept = default;
SceneDoc& SceneDoc::operator=(SceneDoc&&) noexcept = default;

void SceneDoc::set_seed(std::uint64_t seed) {
  if (toml::table* s = tree_->doc["scene"].as_table())
    s->insert_or_assign("seed", static_cast<std::int64_t>(seed));
}

void SceneDoc::final_frame_only() {
  if (toml::table* o = tree_->doc["output"].as_table())
    o->insert_or_assign("frame_interval_s", 0.0);
}

std::optional<double> SceneDoc::number(std::string_view dotted_key) const {
  return tree_->doc.at_path(dotted_key).value<double>();
}

std::optional<std::string> SceneDoc::string(std::string_view dotted_key) const {
  return tree_->doc.at_path(dotted_key).value<std::string>();
}

bool SceneDoc::has(std::string_view dotted_key) const {
  return static_cast<bool>(tree_->doc.at_path(dotted_key));
}

SceneConfig SceneDoc::config() const { return parse_scene_table(tree_->doc, file_); }

SceneConfig load_scene(const std::string& path, const std::vector<std::string>& sets) {
  std::vector<Override> overrides;
  for (const std::string& s : sets) overrides.push_back(parse_override(s, "--set"));
  return load_scene(path, overrides);
}

SceneConfig load_scene(const std::string& path, std::span<const Override> overrides) {
  const std::string file = path.empty() ? "<embedded>" : path;
  if (!path.empty() && !std::filesystem::exists(path))
    throw InputError(path + ": scene file does not exist");
  SceneDoc doc(path);
  try {
    doc.apply(overrides, "--set");
  } catch (const InputError& e) {
    throw InputError(file + ": " + e.what());
  }
  return doc.config();
}

}  // namespace reposetwin::experiments
