// bench_contact_trace: one or two spheres through a contact, traced step by step, with the same
// scene written as a LIGGGHTS 3.8 input, so the two engines' contact laws are compared on
// identical inputs one contact at a time (bench/compare_liggghts_contacts.sh runs both).
//
// Design note. The pile test compares whole pours; when two engines' piles differ, the laws a
// pour is made of must be compared apart. Each case isolates a few of them, with the physics of
// the pile scenes (E softened to 4.68 MPa for every material, nu 0.19 rock / 0.3 plate, rock
// density 2760 kg/m^3, e 0.79 rock-rock / 0.6 rock-plate, mu_s 0.466, epsd with mu_r 0.4 and no
// rolling dashpot, LIGGGHTS epsd2) and the twin's dt for the smallest sphere:
//   plate_slide  a sphere lands on the plate sliding and spinning backwards: normal damping,
//                the Coulomb slip, the change to rolling, then the rolling resistance that stops it;
//   pair_oblique two spheres in free flight meet off-centre, spinning: pair normal, tangential
//                and rolling in one short contact;
//   pair_rest    a sphere dropped slightly off the top of one resting on the plate: a long-lived
//                pair contact loaded by gravity, where the rolling cap decides whether it stays
//                or rolls off (the pile's own question).
// Printed: CSV rows "step,id,x,y,z,vx,vy,vz,wx,wy,wz" every --every steps, ids from 1 as
// LIGGGHTS'. With --write-liggghts DIR the same case is written as DIR/in.trace and DIR/trace.data.
//
// Usage: bench_contact_trace --case plate_slide|pair_oblique|pair_rest [--steps N] [--every K]
//                            [--mu-r X] [--write-liggghts DIR]
#include <CLI/CLI.hpp>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <string>
#include <vector>

#include "sim/model.hpp"
#include "sim/world.hpp"

