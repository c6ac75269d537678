// Tests of the sieve-table file reader: good files (ours and the shipped defaults) parse into the
// values written in them; every kind of bad file gives an error naming the file, field and value.
#include "experiments/io/psd_file.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/toml_tables.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

namespace reposetwin::experiments {
namespace {

namespace fs = std::filesystem;

// Writes `text` to a fresh file in the test's temporary folder and returns its path.
std::string write_temp(const std::string& name, const std::string& text) {
  const fs::path dir = fs::temp_directory_path() / "reposetwin_psd_file_test";
  fs::create_directories(dir);
  const fs::path path = dir / name;
  std::ofstream(path) << text;
  return path.string();
}

const char* kGood = R"(
# a lab sheet
[psd]
name = "my rock"
provenance = "lab sheet 12"
sieve_mm = [0.5, 1, 2.0, 4.0]
passing_percent = [10, 30.0, 60, 100]
d_max_mm = 2.0
d_min_mm = 0.75
fines = "drop"
)";

TEST(PsdFile, GoodFileParsesIntoMetres) {
  const std::string path = write_temp("good.toml", kGood);
  const PsdFile f = read_psd_file(path);
  EXPECT_EQ(f.source, path);
  EXPECT_EQ(f.name, "my rock");
  EXPECT_EQ(f.provenance, "lab sheet 12");
  EXPECT_EQ(f.assumption, "");
  ASSERT_EQ(f.spec.table.size.size(), 4u);
  EXPECT_DOUBLE_EQ(f.spec.table.size[0], 0.5e-3);
  EXPECT_DOUBLE_EQ(f.spec.table.size[3], 4e-3);
  EXPECT_DOUBLE_EQ(f.spec.table.passing[1], 30.0);
  EXPECT_DOUBLE_EQ(f.spec.d_max, 2e-3);
  EXPECT_DOUBLE_EQ(f.spec.d_min, 0.75e-3);
  EXPECT_EQ(f.spec.fines, sim::FinesPolicy::kDrop);
  // Hand calculation: P(0.75 mm) = 20 %, P(2 mm) = 60 %: a third of the sample is below d_min.
  EXPECT_NEAR(sim::resolve_psd(f.spec).fines_fraction, 1.0 / 3.0, 1e-12);
}

TEST(PsdFile, EmbeddedTableInASceneFile) {
  const toml::table scene = toml::parse(R"(
[run]
seed = 3
[psd]
sieve_mm = [1.0, 2.0]
passing_percent = [0, 100]
)");
  const PsdFile f = parse_psd_table(*scene["psd"].as_table(), "scene.toml");
  EXPECT_EQ(f.source, "scene.toml");
  EXPECT_EQ(f.spec.fines, sim::FinesPolicy::kRenormalise);
  EXPECT_DOUBLE_EQ(f.spec.table.size[1], 2e-3);
  EXPECT_EQ(f.spec.d_max, 0.0);  // default: the largest sieve
}

// The shipped defaults: a scalped Fuller-Talbot curve P = 100 (d/d_max)^0.5 with d_min = d_max/2.
TEST(PsdFile, ShippedDefaultsParseAndFollowTheirDeclaredCurve) {
  const struct {
    const char* file;
    double d_max_mm;
  } cases[] = {{"dmax_2mm.toml", 2.0},
               {"dmax_3p35mm.toml", 3.35},
               {"dmax_5mm.toml", 5.0},
               {"dmax_8mm.toml", 8.0},
               {"dmax_70mm.toml", 70.0}};
  for (const auto& c : cases) {
    SCOPED_TRACE(c.file);
    const PsdFile f = read_psd_file(std::string(REPOSETWIN_SOURCE_DIR) + "/data/psd/" + c.file);
    EXPECT_NE(f.provenance.find("not measured"), std::string::npos);
    EXPECT_FALSE(f.assumption.empty());
    EXPECT_NEAR(f.spec.d_max, c.d_max_mm * 1e-3, 1e-12);
    EXPECT_NEAR(f.spec.d_min, 0.5 * c.d_max_mm * 1e-3, 1e-12);
    const auto& t = f.spec.table;
    for (std::size_t i = 0; i < t.size.size(); ++i) {
      EXPECT_NEAR(t.passing[i], 100.0 * std::sqrt(t.size[i] / f.spec.d_max), 0.006) << i;
    }
    // Fines below d_max/2: close to the curve's 1/sqrt(2) (the table is linear between sieves).
    EXPECT_NEAR(sim::resolve_psd(f.spec).fines_fraction, std::sqrt(0.5), 0.01);
  }
}

// Reads `text` as a file and expects an invalid_argument whose message has all `parts`.
void expect_error(const std::string& name, const std::string& text,
                  std::initializer_list<std::string> parts) {
  const std::string path = write_temp(name, text);
  try {
    read_psd_file(path);
    ADD_FAILURE() << name << ": no exception";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path), std::string::npos) << what;
    for (const auto& p : parts) EXPECT_NE(what.find(p), std::string::npos) << p << " in " << what;
  }
}

