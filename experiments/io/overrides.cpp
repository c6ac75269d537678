#include "experiments/io/overrides.hpp"

#include <algorithm>
#include <cctype>
#include <sstream>
#include <stdexcept>

#include "experiments/io/input_error.hpp"
#include "experiments/io/numbers.hpp"
#include "experiments/io/scene_keys.hpp"
#include "experiments/io/toml_edit.hpp"

namespace reposetwin::experiments {
namespace {

std::string where(std::string_view origin) {
  return origin.empty() ? std::string("override") : std::string(origin);
}

// Whether TOML reads `text` as an integer or a float.
bool is_toml_number(std::string_view text) {
  try {
    const toml::table t = toml::parse("v = " + std::string(text));
    const toml::node* v = t.get("v");
    return v != nullptr && (v->is_integer() || v->is_floating_point());
  } catch (const toml::parse_error&) {
    return false;
  }
}

bool is_inf_or_nan(std::string_view text) {
  if (!text.empty() && (text.front() == '+' || text.front() == '-')) text.remove_prefix(1);
  return text == "inf" || text == "nan";
}

bool is_index(const std::string& s) {
  if (s.empty() || s.size() > 9) return false;
  for (char c : s)
    if (!std::isdigit(static_cast<unsigned char>(c))) return false;
  return true;
}

// The type's name with its article ("an integer", "a string").
std::string type_name(toml::node_type t) {
  std::ostringstream os;
  os << t;
  const std::string name = os.str();
  return (std::string("aeiou").find(name.front()) != std::string::npos ? "an " : "a ") + name;
}

// A copy of `value`, converted to float when it is an integer replacing a float.
template <typename Sink>
void store(const toml::node& value, toml::node_type existing, Sink&& sink) {
  if (existing == toml::node_type::floating_point && value.is_integer()) {
    sink(toml::value<double>(static_cast<double>(value.as_integer()->get())));
    return;
  }
  value.visit([&](const auto& v) { sink(v); });
}

// A value keeps its type: a word where the scene has a number is a typo, not a new experiment.
std::string type_change(const toml::node& existing, const toml::node& value) {
  std::string why =
      "the scene has " + type_name(existing.type()) + " here, not " + type_name(value.type());
  if (value.is_string() && existing.is_number())
    why += " (a value that is not a number is read as a word)";
  return why;
}

}  // namespace

std::string toml_value_text(const toml::node& value) {
  std::ostringstream os;
  value.visit([&](const auto& v) { os << v; });
  return os.str();
}

std::vector<std::string> split_dotted_key(std::string_view dotted_key, std::string_view origin) {
  std::vector<std::string> parts;
  std::string cur;
  for (char c : dotted_key) {
    if (c == '.') {
      parts.push_back(cur);
      cur.clear();
    } else {
      cur.push_back(c);
    }
  }
  parts.push_back(cur);
  for (const auto& p : parts)
    if (p.empty())
      throw std::invalid_argument(where(origin) + ": override key '" + std::string(dotted_key) +
                                  "' is not a dotted key path (empty segment)");
  return parts;
}

void apply_override(toml::table& doc, std::string_view dotted_key, const toml::node& value,
                    std::string_view origin, MissingTables missing) {
  const auto parts = split_dotted_key(dotted_key, origin);
  const std::string key(dotted_key);
  auto fail = [&](const std::string& why) -> std::invalid_argument {
    return std::invalid_argument(where(origin) + ": override '" + key +
                                 "' = " + toml_value_text(value) + ": " + why);
  };

  toml::node* parent = &doc;
  std::string path;
  for (std::size_t i = 0; i + 1 < parts.size(); ++i) {
    const std::string& seg = parts[i];
    toml::node* next = nullptr;
    if (auto* t = parent->as_table()) {
      next = t->get(seg);
    } else if (auto* a = parent->as_array(); a && is_index(seg)) {
      const std::size_t idx = std::stoul(seg);
      if (idx >= a->size())
        throw fail("index " + seg + " is out of range for '" + path + "' (" +
                   std::to_string(a->size()) + " elements)");
      next = a->get(idx);
    }
    path += (path.empty() ? "" : ".") + seg;
    const bool create = missing == MissingTables::kCreate ||
                        (missing == MissingTables::kSceneTables && is_scene_table(path));
    if (next == nullptr && create && parent->is_table())
      next = parent->as_table()->insert_or_assign(seg, toml::table{}).first->second.as_table();
    if (next == nullptr)
      throw fail("'" + path + "' does not exist in the scene" +
                 (missing == MissingTables::kSceneTables
                      ? std::string(" and is not a table a scene has (reposetwin keys)")
                      : std::string()));
    if (!next->is_table() && !next->is_array())
      throw fail("'" + path + "' is " + type_name(next->type()) + ", not a table");
    parent = next;
  }

  const std::string& leaf = parts.back();
  if (auto* t = parent->as_table()) {
    // A sieve file set on a scene replaces the scene's own inline table, as a person means it,
    // whether the override comes from --set, a campaign or a lab's sieve sheet.
    if (key == "sample.psd_file") t->erase("psd");
    const toml::node* existing = t->get(leaf);
    if (existing == nullptr) {
      store(value, value.type(), [&](const auto& v) { t->insert_or_assign(leaf, v); });
      return;
    }
    const bool int_to_float = existing->is_floating_point() && value.is_integer();
    if (existing->type() != value.type() && !int_to_float)
      throw fail(type_change(*existing, value));
    store(value, existing->type(), [&](const auto& v) { t->insert_or_assign(leaf, v); });
    return;
  }
  auto* a = parent->as_array();
  if (a == nullptr || !is_index(leaf))
    throw fail("'" + path + "' is an array; '" + leaf + "' is not an index");
  const std::size_t idx = std::stoul(leaf);
  if (idx >= a->size())
    throw fail("index " + leaf + " is out of range for '" + path + "' (" +
               std::to_string(a->size()) + " elements)");
  const toml::node* existing = a->get(idx);
  const bool int_to_float = existing->is_floating_point() && value.is_integer();
  if (existing->type() != value.type() && !int_to_float) throw fail(type_change(*existing, value));
  store(value, existing->type(),
        [&](const auto& v) { a->replace(a->cbegin() + static_cast<std::ptrdiff_t>(idx), v); });
}

void apply_overrides(toml::table& doc, const toml::table& overrides, std::string_view origin) {
  // toml::table iterates in key order, which puts "a" before "a.b".
  for (const auto& [k, v] : overrides) apply_override(doc, k.str(), v, origin);
}

Override parse_override(std::string_view text, std::string_view origin) {
  const auto eq = text.find('=');
  if (eq == std::string_view::npos || eq == 0)
    throw InputError(where(origin) + " \"" + std::string(text) + "\": expected dotted.key=value");
  return {std::string(text.substr(0, eq)), std::string(text.substr(eq + 1))};
}

void apply_overrides(toml::table& doc, const std::vector<Override>& overrides,
                     std::string_view origin, MissingTables missing) {
  for (const Override& o : overrides) {
    toml::table value_doc;
    try {
      value_doc = toml::parse("v = " + o.value);
    } catch (const toml::parse_error& e) {
      throw InputError(where(origin) + " \"" + o.key + "=" + o.value +
                       "\": the value is not a TOML value (" + std::string(e.description()) + ")");
    }
    try {
      apply_override(doc, o.key, *value_doc.get("v"), origin, missing);
    } catch (const std::invalid_argument& e) {
      throw InputError(e.what());
    }
  }
}

Override typed_override(std::string key, std::string_view text, std::string_view origin) {
  if (text.empty()) throw InputError(where(origin) + " \"" + key + "=\": the value is empty");
  if (is_toml_value(text)) {
    // TOML reads 0x1A, 0o17, 0b101 and 1_000 as numbers; a person typing a value means a plain
    // decimal, so those spellings are refused here, once for --set and sheet columns alike.
    // inf and nan pass on to the scene's own checks, which name the key and its finite range.
    if (is_toml_number(text) && !parse_plain_decimal(text) && !is_inf_or_nan(text))
      throw InputError(where(origin) + " \"" + key + "=" + std::string(text) + "\": \"" +
                       std::string(text) +
                       "\" is not a plain decimal (digits, an optional point and exponent; no "
                       "hex, octal, binary or '_' separators)");
    return {std::move(key), std::string(text)};
  }
  // Text that starts like a TOML string, array or table but is not one is a typo in it; any
  // other text is a word.
  if (std::string_view("\"'[{").find(text.front()) != std::string_view::npos) {
    std::string why;
    try {
      (void)toml::parse("v = " + std::string(text));
    } catch (const toml::parse_error& e) {
      why = std::string(e.description());
    }
    throw InputError(where(origin) + " \"" + key + "=" + std::string(text) +
                     "\": the value is not a TOML value (" + why + ")");
  }
  return string_override(std::move(key), text);
}

Override number_override(std::string key, double v) {
  return {std::move(key), toml_value_text(toml::value<double>(v))};
}

Override string_override(std::string key, std::string_view text) {
  return {std::move(key), toml_value_text(toml::value<std::string>(std::string(text)))};
}

Override override_of(std::string key, const toml::node& value) {
  return {std::move(key), toml_value_text(value)};
}

bool is_toml_value(std::string_view text) {
  try {
    (void)toml::parse("v = " + std::string(text));
    return true;
  } catch (const toml::parse_error&) {
    return false;
  }
}

void set_override(std::vector<Override>& list, Override o) {
  auto it = std::lower_bound(list.begin(), list.end(), o.key,
                             [](const Override& a, const std::string& k) { return a.key < k; });
  if (it != list.end() && it->key == o.key) {
    it->value = std::move(o.value);
  } else {
    list.insert(it, std::move(o));
  }
}

nlohmann::json toml_to_json(const toml::node& n) {
  if (const auto* t = n.as_table()) {
    nlohmann::json j = nlohmann::json::object();
    for (const auto& [k, v] : *t) j[std::string(k.str())] = toml_to_json(v);
    return j;
  }
  if (const auto* a = n.as_array()) {
    nlohmann::json j = nlohmann::json::array();
    for (const auto& v : *a) j.push_back(toml_to_json(v));
    return j;
  }
  if (n.is_integer()) return n.as_integer()->get();
  if (n.is_floating_point()) return n.as_floating_point()->get();
  if (n.is_boolean()) return n.as_boolean()->get();
  if (n.is_string()) return n.as_string()->get();
  return toml_value_text(n);  // dates and times
}

nlohmann::json overrides_to_json(const std::vector<Override>& list) {
  nlohmann::json j = nlohmann::json::object();
  for (const Override& o : list) {
    const toml::table v = toml::parse("v = " + o.value);
    j[o.key] = toml_to_json(*v.get("v"));
  }
  return j;
}

}  // namespace reposetwin::experiments
