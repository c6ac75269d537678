// suggest: how far a typed name is from a known one, for "did you mean" in error messages
// (misspelt scene keys and tables, misspelt subcommands).
//
// Design note. Levenshtein distance over bytes, in one row of the table: short names only (keys,
// commands), so its O(|a| |b|) is nothing; no Debian package offers it for C++ without pulling
// in a much larger library.
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

}  // namespace reposetwin::experiments
