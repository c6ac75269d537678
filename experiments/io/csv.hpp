// CSV files: the one reader of the project's comma-separated data (the paper's tables, measured
// lab data).
//
// Design note. Quoting, escaped quotes ("" inside a quoted field), fields spanning lines and the
// CR / LF / CRLF record ends are RFC 4180's rules, and Debian's libcsv implements them (strict
// mode: a stray quote or an unterminated quoted field is an error, not silently read). What this
// wrapper adds is only what our files need beyond RFC 4180: lines whose first non-blank character
// is '#' (outside a quoted field) are comments, kept in order so a table's notes can be quoted;
// blank lines (spaces only included) are skipped; a UTF-8 byte-order mark at the start (which
// spreadsheet exports write) is dropped; the first record is the header; every record keeps the line it
// starts on for error messages. Fields are kept as written (no trimming): what a column means,
// and how many fields a row must have, is the caller's business.
#pragma once

#include <string>
#include <vector>

namespace reposetwin::experiments {

/// One data record of a CSV file.
struct CsvRecord {
  int line = 0;                     // line the record starts on (1-based)
  std::vector<std::string> fields;  // as written, quotes removed
};

/// A CSV file: its comment lines, header and data records.
struct CsvTable {
  std::vector<std::string> comments;  // text after the '#' of each comment line, in order
  std::vector<std::string> header;    // the first record; empty if the file has none
  int header_line = 0;
  std::vector<CsvRecord> rows;
};

/// Parses CSV text; `where` names it in errors. Throws InputError ("where:line: ...") for a
/// malformed quote or an unterminated quoted field.
CsvTable parse_csv(const std::string& text, const std::string& where);

/// Reads and parses a CSV file. Throws InputError naming the file when it cannot be read or is
/// malformed.
CsvTable read_csv_file(const std::string& path);

}  // namespace reposetwin::experiments
