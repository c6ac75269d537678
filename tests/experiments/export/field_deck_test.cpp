// The field deck (`export --field dump`) is the lab deck's writer with a free dump in place of the
// pile test: the same material block line for line, the calibrated mu_r, LIGGGHTS' decomposition
// for N ranks, a ground plane and a release cylinder inside the domain, and a time step that is
// the twin's Rayleigh fraction of the scaled smallest grain's Rayleigh time (closed form). A dump
// the calibration cannot speak for (a pile a few grains high) or a bad value is an InputError
// naming the option and the value.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "../../support/tiny_scene.hpp"
#include "experiments/export/liggghts_deck.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/scene.hpp"
#include "sim/model.hpp"
#include "sim/psd.hpp"

namespace reposetwin::experiments {
namespace {

bool has(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// The tiny scene at the calibrated mu_r 0.297 (its grains, container and plate are all rock).
SceneConfig calibrated_tiny() {
  std::string text = test_support::kTinyScene;
  const std::string from = "rolling_friction = 0.3";
  text.replace(text.find(from), from.size(), "rolling_friction = 0.297");
  return parse_scene_text(text, "tiny.toml");
}

struct Calibrated {
  CalibratedMaterial material;
  DeckCalibration deck;
  Calibrated() {
    material.scene = "tiny.toml";
    material.keys = {"contacts.rock-rock.rolling_friction"};
    material.mu_r = 0.297;
    material.mu_r_lo = 0.258;
    material.mu_r_hi = 0.339;
    material.target_deg = 31.5;
    material.angle = "image";
    deck.material = &material;
    deck.file = "cal1/calibration.json";
    deck.deck_values = {{material.keys.front(), 0.297}};
  }
};

LiggghtsDeck field_deck(const SceneConfig& s, const FieldDumpSettings& f,
                        const DeckCalibration* cal = nullptr) {
  LiggghtsDeckSettings settings;
  settings.field_dump = &f;
  settings.calibration = cal;
  return liggghts_deck(s, settings);
}

// The whitespace-separated words of the first line of `text` that starts with `prefix`.
std::vector<double> numbers_after(const std::string& text, const std::string& prefix) {
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind(prefix, 0) != 0) continue;
    std::istringstream words(line.substr(prefix.size()));
    std::vector<double> v;
    for (double x; words >> x;) v.push_back(x);
    return v;
  }
  ADD_FAILURE() << "no line starts with '" << prefix << "'";
  return {};
}

// The lines of the material block: what the field must carry exactly as the lab does.
std::vector<std::string> material_lines(const std::string& deck) {
  std::vector<std::string> out;
  std::istringstream lines(deck);
  for (std::string line; std::getline(lines, line);)
    if (line.rfind("fix m", 0) == 0 || line.rfind("pair_style", 0) == 0 ||
        line.rfind("soft_particles", 0) == 0 || line.rfind("fix gravi", 0) == 0 ||
        line.rfind("fix plate", 0) == 0)
      out.push_back(line);
  return out;
}

std::string refusal(const SceneConfig& s, const FieldDumpSettings& f,
                    const DeckCalibration* cal = nullptr) {
  try {
    field_deck(s, f, cal);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(FieldDeck, CarriesTheCalibratedMaterialAsTheLabDeckDoes) {
  const SceneConfig s = calibrated_tiny();
  const Calibrated cal;
  LiggghtsDeckSettings lab_settings;
  lab_settings.calibration = &cal.deck;
  const LiggghtsDeck lab = liggghts_deck(s, lab_settings);
  const LiggghtsDeck field = field_deck(s, FieldDumpSettings{}, &cal.deck);
  EXPECT_EQ(field.input_name, "in.dump");
  EXPECT_TRUE(has(field.input, "coefficientRollingFriction peratomtypepair 3 0.297 0.297"))
      << field.input;
  EXPECT_TRUE(has(field.input, "# calibrated: mu_r 0.297 (95% 0.258 to 0.339)"));
  // One writer: E, nu, e, mu_s, mu_r per pair, the law, gravity and the ground line for line.
  EXPECT_EQ(material_lines(field.input), material_lines(lab.input));
  EXPECT_EQ(material_lines(field.input).size(), 9u);
  // At S = 1 the time step is the lab's.
  EXPECT_EQ(numbers_after(field.input, "timestep "), numbers_after(lab.input, "timestep "));
  // No container: no mesh, no STL, no lift; the notes carry the calibration and the scaling.
  EXPECT_FALSE(has(field.input, "mesh/surface"));
  EXPECT_FALSE(has(field.input, "move/mesh"));
  EXPECT_TRUE(field.funnel_stl.empty());
  EXPECT_TRUE(has(field.notes, "mu_r = 0.297, 95% interval 0.258 to 0.339")) << field.notes;
  EXPECT_TRUE(has(field.notes, "## What is scaled and how")) << field.notes;
  EXPECT_TRUE(has(field.scaling, "rolling mu_r (epsd2, R*)")) << field.scaling;
  EXPECT_TRUE(has(field.input, "write_dump all custom final.dump id type x y z radius"));
}

TEST(FieldDeck, WritesTheDecompositionForNRanks) {
  const SceneConfig s = calibrated_tiny();
  FieldDumpSettings f;
  EXPECT_TRUE(has(field_deck(s, f).input, "\nprocessors * * 1\n"));
  f.ranks = 2;
  const LiggghtsDeck two = field_deck(s, f);
  EXPECT_TRUE(has(two.input, "\nprocessors 2 1 1\n")) << two.input;
  EXPECT_TRUE(has(two.input, "# Run: mpirun -np 2 liggghts -in in.dump"));
  // A ground twice as wide as long: six ranks as 3 x 2, the subdomains closest to square.
  f.ranks = 6;
  f.width = 0.6;
  EXPECT_TRUE(has(field_deck(s, f).input, "\nprocessors 3 2 1\n"));
  f.ranks = 7;
  EXPECT_TRUE(has(field_deck(s, f).input, "\nprocessors 7 1 1\n"));
}

TEST(FieldDeck, GroundAndReleaseLieInsideTheDomainAboveThePile) {
  const SceneConfig s = calibrated_tiny();
  const Calibrated cal;
  const FieldDumpSettings f;
  const LiggghtsDeck d = field_deck(s, f, &cal.deck);
  EXPECT_TRUE(has(d.input,
                  "fix plate all wall/gran model hertz tangential history "
                  "rolling_friction epsd2 primitive type 3 zplane 0.0"));
  const std::vector<double> box = numbers_after(d.input, "region domain block ");
  ASSERT_EQ(box.size(), 6u);
  EXPECT_DOUBLE_EQ(box[0], -0.5 * f.width);
  EXPECT_DOUBLE_EQ(box[3], 0.5 * f.length);
  EXPECT_LT(box[4], 0.0);  // the ground z = 0 inside
  // region release cylinder z cx cy r zlo zhi
  const std::vector<double> c = numbers_after(d.input, "region release cylinder z ");
  ASSERT_EQ(c.size(), 5u);
  EXPECT_LE(std::abs(c[0]) + c[2], box[1]);
  EXPECT_LE(std::abs(c[1]) + c[2], box[3]);
  EXPECT_DOUBLE_EQ(c[3], f.release_height);
  EXPECT_LT(c[4], box[5]);
  const FieldScaling x = field_scaling(s, f, &cal.deck);
  EXPECT_GT(c[3], x.pile_height);  // released above the expected pile's top
  EXPECT_LE(1.25 * x.pile_diameter, std::min(f.width, f.length));
  EXPECT_TRUE(x.angle_calibrated);
  EXPECT_DOUBLE_EQ(x.angle_deg, 31.5);
  EXPECT_GE(x.grains_high, kMinGrainsHigh);
  // Grains fall from the cylinder's top onto the expected pile's top: the lift test saw no such
  // impacts, and the deck says so.
  EXPECT_NEAR(x.impact_speed, std::sqrt(2.0 * 9.81 * (c[4] - x.pile_height)), 1e-9);
  EXPECT_TRUE(std::any_of(x.warnings.begin(), x.warnings.end(), [](const std::string& w) {
    return has(w, "grains fall onto the pile at about");
  }));
  EXPECT_TRUE(has(d.scaling, "fall onto the pile")) << d.scaling;
  EXPECT_TRUE(has(d.input, "insert/rate/region seed"));
  EXPECT_TRUE(has(d.input, " mass 0.3 massrate 0.3 insert_every "));
}

// dt = rayleigh_fraction x T_R(S r_min) with T_R = pi R sqrt(rho/G) / (0.1631 nu + 0.8766): the
// tiny scene's grains, container and plate are one rock at the softened E, so one closed form.
TEST(FieldDeck, TimeStepIsTheRayleighFractionOfTheScaledSmallestGrain) {
  const SceneConfig s = calibrated_tiny();
  const double r_min = 0.5 * sim::resolve_psd(s.psd.spec).d_min;
  const double e = s.settings.softened_youngs_modulus, nu = 0.19, rho = 2760.0;
  for (const double scale : {1.0, 2.0}) {
    FieldDumpSettings f;
    f.size_scale = scale;
    f.mass = 0.3 * scale * scale * scale;  // the same pile in grains
    f.rate = f.mass;
    f.width = f.length = 0.3 * scale;
    f.release_height = 0.1 * scale;
    const LiggghtsDeck d = field_deck(s, f);
    const double radius = scale * r_min;
    const double t_r = std::numbers::pi * radius * std::sqrt(rho / (e / (2.0 * (1.0 + nu)))) /
                       (0.1631 * nu + 0.8766);
    const std::vector<double> dt = numbers_after(d.input, "timestep ");
    ASSERT_EQ(dt.size(), 1u);
    EXPECT_NEAR(dt[0], s.settings.rayleigh_fraction * t_r, 1e-9 * dt[0]) << "S " << scale;
    // The grains are the PSD's middle sizes times S: the first interval, 3.0 to 3.5 mm.
    const std::size_t at = d.input.find("fix pts1 all particletemplate/sphere ");
    ASSERT_NE(at, std::string::npos);
    const std::size_t r = d.input.find("radius constant ", at);
    ASSERT_NE(r, std::string::npos);
    EXPECT_NEAR(std::stod(d.input.substr(r + 16, 20)), scale * 0.25 * (3.0e-3 + 3.5e-3), 1e-12);
  }
}

TEST(FieldDeck, RefusesAPileTooFewGrainsHighInNumbers) {
  const SceneConfig s = calibrated_tiny();
  FieldDumpSettings f;
  f.size_scale = 4.0;
  const std::string coarse = refusal(s, f);
  EXPECT_TRUE(has(coarse, "--size-scale 4: ")) << coarse;
  EXPECT_TRUE(has(coarse, "grains high (mass-mean grain")) << coarse;
  EXPECT_TRUE(has(coarse, "Give --size-scale at most")) << coarse;
  f.size_scale = 1.0;
  f.mass = 0.01;
  const std::string small = refusal(s, f);
  EXPECT_TRUE(has(small, "--dump-mass-kg 0.01: ")) << small;
  EXPECT_TRUE(has(small, "fewer than 10 grains high")) << small;
}

TEST(FieldDeck, RefusesABadOptionNamingItAndItsValue) {
  const SceneConfig s = calibrated_tiny();
  auto with = [&](auto set) {
    FieldDumpSettings f;
    set(f);
    return refusal(s, f);
  };
  EXPECT_TRUE(has(with([](FieldDumpSettings& f) { f.rate = -1; }),
                  "--dump-rate-kg-s -1: must be "
                  "a positive number"));
  EXPECT_TRUE(has(with([](FieldDumpSettings& f) { f.size_scale = 0; }), "--size-scale 0: "));
  EXPECT_TRUE(has(with([](FieldDumpSettings& f) { f.ranks = -2; }), "--ranks -2: "));
  EXPECT_TRUE(has(with([](FieldDumpSettings& f) { f.width = 0.05; }), "--domain-width-m 0.05: "));
  EXPECT_TRUE(
      has(with([](FieldDumpSettings& f) { f.release_height = 0.02; }), "--dump-height-m 0.02: "));
  EXPECT_TRUE(has(with([](FieldDumpSettings& f) { f.release_radius = 0.001; }),
                  "--release-radius-m 0.001: cannot take 0.3 kg/s"));
}

TEST(FieldDeck, WarnsOfACoarseGrainingAboveTheStatedFactorAndATallPile) {
  const SceneConfig s = calibrated_tiny();
  FieldDumpSettings f;
  f.size_scale = 4.0;
  f.mass = 0.3 * 64.0;
  f.rate = f.mass;
  f.width = f.length = 1.2;
  f.release_height = 0.4;
  const FieldScaling coarse = field_scaling(s, f, nullptr);
  ASSERT_FALSE(coarse.warnings.empty());
  EXPECT_TRUE(has(coarse.warnings.front(), "--size-scale 4 is above 3")) << coarse.warnings.front();
  // A 50-tonne dump at the lab's soft E: the base overlap far above the lab pile's.
  FieldDumpSettings tall;
  tall.mass = 5e4;
  tall.rate = 100.0;
  tall.size_scale = 20.0;
  tall.width = tall.length = 60.0;
  tall.release_height = 20.0;
  const FieldScaling t = field_scaling(s, tall, nullptr);
  EXPECT_GT(t.overlap, 2.0 * t.overlap_lab);
  EXPECT_TRUE(std::any_of(t.warnings.begin(), t.warnings.end(), [](const std::string& w) {
    return has(w, "the soft stiffness the calibration used is strained");
  }));
}

}  // namespace
}  // namespace reposetwin::experiments
