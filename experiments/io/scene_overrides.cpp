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
  // A scene is a page of text; a cap keeps a wrong file (a log, an image) from filling memory.
  constexpr std::uintmax_t kMaxSceneBytes = std::uintmax_t{16} << 20;
  tree_->doc =
      parse_toml(path.empty() ? embedded_quick_scene() : read_file(path, kMaxSceneBytes), file_);
}

SceneDoc::SceneDoc(const std::string& path, std::span<const Override> overrides,
                   std::string_view origin)
    : SceneDoc(path) {
  apply(overrides, origin);
}

void SceneDoc::apply(std::span<const Override> overrides, std::string_view origin) {
  apply_overrides(tree_->doc, std::vector<Override>(overrides.begin(), overrides.end()), origin);
}

void SceneDoc::apply_command_line(std::span<const std::string> sets) {
  std::vector<Override> overrides;
  try {
    for (const std::string& text : sets) {
      const Override raw = parse_override(text, "--set");
      Override o = typed_override(raw.key, raw.value, "--set");
      if (o.key == "sample.psd_file") {
        const auto path = toml::parse("v = " + o.value)["v"].value<std::string>();
        if (path && path->empty())
          throw InputError("--set " + text + ": sample.psd_file is empty; name a sieve-table file",
                           o.key);
        if (path)
          o = string_override(o.key, std::filesystem::absolute(*path).lexically_normal().string());
      }
      overrides.push_back(std::move(o));
    }
    apply_overrides(tree_->doc, overrides, "--set", MissingTables::kCreate);
  } catch (const InputError& e) {
    throw InputError(file_ + ": " + e.what());
  }
  sets_.insert(sets_.end(), sets.begin(), sets.end());
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
  const toml::node* n = tree_->doc.at_path(dotted_key).node();
  if (n == nullptr) return std::nullopt;
  return number_of(*n);
}

std::optional<std::string> SceneDoc::string(std::string_view dotted_key) const {
  return tree_->doc.at_path(dotted_key).value<std::string>();
}

bool SceneDoc::has(std::string_view dotted_key) const {
  return static_cast<bool>(tree_->doc.at_path(dotted_key));
}

SceneConfig SceneDoc::config() const { return parse_scene_table(tree_->doc, file_); }

SceneConfig SceneDoc::config_after_command_line() const {
  try {
    return config();
  } catch (const InputError& e) {
    // The reader names the k-th of [[sample.shapes]] "sample.shapes[k]", an override
    // "sample.shapes.k".
    std::string k = e.key();
    for (std::size_t at; (at = k.find('[')) != std::string::npos;) {
      const std::size_t close = k.find(']', at);
      if (close == std::string::npos) break;
      k = k.substr(0, at) + "." + k.substr(at + 1, close - at - 1) + k.substr(close + 1);
    }
    if (k.empty()) throw;
    auto under = [](const std::string& a, const std::string& b) {
      return a.size() > b.size() && a.compare(0, b.size(), b) == 0 && a[b.size()] == '.';
    };
    auto parent = [](const std::string& a) { return a.substr(0, a.rfind('.')); };
    // The key in error, or a table holding it, or a key inside it, came from a --set: the last
    // --set of it is the one whose value was read.
    for (auto it = sets_.rbegin(); it != sets_.rend(); ++it) {
      const std::string set = parse_override(*it, "--set").key;
      if (k == set || under(k, set) || under(set, k))
        throw InputError(std::string(e.what()) + " (set by --set " + *it + ")", e.key());
    }
    // Else a key of the same table did: a rule between keys (a shape's flatness and its sphere
    // count), where the user's change is the other key.
    for (auto it = sets_.rbegin(); it != sets_.rend(); ++it) {
      const std::string set = parse_override(*it, "--set").key;
      if (k.find('.') != std::string::npos && parent(k) == parent(set))
        throw InputError(std::string(e.what()) + " (with --set " + *it + ")", e.key());
    }
    throw;
  }
}

SceneConfig load_scene(const std::string& path, const std::vector<std::string>& sets) {
  std::error_code ec;  // a path the system refuses (too long, ...) does not exist either
  if (!path.empty() && !std::filesystem::exists(path, ec))
    throw InputError(path + ": scene file does not exist" + (ec ? " (" + ec.message() + ")" : ""));
  SceneDoc doc(path);
  doc.apply_command_line(sets);
  return doc.config_after_command_line();
}

SceneConfig load_scene(const std::string& path, std::span<const Override> overrides) {
  const std::string file = path.empty() ? "<embedded>" : path;
  std::error_code ec;  // a path the system refuses (too long, ...) does not exist either
  if (!path.empty() && !std::filesystem::exists(path, ec))
    throw InputError(path + ": scene file does not exist" + (ec ? " (" + ec.message() + ")" : ""));
  SceneDoc doc(path);
  try {
    doc.apply(overrides, "--set");
  } catch (const InputError& e) {
    throw InputError(file + ": " + e.what());
  }
  return doc.config();
}

}  // namespace reposetwin::experiments
