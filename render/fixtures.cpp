#include "render/fixtures.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>

namespace reposetwin::render {
namespace {

constexpr Rgb kBlack{20, 20, 20};
constexpr Rgb kWhite{245, 245, 245};

void add_triangle(TriangleMesh& mesh, const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                  const Eigen::Vector3d& p2, const Eigen::Vector3d& n0, const Eigen::Vector3d& n1,
                  const Eigen::Vector3d& n2, Rgb color, bool lit) {
  mesh.positions.insert(mesh.positions.end(), {p0, p1, p2});
  mesh.normals.insert(mesh.normals.end(), {n0, n1, n2});
  mesh.colors.insert(mesh.colors.end(), {color, color, color});
  const std::uint8_t l = lit ? 1 : 0;
  mesh.lit.insert(mesh.lit.end(), {l, l, l});
}

void add_quad(TriangleMesh& mesh, const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
              const Eigen::Vector3d& p2, const Eigen::Vector3d& p3, const Eigen::Vector3d& n,
              Rgb color, bool lit) {
  add_triangle(mesh, p0, p1, p2, n, n, n, color, lit);
  add_triangle(mesh, p0, p2, p3, n, n, n, color, lit);
}

}  // namespace

void add_box(TriangleMesh& mesh, const Eigen::Vector3d& center, const Eigen::Vector3d& a,
             const Eigen::Vector3d& b, const Eigen::Vector3d& c, const Eigen::Vector3d& half,
             Rgb color, bool lit) {
  const Eigen::Vector3d axes[3] = {a * half.x(), b * half.y(), c * half.z()};
  const Eigen::Vector3d units[3] = {a, b, c};
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d& u = axes[(k + 1) % 3];
    const Eigen::Vector3d& v = axes[(k + 2) % 3];
    for (const double s : {-1.0, 1.0}) {
      const Eigen::Vector3d fc = center + s * axes[k];
      add_quad(mesh, fc - u - v, fc + u - v, fc + u + v, fc - u + v, s * units[k], color, lit);
    }
  }
}

void add_shell(TriangleMesh& mesh, const Shell& shell, int segments) {
  const double slope = (shell.r_bottom_m - shell.r_top_m) / (shell.z_top_m - shell.z_bottom_m);
  for (int i = 0; i < segments; ++i) {
    const double a0 = 2.0 * std::numbers::pi * i / segments;
    const double a1 = 2.0 * std::numbers::pi * (i + 1) / segments;
    const Eigen::Vector3d d0(std::cos(a0), std::sin(a0), 0.0);
    const Eigen::Vector3d d1(std::cos(a1), std::sin(a1), 0.0);
    const Eigen::Vector3d n0 = (d0 + Eigen::Vector3d(0, 0, slope)).normalized();
    const Eigen::Vector3d n1 = (d1 + Eigen::Vector3d(0, 0, slope)).normalized();
    const Eigen::Vector3d zb(0, 0, shell.z_bottom_m), zt(0, 0, shell.z_top_m);
    const Eigen::Vector3d b0 = zb + shell.r_bottom_m * d0, b1 = zb + shell.r_bottom_m * d1;
    const Eigen::Vector3d t0 = zt + shell.r_top_m * d0, t1 = zt + shell.r_top_m * d1;
    add_triangle(mesh, b0, b1, t1, n0, n1, n1, shell.color, true);
    add_triangle(mesh, b0, t1, t0, n0, n1, n0, shell.color, true);
  }
}

TriangleMesh build_fixtures(const Scene& scene, const camera::Camera& cam, View view) {
  TriangleMesh mesh;
  const Eigen::Vector3d ex = Eigen::Vector3d::UnitX(), ey = Eigen::Vector3d::UnitY(),
                        ez = Eigen::Vector3d::UnitZ();
  if (scene.plate.enabled) {
    const Plate& p = scene.plate;
    add_box(mesh, Eigen::Vector3d(0, 0, -0.5 * p.thickness_m), ex, ey, ez,
            Eigen::Vector3d(p.half_size_m, p.half_size_m, 0.5 * p.thickness_m), p.color, true);
    if (p.texture > 0.0) std::fill(mesh.lit.begin(), mesh.lit.end(), std::uint8_t{2});
  }
  for (const Shell& s : scene.shells) add_shell(mesh, s);

  const std::optional<Eigen::Vector3d> center = scale_reference_center(scene, cam, view);
  if (!center) return mesh;
  const ScaleReference& sr = scene.scale_reference;
  const double band = 1e-3 * sr.band_mm;
  if (view == View::kSide) {
    // Image-horizontal direction e and horizontal viewing direction h, both flattened.
    const Eigen::Matrix3d r = camera::rotation_world_to_camera(cam);
    Eigen::Vector3d e = r.row(0).transpose();
    Eigen::Vector3d h = r.row(2).transpose();
    e.z() = 0.0;
    h.z() = 0.0;
    e.normalize();
    h = h.norm() > 1e-9 ? h.normalized() : ez.cross(e);
    const double thickness = 1e-3 * sr.thickness_mm;
    // The front face is in the plane through the axis; the board extends away from the camera.
    const Eigen::Vector3d base(center->x(), center->y(), 0.0);
    for (int k = 0; k < sr.count; ++k) {
      const Eigen::Vector3d c = base + (0.5 * thickness) * h + ((k + 0.5) * band) * ez;
      add_box(mesh, c, e, h, ez, Eigen::Vector3d(0.5e-3 * sr.width_mm, 0.5 * thickness, 0.5 * band),
              k % 2 == 0 ? kBlack : kWhite, false);
    }
  } else {
    const double t = 1e-3 * sr.card_thickness_mm;
    const double side = band * sr.squares;
    for (int i = 0; i < sr.squares; ++i) {
      for (int j = 0; j < sr.squares; ++j) {
        const Eigen::Vector3d c(center->x() - 0.5 * side + (i + 0.5) * band,
                                center->y() - 0.5 * side + (j + 0.5) * band, 0.5 * t);
        add_box(mesh, c, ex, ey, ez, Eigen::Vector3d(0.5 * band, 0.5 * band, 0.5 * t),
                (i + j) % 2 == 0 ? kBlack : kWhite, false);
      }
    }
  }
  return mesh;
}

}  // namespace reposetwin::render
