// suggest: how far a typed name is from a known one, for "did you mean" in error messages. Every
// strict reader names its nearest known name through did_you_mean(): the TOML readers (scene,
// campaign, sieve table), the JSON records (json_read.hpp's known_fields), the CSV sheets'
// columns, and the command line's subcommands and options.
//
// Design note. Levenshtein distance over bytes, in one row of the table: short names only (keys,
// commands), so its O(|a| |b|) is nothing; no Debian package offers it for C++ without pulling
// in a much larger library. A misspelling is a letter or two away (a third of a long name); a
// name farther off is something else, and a guess at it would mislead.
#pragma once

#include <algorithm>
#include <cstddef>
#include <string>
#include <vector>

namespace reposetwin::experiments {

/// The number of one-character insertions, deletions and substitutions turning `a` into `b`.
inline std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diag = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diag = up;
    }
  }
  return row[b.size()];
}

/// The name of `known` nearest to `word` when it is near enough to be a misspelling of it (at
/// most max(2, |word| / 3) edits), else empty. Ties go to the first in `known`'s order.
template <class Names>
std::string closest_name(const std::string& word, const Names& known) {
  std::string best;
  std::size_t best_d = std::string::npos;
  for (const auto& k : known) {
    const std::string name(k);
    if (name == word) continue;
    if (const std::size_t d = edit_distance(word, name); d < best_d) best_d = d, best = name;
  }
  return best_d <= std::max<std::size_t>(2, word.size() / 3) ? best : std::string();
}

/// "; did you mean NAME?" for the nearest name of `known` (closest_name), or "" when none is
/// near. `quote` goes around the name ("'" for a command, "\"" for a column, "" for a key).
template <class Names>
std::string did_you_mean(const std::string& word, const Names& known,
                         const std::string& quote = "") {
  const std::string best = closest_name(word, known);
  return best.empty() ? std::string() : "; did you mean " + quote + best + quote + "?";
}

}  // namespace reposetwin::experiments
