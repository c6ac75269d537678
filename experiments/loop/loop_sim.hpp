// The loop's simulations: pile runs of lab tests with extra overrides and seeds, photographed
// through a chosen camera, cached on disk and run on the campaign pool.
//
// Design note. Every simulated quantity of the loop (baseline grid, predictions, fingerprints,
// refits, synthetic datasets) is a pour of one lab test's scene with a few extra overrides and a
// seed, photographed and measured by vision: a request to the pile service
// (campaign/pile_service.hpp), whose store is the loop's cache. SimCache turns the loop's
// request (a lab test, extra overrides, a seed, an ImageVariant) into the service's PileRequest
// and its PileOutcome back into the loop's units (mm). A killed loop therefore resumes where it
// stopped and nothing is ever computed twice, also across datasets that share conditions, and a
// calibration that poured the same piles into the same store has poured them for the loop.
// Measurement effects (camera height, lens distortion) only add photographs of piles that
// already exist.
//
// A photograph is taken by the true camera (ImageVariant: height, distortion, distance, noise)
// and measured with the camera the lab declares (level with the plate and undistorted unless
// declared otherwise), which is how a lab's unknown camera elevation or lens distortion biases
// its measured H, D and angle. When the lab's photos come with camera sidecars, its declared
// cameras are the twin's (ImageVariant::lab_cameras): like for like, the twin's pile is
// photographed from the lab's pose, through its lens, at its resolution, not framed by the
// pile's size.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "camera/camera.hpp"
#include "experiments/campaign/pile_service.hpp"
#include "experiments/loop/loop_data.hpp"
#include "experiments/photos/photographs.hpp"

namespace reposetwin::experiments {

/// How the loop photographs a simulated pile, as measurement effects: the true camera against
/// the declared one. photo_settings() turns it into the one photo pipeline's PhotoSettings, the
/// record the pile service keys a photograph by. Its defaults are the loop's (960 x 720, 2 side
/// views; a campaign's are PhotoSettings' own, 1920 x 1080, 4 views).
struct ImageVariant {
  int width_px = 960;              // [px]
  int height_px = 720;             // [px]
  int side_views = 2;              // azimuths over 180 degrees [-]
  double distance_radii = 12.0;    // camera distance in pile radii [-]
  double camera_height_m = 0.0;    // true camera height above the plate [m]
  double k1 = 0.0;                 // true lens radial distortion [-]
  bool aim_at_axis_foot = false;   // true camera pitched down at the axis foot (a person's
                                   // hold), not level; the measurement still assumes level
  double declared_height_m = 0.0;  // camera height the measurement assumes [m]
  double declared_k1 = 0.0;        // distortion the measurement assumes [-]
  double noise_sd = 0.0;           // Gaussian image noise, grey levels (0-255) [-]
  std::uint64_t noise_seed = 1;    // seed of the noise and of the particle tint
  bool keep_photos = false;        // write the PNGs and their declared-camera sidecars
  bool keep_overlays = false;      // write each measured view's overlay PNG (stem.measured.png)
  // The lab's declared side cameras (its photos' sidecars, LabTest::cameras): when given, the
  // twin photographs its pile with exactly these, one view each (the same pose, lens,
  // resolution and distortion), and width_px, height_px, side_views and distance_radii do not
  // apply. The measurement effects then act on them: the true camera is a lab camera raised by
  // camera_height_m - declared_height_m, its k1 changed by k1 - declared_k1, while the
  // measurement assumes the lab camera as declared. Empty: the twin frames its own cameras.
  std::vector<camera::Camera> lab_cameras;
  // Whether make_request takes a test's declared cameras into lab_cameras (reposetwin loop
  // --own-cameras: false, the twin frames its own; the synthetic loop tests, whose premise is a
  // lab camera other than the loop's). It only decides lab_cameras.
  bool use_lab_cameras = true;
};

/// One simulation request: a lab test's scene with extra overrides and a seed, photographed.
struct SimRequest {
  const LabTest* test = nullptr;                              // conditions and base scene
  std::vector<std::pair<std::string, std::string>> extra;     // dotted key -> TOML value text
  std::uint64_t seed = 1;                                     // scene.seed
  ImageVariant image;                                         // photograph settings
};

/// What one simulation gave.
struct SimOutcome {
  bool pile = false;          // a pile formed and was measured (else the angle is 0, H, D 0)
  std::string no_pile;        // when pile is false and a pile formed: why its photographs
                              // could not be measured (too small for every view)
  double angle_deg = 0.0;     // vision atan(2H/D), mean over the side views [deg]
  double flank_deg = 0.0;     // vision flank-line angle, mean over the side views [deg]; NaN
                              // for a photograph cached by a version that did not record it
  double height_mm = 0.0;     // vision H [mm]
  double diameter_mm = 0.0;   // vision D [mm]
  // Vision crest width, mean over the side views [mm]; NaN for a photograph cached by a version
  // that did not record it.
  double crest_mm = std::numeric_limits<double>::quiet_NaN();
  double positions_angle_deg = 0.0;  // atan(2H/D) from particle positions [deg]
  std::string sim_dir;        // the pile's folder in the store (its run in sim_dir/run)
  std::string image_dir;      // the photograph's folder
  nlohmann::json views;       // the photograph's views as measured (photograph_pile's record)
  nlohmann::json provenance;  // the run's provenance (scene, seed, dt, softened E, version)
  std::uint64_t seed = 0;     // the seed of the pour that gave this outcome
  int clogged_pours = 0;      // earlier pours of the request that formed no pile (repeated)
};

/// Settings of the cache and pool.
struct SimCacheSettings {
  int workers = 2;        // concurrent runs [-]
  bool progress = false;  // progress lines on stderr
};

/// The loop's view of the pile service (see the design note).
class SimCache {
 public:
  SimCache(std::string dir, SimCacheSettings settings = {});
  /// Runs (or finds) every request and returns the outcomes in order. Throws std::runtime_error
  /// naming the failed runs.
  std::vector<SimOutcome> run(const std::vector<SimRequest>& requests);
  /// Pile runs and photographs this object has started (not found finished).
  int simulations_started() const { return service_.simulations_started(); }
  int photos_started() const { return service_.photos_started(); }
  const std::string& dir() const { return service_.dir(); }

