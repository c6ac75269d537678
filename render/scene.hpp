// scene: what the renderer draws, as plain data independent of the simulator.
//
// Design note. render/ must not know sim/: a run hands over sphere centres, radii and material
// ids (copied out of its particle arrays), and the lab fixtures (base plate, funnel or column,
// backdrop, scale reference) are small settings structs with lab-like defaults. Everything is in
// the world frame of camera/camera.hpp: metres, z up, plate top at z = 0, pile axis = z axis.
// The look (colours, scale reference geometry) follows the convention shared with vision/
// (notes/marker.md), so vision can find the plate line and the scale reference in our renders
// the same way it finds them in the lab's photographs.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <vector>

#include "camera/camera.hpp"

namespace reposetwin::render {

/// An 8-bit sRGB colour.
struct Rgb {
  std::uint8_t r = 0;
  std::uint8_t g = 0;
  std::uint8_t b = 0;
};

/// The square base plate, centred on the axis, top face at z = 0.
struct Plate {
  bool enabled = true;
  double half_size_m = 0.25;   // half the side of the square board [m]
  double thickness_m = 0.015;  // board thickness below z = 0 [m]
  Rgb color{70, 80, 95};       // dark blue-grey
  // A board's surface grain: a procedural, deterministic pattern (hashed value noise of the
  // world position, stretched along x like the fibres of a laminated board) that changes the
  // brightness by up to +-texture; 0 = a uniform board [-].
  double texture = 0.0;
  double texture_scale_m = 0.004;  // size of the pattern's features across the fibres [m]
};

/// An open axisymmetric shell about the z axis: a conical frustum (funnel) or a cylinder
/// (column, r_bottom_m == r_top_m). Drawn opaque and two-sided.
struct Shell {
  double z_bottom_m = 0.0;   // height of the lower rim [m]
  double z_top_m = 0.1;      // height of the upper rim [m]
  double r_bottom_m = 0.02;  // radius of the lower rim [m]
  double r_top_m = 0.05;     // radius of the upper rim [m]
  Rgb color{175, 178, 182};  // brushed steel grey
};

/// The backdrop behind the scene (lab backdrop paper); it fills every pixel nothing else covers.
/// A lab's backdrop paper is lit from one side and falls off away from the light: `gradient` is
/// the brightness change from the image's top-left corner to its bottom-right (top-left
/// lighter by gradient / 2, bottom-right darker by as much), linear in the pixel position, so a
/// flat field fitted by vision removes it exactly; 0 = flat [-].
struct Backdrop {
  Rgb color{225, 225, 220};
  double gradient = 0.0;
};

/// The scale reference (marker.md): in the side view a bar of black and white bands standing on
/// the plate in the vertical plane through the axis facing the camera; in the top view a
/// checkerboard card lying on the plate. Drawn unlit, so its colours are exactly the stated ones.
struct ScaleReference {
  bool enabled = true;
  double band_mm = 10.0;  // height of one band (bar) or side of one square (card) [mm]
  // Side view: the band bar.
  int count = 10;                  // number of bands, black at the bottom [-]
  double width_mm = 20.0;          // bar width [mm]
  double thickness_mm = 2.0;       // bar thickness, extending away from the camera [mm]
  std::optional<double> offset_m;  // bar centre's offset from the axis along the image's
                                   // horizontal direction [m]; default: pile radius + 25 mm
  // Top view: the checker card.
  int squares = 4;                               // squares per side [-]
  double card_thickness_mm = 0.5;                // card thickness [mm]
  std::optional<Eigen::Vector2d> card_center_m;  // card centre (x, y) on the plate [m];
                                                 // default: (pile radius + 35 mm, 0)
};

/// Everything drawn: spheres plus the lab fixtures.
struct Scene {
  std::vector<Eigen::Vector3d> positions;  // (n) sphere centres [m]
  std::vector<double> radii;               // (n) sphere radii [m]
  std::vector<int> material_ids;           // (n) material of each sphere, or empty (all 0)
  // (n) the rigid body each sphere belongs to, or empty (every sphere its own body): the
  // components of one clump share one tone, as one grain of rock has one colour.
  std::vector<std::int64_t> body_ids;
  Plate plate;
  std::vector<Shell> shells;  // funnel and/or column; may be empty
  Backdrop backdrop;
  ScaleReference scale_reference;
};

/// Which lab view a render is: decides which scale reference is drawn and the sidecar's scale.
enum class View { kSide, kTop };

/// How the spheres are coloured.
enum class Shading {
  kPhoto,       // rock grey with a small random per-particle brightness tint (default)
  kBySize,      // viridis colour map over the radius range of the scene
  kByMaterial,  // one distinct colour per material id
};

/// Render settings: look and lighting. The light is fixed relative to the camera (a lab lights
/// the pile for its camera), so both views read alike.
struct RenderOptions {
  View view = View::kSide;
  Shading shading = Shading::kPhoto;
  Rgb particle_color{120, 115, 108};  // rock grey (kPhoto)
  double tint_fraction = 0.08;        // per-particle brightness tint, uniform in +-this [-]
  std::uint64_t tint_seed = 1;        // seed of the tint; same seed, same picture
  double ambient = 0.35;              // ambient light fraction [-]
  double diffuse = 0.65;              // diffuse light fraction [-]
  Eigen::Vector3d light_direction_camera{-0.35, -0.6, -1.0};  // towards the light, camera frame
                                                              // (x right, y down, z forward)
  double tone_warmth = 0.0;  // per-grain hue spread (kPhoto): each grain is shifted between its
                             // grey and a brown of the same brightness by a hashed fraction of
                             // this (rock varies warm, never blue, so it stays unlike the plate)
  // Soft shadows of the spheres (on each other, the plate and the funnel) from the light, by
  // shadow mapping with a fixed percentage-closer kernel: deterministic like the rest.
  bool shadows = false;
  double shadow_strength = 0.75;   // fraction of the direct light a full shadow removes [-]
  double shadow_softness_m = 0.0;  // penumbra radius [m]; 0 = half the mean sphere radius
  // Shadow map side [px]; 0: shadow_map_side()'s choice from the image (1024 px at 960 x 720:
  // a quarter of the fragments of a 2048 map, and the same measurement, tests/experiments/photos).
  int shadow_map_px = 0;
  bool occlusion_culling = true;  // skip spheres provably hidden by others: same bytes, faster
  int supersample = 1;  // render at this many times the resolution, then average s x s blocks:
                        // anti-aliased edges like a photograph's; 1 = exact binary coverage [-]
};

/// The lab-photograph look (backdrop gradient, board grain, varied grain tones, soft shadows)
/// applied to a scene and its options; the geometry is unchanged. The plain defaults stay for
/// tests that need exact binary silhouettes and flat colours.
void apply_lab_look(Scene& scene, RenderOptions& options);

/// The shadow map's side [px]: options.shadow_map_px when set, else the image's longer side
/// rounded up to a power of two, from 512 to 2048. The map is fitted to the spheres, which fill
/// part of the frame, so its texels stay smaller than the image's pixels on the pile; a larger
/// map costs fragments (every sphere drawn over its whole footprint) and changes no measurement:
/// a 960 x 720 pile photo reads the same atan(2H/D) to 0.001 deg with 1024 and 2048 (tests/render).
int shadow_map_side(const RenderOptions& options, int width_px, int height_px);

/// The extent of the pile of spheres (bounding cylinder about the z axis).
struct PileExtent {
  double radius_m = 0.0;                               // max over spheres of hypot(x, y) + r [m]
  double z_min_m = 0.0;                                // min over spheres of z - r [m]
  double z_max_m = 0.0;                                // max over spheres of z + r [m]
  Eigen::Vector3d center_m = Eigen::Vector3d::Zero();  // centre of the spheres' bounding box [m]
};

/// Computes the pile extent. Throws std::invalid_argument when the scene has no spheres.
PileExtent pile_extent(const Scene& scene);

/// Checks the scene's data (sizes agree, finite positions, positive radii, sane fixtures).
/// Throws std::invalid_argument naming the field and value.
void validate(const Scene& scene);

/// Checks the scene, the camera and the options together: the camera must be valid
/// (camera::validate), outside every sphere and outside the pile's bounding cylinder, and the
/// pile's centre must be in front of the camera and inside the image. Throws
/// std::invalid_argument naming the field and value.
void validate(const Scene& scene, const camera::Camera& cam, const RenderOptions& options);

/// Where the side-view bar or top-view card actually stands for this scene and camera: the
/// centre of its visible face (bar: front face; card: top face) [m]. std::nullopt when the scale
/// reference is disabled.
std::optional<Eigen::Vector3d> scale_reference_center(const Scene& scene, const camera::Camera& cam,
                                                      View view);

/// Settings for the default lab cameras.
struct LabCameraSettings {
  int width_px = 1920;
  int height_px = 1080;
  double distance_radii = 12.0;  // camera distance from the axis (side) or above the pile top
                                 // (top), in pile radii; at least 10 [-]
  double margin = 1.1;           // field of view / extent of pile, fixtures and scale ref [-]
  double side_height_m = 0.0;    // side camera height; 0 = level with the plate [m]
  // Side view: frame only what stands between the plate's underside and the top of the pile
  // or bar, by shifting the principal point (a shift lens, as architecture and lab
  // photographers use), so the camera stays level and sees the plate edge-on while the pile
  // fills the frame; false = centred on the camera height (half the frame below the plate).
  // Top view: likewise the pile and the card beside it, together, fill the frame.
  bool shift_lens = true;
  double azimuth_deg = 0.0;      // side camera azimuth about z, 0 = from -y [deg]
};

/// The lab's side view of this scene (camera::side_view): level with the plate, distance
/// max(10, distance_radii) pile radii from the axis, field of view just covering the pile, the
/// plate band and the scale bar with `margin` to spare (see shift_lens).
camera::Camera lab_side_camera(const Scene& scene, const LabCameraSettings& settings = {});

/// The lab's top view of this scene (camera::top_view): straight down the axis from
/// distance_radii pile radii above the pile top, field covering the pile and the scale card
/// (see shift_lens).
camera::Camera lab_top_camera(const Scene& scene, const LabCameraSettings& settings = {});

}  // namespace reposetwin::render
