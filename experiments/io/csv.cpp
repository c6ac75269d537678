#include "experiments/io/csv.hpp"

#include <csv.h>

#include <fstream>
#include <memory>
#include <sstream>

#include "experiments/io/input_error.hpp"
#include "experiments/io/provenance.hpp"

namespace reposetwin::experiments {
namespace {

// libcsv's callbacks collect into this.
struct Collector {
  CsvTable table;
  std::vector<std::string> fields;
  int record_line = 0;  // the line the record being read starts on
};

void on_field(void* text, std::size_t len, void* data) {
  auto* c = static_cast<Collector*>(data);
  c->fields.emplace_back(text ? static_cast<const char*>(text) : "", text ? len : 0);
}

void on_record(int /*terminator*/, void* data) {
  auto* c = static_cast<Collector*>(data);
  if (c->table.header.empty() && c->table.header_line == 0) {
    c->table.header = std::move(c->fields);
    c->table.header_line = c->record_line;
  } else {
    c->table.rows.push_back({c->record_line, std::move(c->fields)});
  }
  c->fields.clear();
}

// Fields are kept as written: no character counts as padding to trim.
int no_space(unsigned char) { return 0; }

struct ParserFree {
  void operator()(csv_parser* p) const {
    csv_free(p);
    delete p;
  }
};

// A parse error for a person: the file, the line and what is wrong in CSV terms (libcsv's own
// text, "error parsing data while strict checking enabled", names neither).
std::string csv_problem(const std::string& where, int line, int error, bool open_quote) {
  const std::string why =
      open_quote ? "a quoted field is never closed (an unmatched \")"
      : error == CSV_EPARSE
          ? "a quote where CSV allows none (a \" inside an unquoted field, or text after a "
            "closing quote; a quote inside a field is written \"\")"
          : std::string(csv_strerror(error));
  return where + ":" + std::to_string(line) + ": " + why;
}

}  // namespace

CsvTable parse_csv(const std::string& text, const std::string& where) {
  std::unique_ptr<csv_parser, ParserFree> p(new csv_parser);
  if (csv_init(p.get(), CSV_STRICT | CSV_STRICT_FINI) != 0)
    throw std::runtime_error(where + ": cannot start the CSV parser");
  csv_set_space_func(p.get(), no_space);
  Collector c;
  // Comments are recognised line by line, so the parser is fed one line at a time; a line
  // continues a quoted field when an odd number of quotes came before it ("" keeps the parity).
  bool in_quotes = false;
  std::istringstream in(text);
  int line_no = 0;
  for (std::string line; std::getline(in, line);) {
    ++line_no;
    // A UTF-8 byte-order mark (spreadsheet exports write one) is not part of the first field.
    if (line_no == 1 && line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);
    if (!in_quotes) {
      const std::size_t first = line.find_first_not_of(" \t\r");
      if (first == std::string::npos) continue;  // a blank line, spaces only included
      if (line[first] == '#') {
        std::string comment = line.substr(first + 1);
        if (!comment.empty() && comment.back() == '\r') comment.pop_back();
        c.table.comments.push_back(std::move(comment));
        continue;
      }
      c.record_line = line_no;
    }
    for (char ch : line)
      if (ch == '"') in_quotes = !in_quotes;
    line += '\n';
    if (csv_parse(p.get(), line.data(), line.size(), on_field, on_record, &c) != line.size())
      throw InputError(csv_problem(where, line_no, csv_error(p.get()), false));
  }
  if (csv_fini(p.get(), on_field, on_record, &c) != 0)
    throw InputError(csv_problem(where, c.record_line, csv_error(p.get()), in_quotes));
  return c.table;
}

CsvTable read_csv_file(const std::string& path) {
  // read_file reads only a regular file: a pipe would wait for a writer that never comes.
  std::string text;
  try {
    text = read_file(path);
  } catch (const std::exception& e) {
    throw InputError(std::string(e.what()) + " (a CSV file)");
  }
  return parse_csv(text, path);
}

}  // namespace reposetwin::experiments