 private:
  PileService service_;
};

/// The service's request for a loop request: the test's scene, its resolved overrides, the
/// seed, and the photograph photo_settings(request.image) gives.
PileRequest pile_request(const SimRequest& request);

/// The loop's record of the service's answer (mm, the views as the loop reads them).
SimOutcome sim_outcome(const PileOutcome& outcome, const ImageVariant& image, std::uint64_t seed);

/// Seed of the a-th repeat of a pour with seed s: s + a * kRepourSeedStride (far from the seed
/// lists a user types, so a repeat never lands on another request's seed).
constexpr std::uint64_t kRepourSeedStride = 1000000;

/// Runs `requests` with `run` (SimCache::run, or a stand-in in tests) and repeats every pour
/// that formed no pile with the next repeat seed, up to `max_pours` pours in all, as a lab
/// repeats a pour whose funnel jammed. Each outcome records the seed of its pour and how many
/// pours before it formed no pile; one that still formed none after max_pours is returned as it
/// is (pile false), for the caller to decide. Throws std::invalid_argument for max_pours < 1.
std::vector<SimOutcome> run_repouring(
    const std::vector<SimRequest>& requests, int max_pours,
    const std::function<std::vector<SimOutcome>(const std::vector<SimRequest>&)>& run);

/// The order in which a surface's tests are poured, as groups poured one after the other, from
/// each test's count of jammed pours so far (`jams`). A surface fails whole when one test forms
/// no pile at some grid point (a refit trial then steps back), so the tests that jammed before
/// are poured first and alone: a trial their outlet ends is known before the other tests' piles,
/// often the costly ones, are run. One group of every test (in order) when none or all jammed.
/// The order changes no result: each pour's seed is its own.
std::vector<std::vector<std::size_t>> pour_groups(const std::vector<int>& jams);

/// The resolved overrides of a request: the test's, then the extra ones (later keys win), as
/// "key=value" strings in application order.
std::vector<std::string> resolved_overrides(const SimRequest& request);

/// The photo pipeline's settings for `variant` (photos/photographs.hpp): the true cameras (the
/// twin's framing, or the lab's with the measurement effects applied) and the declared ones the
/// measurement assumes; no top view, no scale bar, no overlays. Throws InputError for
/// side_views < 1.
PhotoSettings photo_settings(const ImageVariant& variant);

/// Photographs a pile (centres, radii, material ids) with `variant` through the one photo
/// pipeline (photos/photographs.hpp: the true camera renders, the declared camera measures; a
/// view vision cannot measure is recorded and the others count) and returns the loop's record
/// {angle_deg, flank_deg, height_mm, diameter_mm, crest_width_mm, views[...]}, or
/// {error, views[...]} if no view could be measured (a pile of a few spheres). Writes the
/// photographs and their declared-camera sidecars into `out_dir` when keep_photos is set
/// (names side_az000.png / .json ...; each view's "photo"), and each measured view's overlay
/// when keep_overlays is set (side_az000.measured.png; the view's "overlay"). Uses OSMesa: call it
/// in a worker, not before forking.
nlohmann::json photograph_pile(const std::vector<Eigen::Vector3d>& positions,
                               const std::vector<double>& radii, const std::vector<int>& materials,
                               const ImageVariant& variant, const std::string& out_dir);

}  // namespace reposetwin::experiments
