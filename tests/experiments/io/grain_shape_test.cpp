// Grain shapes as scene keys ([sample.shape], [[sample.shapes]]): templates and generated
// families resolve to unit templates with the stated sieve-size convention (intermediate
// extent 1), and every bad input is an InputError naming the file, the key and the value,
// before anything runs.
#include "experiments/io/grain_shape.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "../../support/tiny_scene.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/scene.hpp"

namespace reposetwin::experiments {
namespace {

const std::string kFile = "shape_scene.toml";

std::string with_outlet(std::string text, double w) {
  const std::string key = "bottom_diameter_m = 0.02";
  text.replace(text.find(key), key.size(), "bottom_diameter_m = " + std::to_string(w));
  return text;
}

SceneConfig parse(const std::string& shape_toml, double outlet = 0.02) {
  return parse_scene_text(with_outlet(test_support::kTinyScene, outlet) + shape_toml, kFile);
}

/// The message of the InputError that parsing throws ("" if none).
std::string error_of(const std::string& shape_toml, double outlet = 0.02) {
  try {
    parse(shape_toml, outlet);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

/// Expects an error that names the file and every one of `parts` (key, value).
void expect_error(const std::string& shape_toml, std::initializer_list<const char*> parts,
                  double outlet = 0.02) {
  const std::string e = error_of(shape_toml, outlet);
  ASSERT_FALSE(e.empty()) << shape_toml;
  EXPECT_NE(e.find(kFile), std::string::npos) << e;
  for (const char* p : parts) EXPECT_NE(e.find(p), std::string::npos) << "'" << p << "' in " << e;
}

TEST(GrainShape, NoShapeKeysMeanSpheres) {
  const SceneConfig s = parse("");
  EXPECT_TRUE(s.shapes.empty());
  EXPECT_EQ(grain_radius_range(s, 3e-3, 4e-3), (std::pair<double, double>{1.5e-3, 2e-3}));
}

// A rod of four equal spheres in a row, ends at +-L/2: its principal extents are L, I = S, and
// scaled to I = 1 the ratio L/I is the elongation asked for; its volume lies between the
// inscribed sphere's and the capsule's of the same length.
TEST(GrainShape, AGeneratedRodHasTheAskedElongationAtSieveSizeOne) {
  const SceneConfig s = parse(R"(
[sample.shape]
kind = "generated"
elongation = 1.5
spheres = 4
)");
  ASSERT_EQ(s.shapes.size(), 1u);
  const GrainShape& g = s.shapes[0];
  EXPECT_EQ(g.unit.size(), 4u);
  EXPECT_NEAR(g.longest, 1.5, 1e-12);
  EXPECT_NEAR(g.intermediate, 1.0, 1e-12);
  EXPECT_NEAR(g.shortest, 1.0, 1e-12);
  EXPECT_NEAR(g.outlet_diameter, 1.0, 1e-12);
  for (double r : g.unit.radii) EXPECT_NEAR(r, 0.5, 1e-12);
  const double sphere = std::numbers::pi / 6.0;
  const double capsule = sphere + std::numbers::pi * 0.25 * 0.5;
  EXPECT_GT(g.volume_per_cube(), sphere);
  EXPECT_LT(g.volume_per_cube(), capsule);
  EXPECT_DOUBLE_EQ(g.mass_fraction, 1.0);
  // The model's components span [d_min/2, d_max/2].
  EXPECT_NEAR(grain_radius_range(s, 3e-3, 4e-3).first, 1.5e-3, 1e-15);
}

TEST(GrainShape, AFlatFamilyHasBothRatiosAndRoundnessTapersTheEnds) {
  const SceneConfig s = parse(R"(
[[sample.shapes]]
name = "flat"
kind = "generated"
elongation = 1.2
flatness = 1.5
spheres = 6
mass_fraction = 0.25
[[sample.shapes]]
name = "spindle"
kind = "generated"
elongation = 2.0
spheres = 5
roundness = 0.5
mass_fraction = 0.75
)");
  ASSERT_EQ(s.shapes.size(), 2u);
  const GrainShape& flat = s.shapes[0];
  EXPECT_EQ(flat.key, "sample.shapes[0]");
  EXPECT_NEAR(flat.longest / flat.intermediate, 1.2, 1e-9);
  EXPECT_NEAR(flat.intermediate / flat.shortest, 1.5, 1e-9);
  const GrainShape& spindle = s.shapes[1];
  EXPECT_EQ(spindle.name, "spindle");
  EXPECT_NEAR(spindle.longest, 2.0, 1e-9);  // the middle sphere is the thickest: I = S = 1
  double r_min = 1, r_max = 0;
  for (double r : spindle.unit.radii) r_min = std::min(r_min, r), r_max = std::max(r_max, r);
  EXPECT_NEAR(r_min / r_max, 0.5, 1e-12);
}

// A template in any unit is scaled to its intermediate extent: a sphere of radius 7 becomes the
// sphere of diameter 1, and two overlapping spheres (radius 1, centres 1.5 apart) have
// L/I = 3.5/2 and the union's volume: two spheres less their lens, pi (4r + d)(2r - d)^2 / 12.
TEST(GrainShape, ATemplateIsScaledToItsIntermediateExtent) {
  const SceneConfig one = parse(R"(
[sample.shape]
kind = "template"
offsets = [[1.0, 2.0, 3.0]]
radii = [7.0]
)");
  ASSERT_TRUE(one.shapes[0].sphere());
  EXPECT_DOUBLE_EQ(one.shapes[0].unit.radii[0], 0.5);
  EXPECT_DOUBLE_EQ(one.shapes[0].volume_per_cube(), std::numbers::pi / 6.0);
  const SceneConfig two = parse(R"(
[sample.shape]
kind = "template"
offsets = [[0.0, 0.0, 0.0], [1.5, 0.0, 0.0]]
radii = [1.0, 1.0]
)");
  const double pi = std::numbers::pi;
  const double union_volume = 2.0 * 4.0 / 3.0 * pi - pi * 5.5 * 0.25 / 12.0;
  EXPECT_NEAR(two.shapes[0].longest, 1.75, 1e-12);
  EXPECT_NEAR(two.shapes[0].volume_per_cube(), union_volume / 8.0, 1e-6 * union_volume / 8.0);
}

TEST(GrainShape, BadTemplatesNameFileKeyAndValue) {
  expect_error("[sample.shape]\nkind = \"template\"\noffsets = [[0.0,0.0,0.0],[0.5,0.0,0.0]]\n"
               "radii = [0.5, 0.0]\n",
               {"sample.shape.radii[1]", "= 0", "positive"});
  expect_error("[sample.shape]\nkind = \"template\"\noffsets = [[0.0,0.0,0.0],[0.5,0.0,0.0]]\n"
               "radii = [-0.2, 0.5]\n",
               {"sample.shape.radii[0]", "= -0.2"});
  expect_error("[sample.shape]\nkind = \"template\"\noffsets = [[0.0,0.0,0.0],[3.0,0.0,0.0]]\n"
               "radii = [0.5, 0.5]\n",
               {"sample.shape.offsets", "in pieces", "component 1"});
  expect_error("[sample.shape]\nkind = \"template\"\noffsets = [[0.0,0.0]]\nradii = [0.5]\n",
               {"sample.shape.offsets[0]", "[x, y, z]"});
  expect_error("[sample.shape]\nkind = \"template\"\noffsets = [[0.0,0.0,0.0]]\n"
               "radii = [0.5, 0.5]\n",
               {"sample.shape.offsets", "1 points", "2 values"});
  expect_error("[sample.shape]\nkind = \"polyhedron\"\n", {"sample.shape.kind", "polyhedron"});
}

TEST(GrainShape, BadFamiliesNameFileKeyAndValue) {
  expect_error("[sample.shape]\nkind = \"generated\"\nelongation = 0.8\nspheres = 4\n",
               {"sample.shape.elongation", "= 0.8", "at least 1"});
  expect_error("[sample.shape]\nkind = \"generated\"\nflatness = 0.9\nspheres = 4\n",
               {"sample.shape.flatness", "= 0.9"});
  expect_error("[sample.shape]\nkind = \"generated\"\nroundness = 0.0\nspheres = 4\n",
               {"sample.shape.roundness", "= 0"});
  expect_error("[sample.shape]\nkind = \"generated\"\nflatness = 1.5\nspheres = 5\n",
               {"sample.shape.spheres", "= 5", "even"});
  expect_error("[sample.shape]\nkind = \"generated\"\nelongation = 1.5\nspheres = 1\n",
               {"sample.shape.spheres", "= 1"});
  // Rows farther apart than the spheres reach: flatness 3 makes two separate rods.
  expect_error("[sample.shape]\nkind = \"generated\"\nflatness = 3.0\nspheres = 4\n",
               {"sample.shape.spheres", "in pieces"});
  // A rod too long for its spheres: the message gives both ways out, the longest elongation
  // the spheres reach (n - 1 + roundness) and the sphere count the elongation needs, or that
  // none is enough.
  expect_error("[sample.shape]\nkind = \"generated\"\nelongation = 4.5\nspheres = 3\n",
               {"sample.shape.elongation", "= 4.5", "in pieces", "at most 3", "spheres = 5"});
  expect_error("[sample.shape]\nkind = \"generated\"\nelongation = 100.0\nspheres = 3\n",
               {"sample.shape.elongation", "at most 3", "64 spheres, the most, allow 64"});
  // A typo is refused by name, before the missing key it stood for.
  expect_error("[sample.shape]\nkind = \"generated\"\nelongaton = 1.5\nspheres = 4\n",
               {"sample.shape.elongaton"});
}

TEST(GrainShape, MixesMustSumToOneAndNameEachFraction) {
  const std::string two = R"(
[[sample.shapes]]
kind = "generated"
elongation = 1.5
spheres = 4
mass_fraction = 0.5
[[sample.shapes]]
kind = "generated"
elongation = 2.0
spheres = 4
mass_fraction = 0.4
)";
  expect_error(two, {"sample.shapes", "0.5 + 0.4", "sum to 0.9"});
  expect_error("[[sample.shapes]]\nkind = \"generated\"\nspheres = 1\n"
               "[[sample.shapes]]\nkind = \"generated\"\nspheres = 1\nmass_fraction = 1.0\n",
               {"sample.shapes[0].mass_fraction", "required"});
  expect_error("[sample.shape]\nkind = \"generated\"\nspheres = 1\n"
               "[[sample.shapes]]\nkind = \"generated\"\nspheres = 1\n",
               {"sample.shape", "both"});
  expect_error("[sample.shape]\nkind = \"generated\"\nspheres = 1\nmass_fraction = 0.5\n",
               {"sample.shape", "0.5", "sum to 0.5"});
}

// The blocky family: a rounded box L x I x S of equal spheres. Two closed forms: angularity 0
// on a cube is one sphere of diameter 1 (volume pi/6), and on a 1.5 x 1 x 1 box it is two
// spheres of radius 1/2 whose centres are 0.5 apart (a lens of two caps subtracted:
// V = 2 (4/3) pi r^3 - pi (4r + d)(2r - d)^2 / 12).
TEST(GrainShape, BlockyAtAngularityZeroIsSpheresOfHalfTheShortestExtent) {
  const SceneConfig one = parse("[sample.shape]\nkind = \"blocky\"\n");
  ASSERT_EQ(one.shapes[0].unit.size(), 1u);
  EXPECT_NEAR(one.shapes[0].volume_per_cube(), std::numbers::pi / 6.0, 1e-6);
  const SceneConfig two = parse("[sample.shape]\nkind = \"blocky\"\nelongation = 1.5\n");
  const GrainShape& g = two.shapes[0];
  ASSERT_EQ(g.unit.size(), 2u);
  const double r = 0.5, d = 0.5;
  const double lens = std::numbers::pi * (4 * r + d) * (2 * r - d) * (2 * r - d) / 12.0;
  EXPECT_NEAR(g.volume_per_cube(), 2.0 * 4.0 / 3.0 * std::numbers::pi * r * r * r - lens, 1e-5);
  EXPECT_NEAR(g.longest, 1.5, 1e-12);
  EXPECT_NEAR(g.shortest, 1.0, 1e-12);
}

// A sharp box at waste rock's ratios has the asked extents, its edge radius
// (1 - angularity) S / 2, a volume inside the box and inside the Minkowski rounded box its
// spheres' centres span (inner box a x b x c swept by a ball of radius r:
// abc + 2r(ab + bc + ca) + pi r^2 (a + b + c) + 4/3 pi r^3), and it fills more of the box as it
// grows sharper.
TEST(GrainShape, ABlockyBoxHasTheAskedRatiosAndSharpensWithAngularity) {
  auto box = [](double angularity) {
    return parse("[sample.shape]\nkind = \"blocky\"\nelongation = 1.4\nflatness = 1.6\n"
                 "angularity = " + std::to_string(angularity) + "\n").shapes[0];
  };
  const double L = 1.4, S = 1.0 / 1.6;
  double last = 0.0;
  for (double ang : {0.0, 0.25, 0.5}) {
    const GrainShape g = box(ang);
    EXPECT_EQ(g.kind, "blocky");
    EXPECT_NEAR(g.longest, L, 1e-9) << ang;
    EXPECT_NEAR(g.intermediate, 1.0, 1e-12) << ang;
    EXPECT_NEAR(g.shortest, S, 1e-9) << ang;
    const double r = 0.5 * (1.0 - ang) * S;
    for (double ri : g.unit.radii) EXPECT_NEAR(ri, r, 1e-9) << ang;
    const double a = L - 2 * r, b = 1.0 - 2 * r, c = S - 2 * r;
    const double rounded = a * b * c + 2 * r * (a * b + b * c + c * a) +
                           std::numbers::pi * r * r * (a + b + c) +
                           4.0 / 3.0 * std::numbers::pi * r * r * r;
    EXPECT_LT(g.volume_per_cube(), rounded) << ang;
    EXPECT_LE(rounded, L * S + 1e-12) << ang;
    EXPECT_GT(g.volume_per_cube(), last) << ang;
    last = g.volume_per_cube();
  }
  // The study's boxes (experiments/studies/pile_top_s4.toml): 8 corner spheres at 0.25, and
  // the prism 1.5 x 1 x 0.8 of 3 x 2 x 2.
  EXPECT_EQ(parse("[sample.shape]\nkind = \"blocky\"\nelongation = 1.2\nflatness = " +
                  std::to_string(1.0 / 0.85) + "\nangularity = 0.2470588235\n")
                .shapes[0].unit.size(), 8u);
  EXPECT_EQ(parse("[sample.shape]\nkind = \"blocky\"\nelongation = 1.5\nflatness = 1.25\n"
                  "angularity = 0.25\n").shapes[0].unit.size(), 12u);
}

TEST(GrainShape, BadBlockyNamesFileKeyAndValue) {
  expect_error("[sample.shape]\nkind = \"blocky\"\nangularity = 1.0\n",
               {"sample.shape.angularity", "= 1", "[0, 1)"});
  expect_error("[sample.shape]\nkind = \"blocky\"\nangularity = -0.1\n",
               {"sample.shape.angularity", "= -0.1"});
  expect_error("[sample.shape]\nkind = \"blocky\"\nangularity = nan\n",
               {"sample.shape.angularity", "nan"});
  expect_error("[sample.shape]\nkind = \"blocky\"\nelongation = 0.7\n",
               {"sample.shape.elongation", "= 0.7"});
  expect_error("[sample.shape]\nkind = \"blocky\"\nflatness = inf\n",
               {"sample.shape.flatness", "inf"});
  expect_error("[sample.shape]\nkind = \"blocky\"\nelongation = 3\nflatness = 2\n"
               "angularity = 0.9\n",
               {"sample.shape.angularity", "= 0.9", "at most 64"});
  expect_error("[sample.shape]\nkind = \"blocky\"\nspheres = 4\n", {"sample.shape.spheres"});
}

// An L of three spheres is wider across its long axis than its intermediate extent: a funnel
// that passes its sieve size d_max but not its cross-section refuses it, while spheres of the
// same PSD pass the same funnel.
TEST(GrainShape, AClumpTooWideForTheOutletIsRefused) {
  const std::string ell = R"(
[sample.shape]
name = "ell"
kind = "template"
offsets = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
radii = [0.6, 0.6, 0.6]
)";
  const double w = parse(ell).shapes[0].outlet_diameter;
  ASSERT_GT(w, 1.05);
  const double d_max = 4e-3, outlet = d_max * (1.0 + w) / 2.0;  // between d_max and w d_max
  EXPECT_EQ(error_of("", outlet), "");
  expect_error(ell, {"sample.shape", "ell", "does not pass the outlet",
                     "container.bottom_diameter_m"},
               outlet);
  EXPECT_EQ(error_of(ell, d_max * w * 1.01), "");
}

}  // namespace
}  // namespace reposetwin::experiments
