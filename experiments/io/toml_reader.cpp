#include "experiments/io/toml_reader.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

#include "experiments/io/format.hpp"
#include "experiments/io/suggest.hpp"

namespace reposetwin::experiments {
namespace {
thread_local std::set<std::string>* g_recorded_keys = nullptr;
}  // namespace

void record_keys(std::set<std::string>* keys) { g_recorded_keys = keys; }

std::string show_node(const toml::node& node) {
  std::ostringstream os;
  if (const auto* s = node.as_string()) {
    os << '"' << s->get() << '"';
  } else if (const auto* t = node.as_table()) {
    os << "{table with " << t->size() << " keys}";
  } else if (const auto* f = node.as_floating_point()) {
    os << shortest_text(f->get());  // as typed ("1e-30"), not to seventeen digits
  } else {
    node.visit([&os](const auto& v) { os << v; });
  }
  return os.str();
}

std::optional<double> number_of(const toml::node& node) {
  if (const auto* f = node.as_floating_point()) return f->get();
  if (const auto* i = node.as_integer()) return static_cast<double>(i->get());
  return std::nullopt;
}

toml::table parse_toml(const std::string& text, const std::string& file) {
  try {
    return toml::parse(text, file);
  } catch (const toml::parse_error& e) {
    std::ostringstream os;
    os << file << ":" << e.source().begin.line << ":" << e.source().begin.column << ": "
       << e.description();
    throw InputError(os.str());
  }
}

TableReader::TableReader(const toml::table& table, std::string file, std::string path)
    : table_(&table), file_(std::move(file)), path_(std::move(path)) {}

std::string TableReader::where(const std::string& key) const {
  return path_.empty() ? key : path_ + "." + key;
}

void TableReader::fail(const std::string& key, const std::string& what) const {
  throw InputError(file_ + ": " + where(key) + " " + what, where(key));
}

bool TableReader::has(const std::string& key) const { return table_->contains(key); }

const toml::node* TableReader::get(const std::string& key) {
  used_.insert(key);
  if (g_recorded_keys) g_recorded_keys->insert(where(key));
  return table_->get(key);
}

double TableReader::number(const std::string& key, double fallback) {
  const toml::node* n = get(key);
  if (!n) return fallback;
  if (const std::optional<double> v = number_of(*n)) {
    // TOML has inf and nan; no key of ours means either, and a nan passes every `<` check.
    if (!std::isfinite(*v)) fail(key, "= " + show_node(*n) + " must be a finite number");
    return *v;
  }
  fail(key, "must be a number, got " + show_node(*n));
}

double TableReader::number(const std::string& key) {
  if (!has(key)) fail(key, "is required");
  return number(key, 0.0);
}

std::int64_t TableReader::integer(const std::string& key, std::int64_t fallback) {
  const toml::node* n = get(key);
  if (!n) return fallback;
  if (n->is_integer()) return *n->value<std::int64_t>();
  fail(key, "must be an integer, got " + show_node(*n));
}

bool TableReader::boolean(const std::string& key, bool fallback) {
  const toml::node* n = get(key);
  if (!n) return fallback;
  if (n->is_boolean()) return *n->value<bool>();
  fail(key, "must be true or false, got " + show_node(*n));
}

std::string TableReader::string(const std::string& key, const std::string& fallback) {
  const toml::node* n = get(key);
  if (!n) return fallback;
  if (n->is_string()) return *n->value<std::string>();
  fail(key, "must be a string, got " + show_node(*n));
}

std::string TableReader::string(const std::string& key) {
  if (!has(key)) fail(key, "is required");
  return string(key, "");
}

std::vector<double> TableReader::numbers(const std::string& key) {
  const toml::node* n = get(key);
  if (!n) fail(key, "is required");
  const toml::array* a = n->as_array();
  if (!a) fail(key, "must be an array of numbers, got " + show_node(*n));
  std::vector<double> out;
  for (std::size_t i = 0; i < a->size(); ++i) {
    const toml::node& item = *a->get(i);
    const std::optional<double> v = number_of(item);
    if (!v)
      fail(key + "[" + std::to_string(i) + "]", "must be a number, got " + show_node(item));
    if (!std::isfinite(*v))
      fail(key + "[" + std::to_string(i) + "]",
           "= " + show_node(item) + " must be a finite number");
    out.push_back(*v);
  }
  return out;
}

std::optional<TableReader> TableReader::table(const std::string& key, bool optional) {
  const toml::node* n = get(key);
  if (!n) {
    if (optional) return std::nullopt;
    fail(key, "is required (a table)");
  }
  const toml::table* t = n->as_table();
  if (!t) fail(key, "must be a table, got " + show_node(*n));
  return TableReader(*t, file_, where(key));
}

std::vector<std::string> TableReader::keys() const {
  std::vector<std::string> k;
  for (const auto& [key, node] : *table_) k.emplace_back(key.str());
  return k;
}

void TableReader::finish() const {
  // The keys this table's reader asked for are the ones it knows: a misspelling is near one.
  for (const auto& [key, node] : *table_) {
    const std::string k(key.str());
    if (!used_.count(k))
      fail(k, "is not a known key (value " + show_node(node) + ")" + did_you_mean(k, used_));
  }
}

void TableReader::known_keys(const std::set<std::string>& allowed) const {
  for (const auto& [key, node] : *table_) {
    const std::string k(key.str());
    if (allowed.count(k)) continue;
    std::string list;
    for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
    fail(k, "is an unknown key (value " + show_node(node) + ")" + did_you_mean(k, allowed) +
                " allowed: " + list);
  }
}

}  // namespace reposetwin::experiments
