// The one reader of numbers and seeds a person writes (io/numbers.hpp), as a table: every
// spelling that is a plain decimal or a seed is read exactly, every other refused, and the
// readers of sheets (a PSD sheet here) refuse what it refuses, naming the file, line and text.
#include "experiments/io/numbers.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include "../../support/scratch.hpp"
#include "experiments/io/files.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/psd_file.hpp"

namespace reposetwin::experiments {
namespace {

TEST(Numbers, APlainDecimalIsReadExactlyAndNothingElseIs) {
  const std::vector<std::pair<const char*, double>> good = {
      {"0", 0.0},     {"12", 12.0},
      {"-3.5", -3.5}, {"+2", 2.0},
      {".5", 0.5},    {"5.", 5.0},
      {"1e-3", 1e-3}, {"2.5E+2", 250.0},
      {"0.1", 0.1},   {"1.7976931348623157e308", 1.7976931348623157e308}};
  for (const auto& [text, value] : good) {
    const std::optional<double> v = parse_plain_decimal(text);
    ASSERT_TRUE(v) << text;
    EXPECT_EQ(*v, value) << text;
  }
  for (const char* bad :
       {"",    " ",     "0x1A",   "0X10",  "0x1p3", "inf", "-inf",  "Infinity", "nan",
        "NaN", "1e999", "-1e999", "12abc", "1,5",   " 1",  "1 ",    "1e",       "e5",
        ".",   "-",     "+-1",    "1..2",  "1e5.5", "١٢",  "1_000", "--1",      "0b101"})
    EXPECT_FALSE(parse_plain_decimal(bad)) << "\"" << bad << "\"";
  try {
    plain_decimal("0x1A", "sheet.csv:3, column mass_g");
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("sheet.csv:3, column mass_g: \"0x1A\" is not a number "
                                         "(a plain decimal is expected"),
              std::string::npos)
        << e.what();
  }
}

TEST(Numbers, SeedsAreExactIntegersInRangeEachOnce) {
  EXPECT_EQ(parse_seed("0"), 0u);
  EXPECT_EQ(parse_seed("9007199254740993"), 9007199254740993ull);  // 2^53 + 1: not via double
  EXPECT_EQ(parse_seed("9223372036854775807"), kMaxSeed);
  for (const char* bad : {"", "-1", "+1", "1.0", "1e3", "0x10", " 1", "1 ", "9223372036854775808",
                          "18446744073709551616", "nan", "1,2"})
    EXPECT_FALSE(parse_seed(bad)) << "\"" << bad << "\"";
  // Two seeds a double would merge stay two.
  EXPECT_EQ(parse_seed_list("9007199254740992,9007199254740993", "--seeds"),
            (std::vector<std::uint64_t>{9007199254740992ull, 9007199254740993ull}));
  struct Bad {
    const char* list;
    const char* says;
  };
  for (const Bad& b : std::vector<Bad>{{"1,1", "seed 1 is given twice"},
                                       {"3,1,2,3", "seed 3 is given twice"},
                                       {"1,,2", "\"\" is not a seed"},
                                       {"1,2.5", "\"2.5\" is not a seed"},
                                       {"1,-2", "\"-2\" is not a seed"},
                                       {"", "\"\" is not a seed"},
                                       {"1,", "\"\" is not a seed"}}) {
    try {
      parse_seed_list(b.list, "--seeds");
      ADD_FAILURE() << b.list;
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind(std::string("--seeds ") + b.list + ":", 0), 0u) << what;
      EXPECT_NE(what.find(b.says), std::string::npos) << what;
    }
  }
}

TEST(Numbers, ScalesAndTolerancesAreFiniteAndPositive) {
  EXPECT_EQ(positive_finite(0.25, "--mm-per-px"), 0.25);
  for (double bad : std::initializer_list<double>{0.0, -1.0, NAN, INFINITY, -INFINITY}) {
    try {
      positive_finite(bad, "--mm-per-px");
      ADD_FAILURE() << bad;
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).rfind("--mm-per-px = ", 0), 0u) << e.what();
      EXPECT_NE(std::string(e.what()).find("must be a finite number > 0"), std::string::npos);
    }
  }
}

TEST(Numbers, RepeatedPhotosAreRefusedByContentUnderAnyName) {
  const auto d = test_support::temp_dir("numbers_repeated_photos");
  for (const auto& [name, text] : std::vector<std::pair<const char*, const char*>>{
           {"a.png", "first"}, {"b.png", "second"}, {"copy_of_a.png", "first"}})
    std::ofstream(d / name) << text;
  EXPECT_NO_THROW(refuse_repeated_contents({(d / "a.png").string(), (d / "b.png").string()}, "x"));
  try {
    refuse_repeated_contents(
        {(d / "a.png").string(), (d / "b.png").string(), (d / "copy_of_a.png").string()}, "--side");
    ADD_FAILURE();
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("--side: "), std::string::npos) << what;
    EXPECT_NE(what.find("copy_of_a.png is the same image as"), std::string::npos) << what;
  }
}

TEST(Numbers, ASieveSheetRefusesWhatTheReaderRefuses) {
  const auto d = test_support::temp_dir("numbers_psd_sheet");
  for (const char* bad : {"0x10", "inf", "nan", "1e999"}) {
    const auto file = d / "sieve.csv";
    std::ofstream(file) << "sieve_mm,passing_percent\n1.0,0\n" << bad << ",50\n8.0,100\n";
    try {
      read_psd_file(file.string());
      ADD_FAILURE() << bad;
    } catch (const std::exception& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("sieve.csv:3"), std::string::npos) << what;
      EXPECT_NE(what.find(std::string("\"") + bad + "\""), std::string::npos) << what;
      EXPECT_NE(what.find("a plain decimal is expected"), std::string::npos) << what;
    }
  }
}

}  // namespace
}  // namespace reposetwin::experiments
