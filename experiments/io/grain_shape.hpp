// Grain shapes of a scene's sample: multi-sphere templates and generated families, mixed by mass.
//
// Design note. A scene without shape keys is a sample of spheres, run exactly as it always was.
// With `[sample.shape]` (one shape) or `[[sample.shapes]]` (a mix), every grain is a rigid clump
// of spheres (sim/clump.hpp). A shape is either
//   kind = "template"   component `offsets` ([[x, y, z], ...]) and `radii`, as EDEM's
//                       multi-sphere templates, in any unit: the template is scaled so that
//                       its sieve size (below) is 1, so a template given in units of the
//                       grain's sieve size is used as written;
//   kind = "blocky"     a box of extents L x I x S with rounded edges, for angular, blocky
//                       rock: `elongation` L/I and `flatness` I/S as below and `angularity`
//                       in [0, 1), 1 - (edge radius) / (S/2); built of a grid of equal spheres
//                       (io/grain_shape.cpp says how many). Waste rock is mostly
//                       sub-angular, sub-discoidal and sub-prismoidal blocks (Nunoo et al. 2009,
//                       SME preprint 09-018, Questa mine rock piles; Linero et al. 2020, Slope
//                       Stability 2020: 667-676, slabs to sub-equant blocks of coarse mine waste);
//                       measure L, I, S on a few dozen of your grains and give their ratios;
//   kind = "generated"  a family with four parameters a user can reason about: `elongation`
//                       L/I >= 1 and `flatness` I/S >= 1 (Zingg's ratios of the principal
//                       extents), `spheres` (components) and `roundness` in (0, 1], the radius
//                       of the end components against the thickest (1: ends as round as the
//                       body is thick, a capsule; smaller: tapered, pointed ends). The spheres
//                       lie in one row along the long axis (flatness 1) or in two parallel rows
//                       (flatness > 1, an even number of spheres), with thickest radius S/2, the
//                       rows' centres at +-(I - S)/2 and each row's ends at +-L/2. For roundness
//                       1 the extents are L, I, S exactly; otherwise the thickest sphere is the
//                       middle one and the measured ratios (recorded with the nominal ones) are
//                       those of the body as built.
// Several shapes are mixed by `mass_fraction`, which must sum to 1.
//
// Sieve-size convention. A grain with principal extents L >= I >= S (its extents along its
// principal axes of inertia) passes a square sieve opening a when its intermediate extent does,
// I <= a: it can pass lengthwise, and its smaller cross-section, I x S, fits the opening's side.
// This is the long-standing reading of a sieve size as the intermediate (b) axis of a grain
// (Krumbein 1941, J. Sediment. Petrol. 11:64-72; Blott and Pye 2008, Sedimentology 55:31-63,
// who note that flat grains pass a little larger, by the opening's diagonal, which this
// convention ignores). So a clump of sieve size d is its unit template scaled by d, and the PSD
// sampler draws d (sim/psd.hpp, sample_psd_shapes) with the clump's true mass: the volume of
// the union of its spheres (sim/clump's mass properties) times d^3 times the density.
//
// The outlet. A grain passes a round outlet lengthwise when its cross-section about its long
// axis does: outlet_diameter is twice the largest distance of a component's surface from the
// long axis through the centre of mass (>= I; exactly 1 for a sphere, where it is the sphere's
// old rule d_max < W). A shape whose d_max grain would not pass is refused at parse time.
#pragma once

#include <string>
#include <vector>

#include "sim/clump.hpp"

namespace reposetwin::experiments {

// The strict TOML reader (toml_reader.hpp); declared here so that this header, included across
// experiments/, does not pull toml++ into every file that includes it.
class TableReader;

/// One grain shape of the sample, resolved to its unit template (sieve size 1).
struct GrainShape {
  std::string key;               // where it is in the scene: "sample.shape", "sample.shapes[k]"
  std::string name;              // as given, or "shape <k>"
  std::string kind;              // "template", "generated" or "blocky"
  double mass_fraction = 1.0;    // share of the sample's mass [-]
  // The generated family's nominal parameters (kind "generated"; 1 for a template).
  double elongation = 1.0, flatness = 1.0, roundness = 1.0;  // [-]
  double angularity = 0.0;  // kind "blocky": 1 - edge radius / (S/2), in [0, 1) [-]
  int spheres = 1;                                           // components [-]
  sim::ClumpTemplate unit;       // principal frame, sieve size 1 (lengths in sieve sizes)
  double longest = 1.0, intermediate = 1.0, shortest = 1.0;  // L, I (= 1), S [sieve sizes]
  double outlet_diameter = 1.0;  // smallest round outlet it passes lengthwise [sieve sizes]

  /// The volume of a grain of sieve size d divided by d^3 [-].
  double volume_per_cube() const { return unit.volume; }
  bool sphere() const { return unit.size() == 1; }
};

/// Principal extents of a template (in its principal frame), sorted L >= I >= S, and the index
/// of the long axis.
struct PrincipalExtents {
  double longest = 0.0, intermediate = 0.0, shortest = 0.0;  // [m]
  int long_axis = 0;
};
PrincipalExtents principal_extents(const sim::ClumpTemplate& t);

/// Twice the largest distance of a component's surface from the long axis through the centre
/// of mass [m] (design note: the outlet a grain passes lengthwise).
double outlet_diameter(const sim::ClumpTemplate& t);

/// Reads `[sample.shape]` or `[[sample.shapes]]` from the sample table (marking the key used);
/// returns no shapes (spheres) when neither is there. Throws InputError naming the file, the
/// key and the value for unknown keys, a radius that is not positive, a body in pieces, aspect
/// ratios below 1, a roundness outside (0, 1], a sphere count that cannot build the family, or
/// fractions that do not sum to 1.
std::vector<GrainShape> read_grain_shapes(TableReader& sample);

/// The outlet check: throws InputError naming the shape's key if a grain of sieve size d_max [m]
/// does not pass an outlet of diameter w [m].
void check_shapes_pass_outlet(const std::vector<GrainShape>& shapes, double d_max, double w,
                              const std::string& file);

}  // namespace reposetwin::experiments