TEST(PsdFile, BadFilesNameFileFieldAndValue) {
  expect_error("unknown_key.toml", R"([psd]
sieve_mm = [1.0, 2.0]
passing_percent = [0, 100]
dmax_mm = 2.0
)",
               {"dmax_mm", "unknown key", "2.0"});
  expect_error("wrong_type.toml", R"([psd]
sieve_mm = [1.0, 2.0]
passing_percent = [0, 100]
d_max_mm = "2"
)",
               {"d_max_mm", "'2'", "must be a number"});
  expect_error("wrong_item.toml", R"([psd]
sieve_mm = [1.0, "two"]
passing_percent = [0, 100]
)",
               {"sieve_mm[1]", "'two'"});
  expect_error("not_array.toml", R"([psd]
sieve_mm = 1.0
passing_percent = [0, 100]
)",
               {"sieve_mm", "must be an array"});
  expect_error("missing.toml", R"([psd]
passing_percent = [0, 100]
)",
               {"sieve_mm", "missing"});
  expect_error("not_monotone.toml", R"([psd]
sieve_mm = [0.5, 1.0, 2.0]
passing_percent = [40, 30, 100]
)",
               {"passing_percent", "percent passing[1] = 30"});
  expect_error("not_100.toml", R"([psd]
sieve_mm = [0.5, 1.0, 2.0]
passing_percent = [10, 30, 95]
)",
               {"passing_percent", "95", "100"});
  expect_error("negative.toml", R"([psd]
sieve_mm = [-0.5, 1.0, 2.0]
passing_percent = [10, 30, 100]
)",
               {"sieve_mm", "-0.5 mm"});
  expect_error("d_max_above.toml", R"([psd]
sieve_mm = [0.5, 1.0, 2.0]
passing_percent = [10, 30, 100]
d_max_mm = 3
)",
               {"d_max_mm", "3 mm"});
  expect_error("bad_fines.toml", R"([psd]
sieve_mm = [0.5, 1.0, 2.0]
passing_percent = [10, 30, 100]
fines = "keep"
)",
               {"fines", "'keep'"});
  expect_error("top_level.toml", R"(extra = 1
[psd]
sieve_mm = [0.5, 1.0, 2.0]
passing_percent = [10, 30, 100]
)",
               {"extra", "unknown top-level key"});
  // An integer beyond 2^53 where a number is expected is read by its size (toml++'s
  // value<double>() gives nothing for it, and a dereference read garbage that passed on one
  // machine): a fraction of 2^63 - 1 is refused as out of range, naming the key.
  for (const char* huge : {"9223372036854775807", "-9223372036854775808"})
    expect_error("huge_fraction.toml", std::string(R"([psd]
sieve_mm = [0.5, 1.0, 2.0]
passing_percent = [10, 30, 100]
interval_sd_fraction = )") + huge + "\n",
                 {"psd.interval_sd_fraction", huge, "must lie in (0, 1]"});
  expect_error("huge_size.toml", R"([psd]
sieve_mm = [0.5, 1.0, 9007199254740993]
passing_percent = [10, 30, 100]
)",
               {"sieve_mm[2]"});
}

TEST(PsdFile, SyntaxErrorAndMissingFileNameTheFile) {
  const std::string path = write_temp("syntax.toml", "[psd\nsieve_mm = [1, 2]\n");
  try {
    read_psd_file(path);
    ADD_FAILURE() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path + ":1:"), std::string::npos) << e.what();
  }
  EXPECT_THROW(read_psd_file("/nonexistent/psd.toml"), InputError);
}

}  // namespace
}  // namespace reposetwin::experiments
