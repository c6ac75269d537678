// The scene-key reference is complete: every key the parser reads (recorded while it parses
// scenes that use every table, a funnel and a cylinder, an inline sieve table and a file) and
// every key the sieve-table reader allows is in scene_keys(), and every key there is one the
// parser reads.
#include "experiments/io/scene_keys.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <set>
#include <string>

#include "experiments/io/input_error.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/io/scene.hpp"
#include "experiments/io/toml_reader.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;

const fs::path kSource = REPOSETWIN_SOURCE_DIR;

// Every key (as written, dotted) the parser looks up while parsing `text`, added to `raw`.
void record_reads(const std::string& text, const std::string& file, std::set<std::string>& raw) {
  record_keys(&raw);
  try {
    parse_scene_text(text, file);
  } catch (...) {
    record_keys(nullptr);
    throw;
  }
  record_keys(nullptr);
}

// The reference form of recorded keys. A table is a key too, but is named by the keys inside it
// ("scene" by "scene.name"), so it is left out.
std::set<std::string> reference_form(const std::set<std::string>& raw) {
  std::set<std::string> keys;
  for (const std::string& k : raw) {
    const auto next = raw.upper_bound(k);
    if (next == raw.end() || next->rfind(k + ".", 0) != 0) keys.insert(scene_key_pattern(k));
  }
  return keys;
}

// The keys the sieve-table reader allows, from its own message for an unknown key.
std::set<std::string> psd_keys_allowed() {
  std::string text = embedded_quick_scene();
  const std::string anchor = "[sample.psd]\n";
  text.insert(text.find(anchor) + anchor.size(), "not_a_key = 1\n");
  std::string msg;
  try {
    parse_scene_text(text, "probe.toml");
  } catch (const InputError& e) {
    msg = e.what();
  }
  const std::string marker = "allowed keys: ";
  const auto at = msg.find(marker);
  EXPECT_NE(at, std::string::npos) << msg;
  std::set<std::string> keys;
  std::string list = msg.substr(at + marker.size()) + ",";
  for (std::size_t start = 0, end; (end = list.find(',', start)) != std::string::npos;
       start = end + 1) {
    std::string k = list.substr(start, end - start);
    k.erase(0, k.find_first_not_of(' '));
    if (!k.empty()) keys.insert("sample.psd." + k);
  }
  return keys;
}

std::set<std::string> reference() {
  std::set<std::string> keys;
  for (const SceneKey& k : scene_keys()) keys.insert(k.key);
  return keys;
}

std::set<std::string> all_keys_the_parser_reads() {
  // The quick scene with every optional table and key present, and a cylinder scene read from
  // its file with a psd_file (the paper's column).
  std::string quick = embedded_quick_scene() + "\n[measure]\n";
  const std::string sample = "mass_kg = 0.05\n";
  quick.insert(quick.find(sample) + sample.size(), "d_min_mm = 2.5\nd_max_mm = 5.0\n");
  std::set<std::string> raw;
  record_reads(quick, "<embedded>", raw);
  const fs::path column = kSource / "data/scenes/paper/fig18_column_dmax70.toml";
  record_reads(experiments::read_file(column.string()), column.string(), raw);
  std::set<std::string> keys = reference_form(raw);
  for (const std::string& k : psd_keys_allowed()) keys.insert(k);
  return keys;
}

TEST(SceneKeys, EveryKeyTheParserReadsIsInTheReference) {
  const std::set<std::string> ref = reference();
  const std::set<std::string> read = all_keys_the_parser_reads();
  EXPECT_GT(read.size(), 50u);
  for (const std::string& k : read)
    EXPECT_TRUE(ref.count(k)) << k << " is read by the parser but missing from scene_keys() "
                              << "(experiments/io/scene_keys.cpp)";
}

TEST(SceneKeys, EveryKeyInTheReferenceIsReadByTheParser) {
  std::set<std::string> read = all_keys_the_parser_reads();
  for (const SceneKey& k : scene_keys()) {
    if (k.type == "table") continue;  // named by the keys inside it
    EXPECT_TRUE(read.count(k.key)) << k.key << " is in the reference but the parser never reads it";
    EXPECT_FALSE(k.type.empty() || k.default_text.empty() || k.unit.empty() || k.meaning.empty())
        << k.key;
  }
}

TEST(SceneKeys, PatternsNameTheTablesOfUserChosenNames) {
  EXPECT_EQ(scene_key_pattern("materials.rock.poisson_ratio"), "materials.<name>.poisson_ratio");
  EXPECT_EQ(scene_key_pattern("contacts.rock-steel.friction"), "contacts.<a>-<b>.friction");
  EXPECT_EQ(scene_key_pattern("materials.rock"), "materials.<name>");
  EXPECT_EQ(scene_key_pattern("procedure.max_time_s"), "procedure.max_time_s");
}

TEST(SceneKeys, DefaultsAreTheParsersDefaults) {
  for (const SceneKey& k : scene_keys()) {
    if (k.key == "procedure.lift_speed_m_s") {
      EXPECT_EQ(k.default_text, "0.01");
    }
    if (k.key == "output.checkpoint_interval_s") {
      EXPECT_EQ(k.default_text, "120");
    }
    if (k.key == "scene.name") {
      EXPECT_EQ(k.default_text, "required");
    }
  }
  const std::string md = scene_keys_markdown();
  EXPECT_NE(md.find("| `output.checkpoint_interval_s` | number | 120 | s |"), std::string::npos);
}

}  // namespace
}  // namespace reposetwin::experiments