namespace {
using reposetwin::sim::Material;
using reposetwin::sim::Model;
using reposetwin::sim::PairParams;
using reposetwin::sim::RollingModel;
using reposetwin::sim::Vec3;
using reposetwin::sim::WallKind;
using reposetwin::sim::WallSpec;
using reposetwin::sim::World;

constexpr double kSoftE = 4.68e6;   // [Pa] the pile scenes' softened E
constexpr double kDensity = 2760;  // [kg/m^3]

struct Body {
  Vec3 x, v, w;   // [m], [m/s], [rad/s]
  double r = 0;   // [m]
};

struct Case {
  std::vector<Body> bodies;
  bool gravity = true;
  bool plate = true;
};

Case make_case(const std::string& name) {
  Case c;
  if (name == "plate_slide") {
    c.bodies = {{Vec3(0, 0, 0.0040), Vec3(0.3, 0.05, -0.1), Vec3(0, -40, 5), 0.0035}};
  } else if (name == "pair_oblique") {
    c.gravity = false;
    c.plate = false;
    c.bodies = {{Vec3(-0.0036, 0, 0.05), Vec3(0.4, 0.02, 0), Vec3(0, 10, 30), 0.0035},
                {Vec3(0.0036, 0.0025, 0.05), Vec3(-0.3, 0, 0.05), Vec3(-5, 0, 0), 0.0032}};
  } else if (name == "pair_rest") {
    c.bodies = {{Vec3(0, 0, 0.0035), Vec3::Zero(), Vec3::Zero(), 0.0035},
                {Vec3(0.0015, 0.0004, 0.0035 + 0.0070 + 0.0004), Vec3::Zero(), Vec3::Zero(),
                 0.0035}};
  } else {
    throw CLI::ValidationError("--case", "unknown case '" + name +
                                             "' (plate_slide, pair_oblique, pair_rest)");
  }
  return c;
}

Model make_model(const Case& c, double mu_r) {
  Model m;
  Material rock{};
  rock.name = "rock";
  rock.density = kDensity;
  rock.youngs_modulus = 46.8e9;
  rock.poisson_ratio = 0.19;
  Material plate = rock;
  plate.name = "plate";
  plate.density = 7850;
  plate.poisson_ratio = 0.3;
  m.materials = {rock, plate};
  PairParams rr;
  rr.restitution = 0.79;
  rr.friction = 0.466;
  rr.rolling_friction = mu_r;
  rr.rolling_model = RollingModel::kEpsd;
  rr.rolling_damping = 0.0;
  PairParams rp = rr;
  rp.restitution = 0.6;
  m.set_pair(0, 0, rr);
  m.set_pair(0, 1, rp);
  m.set_pair(1, 1, rp);
  m.settings.softened_youngs_modulus = kSoftE;
  m.settings.gravity = c.gravity ? Vec3(0, 0, -9.81) : Vec3::Zero();
  if (c.plate) {
    WallSpec w;
    w.name = "plate";
    w.kind = WallKind::kPlane;
    w.material = 1;
    w.point = Vec3(0, 0, 0);
    w.normal = Vec3(0, 0, 1);
    m.walls.push_back(w);
  }
  double r_min = c.bodies[0].r, r_max = c.bodies[0].r;
  for (const Body& b : c.bodies) {
    r_min = std::min(r_min, b.r);
    r_max = std::max(r_max, b.r);
  }
  m.finalize(r_min, r_max);
  return m;
}

void write_liggghts(const Case& c, const Model& m, double mu_r, int steps, int every,
                    const std::string& dir) {
  namespace fs = std::filesystem;
  fs::create_directories(dir);
  std::ofstream d(fs::path(dir) / "trace.data");
  d << std::setprecision(17) << "LIGGGHTS data file written by bench_contact_trace\n\n"
    << c.bodies.size() << " atoms\n2 atom types\n\n"
    << "-0.1 0.1 xlo xhi\n-0.1 0.1 ylo yhi\n-0.01 0.2 zlo zhi\n\nAtoms\n\n";
  for (std::size_t i = 0; i < c.bodies.size(); ++i) {
    const Body& b = c.bodies[i];
    d << i + 1 << " 1 " << 2 * b.r << " " << kDensity << " " << b.x.x() << " " << b.x.y() << " "
      << b.x.z() << "\n";
  }
  d << "\nVelocities\n\n";
  for (std::size_t i = 0; i < c.bodies.size(); ++i) {
    const Body& b = c.bodies[i];
    d << i + 1 << " " << b.v.x() << " " << b.v.y() << " " << b.v.z() << " " << b.w.x() << " "
      << b.w.y() << " " << b.w.z() << "\n";
  }
  std::ofstream f(fs::path(dir) / "in.trace");
  f << std::setprecision(17)
    << "# LIGGGHTS 3.8 input written by bench_contact_trace: the same case, physics and dt.\n"
       "atom_style granular\natom_modify map array\nboundary f f f\n"
       "communicate single vel yes\nunits si\nnewton off\nprocessors * * 1\n"
       "read_data trace.data\n"
    << "neighbor " << 0.5 * m.r_min << " bin\nneigh_modify delay 0\n"
    << "soft_particles yes\n"
    << "fix m1 all property/global youngsModulus peratomtype " << kSoftE << " " << kSoftE << "\n"
    << "fix m2 all property/global poissonsRatio peratomtype 0.19 0.3\n"
    << "fix m3 all property/global coefficientRestitution peratomtypepair 2 0.79 0.6 0.6 0.6\n"
    << "fix m4 all property/global coefficientFriction peratomtypepair 2 0.466 0.466 0.466 "
       "0.466\n"
    << "fix m5 all property/global coefficientRollingFriction peratomtypepair 2 " << mu_r << " "
    << mu_r << " " << mu_r << " " << mu_r << "\n"
    << "pair_style gran model hertz tangential history rolling_friction epsd2\n"
    << "pair_coeff * *\n"
    << "timestep " << m.dt << "\n";
  if (c.gravity) f << "fix gravi all gravity 9.81 vector 0.0 0.0 -1.0\n";
  if (c.plate)
    f << "fix plate all wall/gran model hertz tangential history rolling_friction epsd2 "
         "primitive type 2 zplane 0.0\n";
  f << "fix integr all nve/sphere\n"
    << "dump tr all custom " << every << " trace.dump id x y z vx vy vz omegax omegay omegaz\n"
    << "dump_modify tr sort id format \"%d %.12g %.12g %.12g %.12g %.12g %.12g %.12g %.12g "
       "%.12g\"\n"
    << "run " << steps << "\n";
  if (!d || !f) throw std::runtime_error("--write-liggghts: cannot write into " + dir);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"bench_contact_trace: spheres through a contact, step by step (design note)"};
  std::string name = "plate_slide", liggghts_dir;
  int steps = 5000, every = 50;
  double mu_r = 0.4;
  app.add_option("--case", name, "plate_slide, pair_oblique or pair_rest")->capture_default_str();
  app.add_option("--steps", steps, "steps to run")->check(CLI::PositiveNumber);
  app.add_option("--every", every, "steps between printed rows")->check(CLI::PositiveNumber);
  app.add_option("--mu-r", mu_r, "rolling coefficient (epsd, both pairs)")->check(
      CLI::Range(0.0, 10.0));
  app.add_option("--write-liggghts", liggghts_dir, "also write the case for LIGGGHTS here");
  CLI11_PARSE(app, argc, argv);
  try {
    const Case c = make_case(name);
    const Model model = make_model(c, mu_r);
    if (!liggghts_dir.empty()) write_liggghts(c, model, mu_r, steps, every, liggghts_dir);
    World world(model);
    for (std::size_t i = 0; i < c.bodies.size(); ++i) {
      const Body& b = c.bodies[i];
      const std::size_t k = world.add_particle(b.x, b.r, 0);
      world.state().particles.v[k] = b.v;
      world.state().particles.w[k] = b.w;
    }
    std::cout << "# dt " << std::setprecision(10) << model.dt << " s\n"
              << "step,id,x,y,z,vx,vy,vz,wx,wy,wz\n"
              << std::setprecision(12);
    for (int s = 0; s <= steps; ++s) {
      if (s % every == 0) {
        const auto& p = world.state().particles;
        for (std::size_t i = 0; i < p.size(); ++i)
          std::cout << s << "," << p.id[i] + 1 << "," << p.x[i].x() << "," << p.x[i].y() << ","
                    << p.x[i].z() << "," << p.v[i].x() << "," << p.v[i].y() << "," << p.v[i].z()
                    << "," << p.w[i].x() << "," << p.w[i].y() << "," << p.w[i].z() << "\n";
      }
      if (s < steps) world.step();
    }
  } catch (const std::exception& e) {
    std::cerr << "bench_contact_trace: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
