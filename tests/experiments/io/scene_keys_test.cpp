// The scene-key reference is complete: every key the parser reads (recorded while it parses
// scenes that use every table, a funnel and a cylinder, an inline sieve table and a file) and
// every key the sieve-table reader allows, and the same for the grain-shape reader under
// [sample.shape] and [[sample.shapes]], is in scene_keys(), and every key there is one the parser
// reads.
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

// The keys a reader allows in the table that `anchor` opens, from its own message for an unknown
// key put there ("... allowed keys: a, b" or "... allowed: a, b"), each as `prefix` + key.
std::set<std::string> keys_allowed(std::string text, const std::string& anchor,
                                   const std::string& marker, const std::string& prefix) {
  text.insert(text.find(anchor) + anchor.size(), "not_a_key = 1\n");
  std::string msg;
  try {
    parse_scene_text(text, "probe.toml");
  } catch (const InputError& e) {
    msg = e.what();
  }
  const auto at = msg.find(marker);
  EXPECT_NE(at, std::string::npos) << msg;
  std::set<std::string> keys;
  if (at == std::string::npos) return keys;
  std::string list = msg.substr(at + marker.size()) + ",";
  for (std::size_t start = 0, end; (end = list.find(',', start)) != std::string::npos;
       start = end + 1) {
    std::string k = list.substr(start, end - start);
    k.erase(0, k.find_first_not_of(' '));
    if (!k.empty()) keys.insert(prefix + k);
  }
  return keys;
}

std::set<std::string> psd_keys_allowed() {
  return keys_allowed(embedded_quick_scene(), "[sample.psd]\n", "allowed keys: ", "sample.psd.");
}

// Grain shapes: one template and one generated family, as [sample.shape] and as a mix.
constexpr const char* kTemplateShape =
    "kind = \"template\"\nname = \"dumbbell\"\nmass_fraction = 1.0\n"
    "offsets = [[-0.5, 0.0, 0.0], [0.5, 0.0, 0.0]]\nradii = [0.6, 0.6]\n";
constexpr const char* kGeneratedShape =
    "kind = \"generated\"\nname = \"rod\"\nelongation = 1.5\nflatness = 1.2\n"
    "spheres = 6\nroundness = 0.8\n";

std::string with_shapes(const std::string& shapes) { return embedded_quick_scene() + shapes; }

std::string one_shape(const char* shape) {
  return with_shapes("[sample.shape]\n" + std::string(shape));
}

std::string mixed_shapes() {
  return with_shapes("[[sample.shapes]]\n" + std::string(kTemplateShape) +
                     "\n[[sample.shapes]]\nmass_fraction = 0.0\n" + kGeneratedShape);
}

// The keys the shape reader allows, as [sample.shape] and as the k-th of [[sample.shapes]].
std::set<std::string> shape_keys_allowed() {
  std::set<std::string> keys =
      keys_allowed(one_shape(kGeneratedShape), "[sample.shape]\n", "allowed: ", "sample.shape.");
  for (const std::string& k : keys_allowed(mixed_shapes(), "[[sample.shapes]]\n", "allowed: ",
                                           "sample.shapes[<k>]."))
    keys.insert(k);
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
  // The quick scene again with each kind of grain shape, alone and in a mix (the template's
  // offsets are read as a raw array, so the shape reader's allowed keys are taken too).
  for (const std::string& text :
       {one_shape(kTemplateShape), one_shape(kGeneratedShape), mixed_shapes()})
    record_reads(text, "<embedded>", raw);
  std::set<std::string> keys = reference_form(raw);
  for (const std::string& k : psd_keys_allowed()) keys.insert(k);
  for (const std::string& k : shape_keys_allowed()) keys.insert(k);
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
    // A table, or an array of them, is named by the keys inside it.
    if (k.type == "table" || k.type == "array of tables") continue;
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
  EXPECT_EQ(scene_key_pattern("sample.shapes[12].elongation"), "sample.shapes[<k>].elongation");
  EXPECT_EQ(scene_key_pattern("sample.shapes.0.spheres"), "sample.shapes[<k>].spheres");
  EXPECT_EQ(scene_key_pattern("sample.shape.spheres"), "sample.shape.spheres");
  EXPECT_EQ(scene_key_pattern("sample.shapes"), "sample.shapes");
}

// The shape keys are in the reference with the reader's defaults and ranges, and the reader
// refuses what the reference says is out of range.
TEST(SceneKeys, TablesAScenesCanHaveAreKnown) {
  for (const char* t : {"sample", "sample.shape", "sample.psd", "output", "contacts",
                        "contacts.rock-plate", "materials.steel", "sample.shapes.1"})
    EXPECT_TRUE(is_scene_table(t)) << t;
  // A key is not a table, [[sample.shapes]] is an array of tables, and no scene has the others.
  for (const char* t : {"sample.mass_kg", "sample.shapes", "rolling", "rolling.spring",
                        "sample.shap", "contacts.rock-plate.friction"})
    EXPECT_FALSE(is_scene_table(t)) << t;
}

TEST(SceneKeys, ShapeKeysCarryDefaultsAndRanges) {
  std::set<std::string> seen;
  for (const SceneKey& k : scene_keys()) {
    if (k.key.rfind("sample.shape", 0) != 0) continue;
    seen.insert(k.key);
    if (k.key == "sample.shape.elongation" || k.key == "sample.shapes[<k>].flatness") {
      EXPECT_EQ(k.default_text, "1");
      EXPECT_NE(k.meaning.find(">= 1"), std::string::npos) << k.meaning;
    }
    if (k.key == "sample.shape.roundness") {
      EXPECT_NE(k.meaning.find("(0, 1]"), std::string::npos) << k.meaning;
    }
    if (k.key == "sample.shape.mass_fraction") {
      EXPECT_EQ(k.default_text, "1");
    }
    if (k.key == "sample.shapes[<k>].mass_fraction") {
      EXPECT_NE(k.default_text.find("required"), std::string::npos);
    }
  }
  for (const char* key : {"sample.shape", "sample.shape.kind", "sample.shape.offsets",
                          "sample.shape.radii", "sample.shape.spheres", "sample.shapes",
                          "sample.shapes[<k>].kind", "sample.shapes[<k>].roundness"})
    EXPECT_TRUE(seen.count(key)) << key;
  const std::string md = scene_keys_markdown();
  EXPECT_NE(md.find("| `sample.shape.elongation` | number | 1 | - |"), std::string::npos);
  EXPECT_NE(md.find("| `sample.shapes[<k>].spheres` | integer | required (generated) |"),
            std::string::npos);
  std::string below = one_shape(kGeneratedShape);
  below.replace(below.find("elongation = 1.5"), 16, "elongation = 0.9");
  EXPECT_THROW(parse_scene_text(below, "probe.toml"), InputError);
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
