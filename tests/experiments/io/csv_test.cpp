// The one CSV reader: RFC 4180 quotes (through libcsv) plus our comment lines and header.
#include "experiments/io/csv.hpp"

#include <gtest/gtest.h>

#include <filesystem>

#include "experiments/io/input_error.hpp"
#include "experiments/io/provenance.hpp"

namespace reposetwin::experiments {
namespace {

TEST(Csv, QuotedFieldsKeepCommasQuotesAndNewlines) {
  const CsvTable t = parse_csv("a,b,c,d\nx,\"b,c\",\"d\"\"e\",\n\"two\nlines\",2,3,4\n", "t");
  ASSERT_EQ(t.header, (std::vector<std::string>{"a", "b", "c", "d"}));
  ASSERT_EQ(t.rows.size(), 2u);
  EXPECT_EQ(t.rows[0].fields, (std::vector<std::string>{"x", "b,c", "d\"e", ""}));
  EXPECT_EQ(t.rows[0].line, 2);
  EXPECT_EQ(t.rows[1].fields[0], "two\nlines");
  EXPECT_EQ(t.rows[1].line, 3);
}

TEST(Csv, CommentsBlankLinesAndLineEnds) {
  // A '#' line is a comment, kept; inside a quoted field it is data. CRLF ends a record like LF,
  // blank lines are skipped and fields keep their spaces.
  const CsvTable t =
      parse_csv("# note one\r\nk,v\r\n\r\n  # note two\n a ,\"x\n# not a comment\"\nlast,1", "t");
  EXPECT_EQ(t.comments, (std::vector<std::string>{" note one", " note two"}));
  EXPECT_EQ(t.header_line, 2);
  ASSERT_EQ(t.rows.size(), 2u);
  EXPECT_EQ(t.rows[0].fields, (std::vector<std::string>{" a ", "x\n# not a comment"}));
  EXPECT_EQ(t.rows[0].line, 5);
  EXPECT_EQ(t.rows[1].fields, (std::vector<std::string>{"last", "1"}));
}

TEST(Csv, MalformedQuotesAreErrorsWithTheLine) {
  try {
    parse_csv("a,b\nx,\"y\n", "f.csv");  // unterminated
    FAIL() << "expected an error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("f.csv:2: a quoted field is never closed"),
              std::string::npos)
        << e.what();
  }
  try {
    parse_csv("a,b\nx,y\"z\n", "f.csv");  // a quote inside an unquoted field
    FAIL() << "expected an error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("f.csv:2: a quote where CSV allows none"),
              std::string::npos)
        << e.what();
  }
  const CsvTable empty = parse_csv("# only a comment\n", "t");
  EXPECT_TRUE(empty.header.empty());
  EXPECT_THROW(read_csv_file("/nonexistent/dir/x.csv"), InputError);
}

TEST(Csv, ByteOrderMarkAndLinesOfSpaces) {
  const CsvTable t = parse_csv("\xEF\xBB\xBFid,v\r\n   \r\n\t\na,1\r\n", "t");
  ASSERT_EQ(t.header.size(), 2u);
  EXPECT_EQ(t.header[0], "id");  // the mark is not part of the first name
  ASSERT_EQ(t.rows.size(), 1u);
  EXPECT_EQ(t.rows[0].line, 4);
  EXPECT_EQ(t.rows[0].fields[1], "1");
}

TEST(Csv, ReadsAFile) {
  const auto p = std::filesystem::temp_directory_path() / "reposetwin_csv_test.csv";
  write_file_atomic(p.string(), "# c\nsample,mu_r\n1,0.15\n");
  const CsvTable t = read_csv_file(p.string());
  ASSERT_EQ(t.rows.size(), 1u);
  EXPECT_EQ(t.rows[0].fields[1], "0.15");
}

}  // namespace
}  // namespace reposetwin::experiments
