// Strict reading of TOML tables into plain structs.
//
// Every scene and campaign file is read through TableReader: each key is read with its type
// checked, and finish() rejects any key that was not read, so a typo is an error rather than a
// silently ignored setting. Every message names the file, the dotted key and the value. Numbers
// are finite: TOML's inf and nan mean nothing in any of our files, and a nan slips through every
// range check written as a comparison.
#pragma once

#include <toml++/toml.h>

#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "experiments/io/input_error.hpp"

namespace reposetwin::experiments {

class TableReader {
 public:
  /// `path` is the dotted path of this table in the file ("" for the root).
  TableReader(const toml::table& table, std::string file, std::string path = "");

  bool has(const std::string& key) const;
  /// A number (an integer reads as one); inf and nan are refused, naming the key.
  double number(const std::string& key, double fallback);
  double number(const std::string& key);  // required
  std::int64_t integer(const std::string& key, std::int64_t fallback);
  bool boolean(const std::string& key, bool fallback);
  std::string string(const std::string& key, const std::string& fallback);
  std::string string(const std::string& key);  // required
  std::vector<double> numbers(const std::string& key);
  /// A sub-table (required unless `optional`); nullopt if absent and optional.
  std::optional<TableReader> table(const std::string& key, bool optional = false);
  /// The keys of this table, in the file's (sorted) order.
  std::vector<std::string> keys() const;
  /// Marks a key as handled by someone else (for example a nested file reader).
  void mark_used(const std::string& key) { used_.insert(key); }
  const toml::table& raw() const { return *table_; }

  /// Throws InputError for the first key that was never read.
  void finish() const;
  /// Throws InputError for the first key not in `allowed`, listing the allowed ones. Called
  /// before reading, it names a misspelt key rather than the missing key it stood for.
  void known_keys(const std::set<std::string>& allowed) const;

  /// An error about `key` of this table.
  [[noreturn]] void fail(const std::string& key, const std::string& what) const;
  std::string where(const std::string& key) const;
  const std::string& file() const { return file_; }

 private:
  const toml::node* get(const std::string& key);
  const toml::table* table_;
  std::string file_;
  std::string path_;
  std::set<std::string> used_;
};

/// From now on, every key a TableReader on this thread looks up (dotted, as where() gives it)
/// is also added to `keys`, until called with nullptr: how the scene-key reference's test
/// (io/scene_keys.hpp) learns every key the parser reads.
void record_keys(std::set<std::string>* keys);

/// Parses TOML text; a syntax error becomes an InputError "file:line:column: description".
toml::table parse_toml(const std::string& text, const std::string& file);

/// The text of a TOML value for messages.
std::string show_node(const toml::node& node);

/// A TOML number as a double: a float as written, an integer rounded to the nearest double
/// (9223372036854775807 reads 9.2e18, so a range check refuses it by its size); nullopt for
/// anything else. Every number of our files is read through this: toml++'s value<double>()
/// gives nothing for an integer beyond 2^53, and a read that dereferenced that took whatever
/// the empty optional held (a huge integer for a fraction passed on one machine, not another).
std::optional<double> number_of(const toml::node& node);

}  // namespace reposetwin::experiments
