#include "experiments/export/liggghts_deck.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <sstream>
#include <vector>

#include "experiments/io/format.hpp"
#include "experiments/io/input_error.hpp"
#include "sim/psd.hpp"

namespace reposetwin::experiments {
namespace {

// LIGGGHTS numbers its atom types from 1: the sample, the container, the plate.
constexpr int kTypes = 3;
// Settling is checked every this many steps (a thermo step).
constexpr long long kSettleChunk = 1000;

std::string num(double v) {
  std::ostringstream os;
  os.precision(10);
  os << v;
  return os.str();
}

// A prime above 10000 for each of LIGGGHTS' random streams (it refuses other seeds).
std::uint64_t prime_seed(std::uint64_t seed, int stream) {
  std::uint64_t n = 10007 + 1000 * ((seed * 7 + static_cast<std::uint64_t>(stream)) % 100000);
  auto prime = [](std::uint64_t k) {
    for (std::uint64_t d = 2; d * d <= k; ++d)
      if (k % d == 0) return false;
    return true;
  };
  while (!prime(n)) ++n;
  return n;
}

// The material names of the three types and the pair parameters between them.
struct Types {
  std::string name[kTypes];
  const sim::Material* material[kTypes] = {};
};

const sim::PairParams& pair_of(const SceneConfig& scene, const std::string& a,
                               const std::string& b) {
  if (auto it = scene.contacts.find({a, b}); it != scene.contacts.end()) return it->second;
  if (auto it = scene.contacts.find({b, a}); it != scene.contacts.end()) return it->second;
  static const sim::PairParams kUnused{};  // container-plate: never in contact
  return kUnused;
}

// `fix ... property/global NAME peratomtypepair 3 v11 v12 ... v33`.
std::string per_pair(const SceneConfig& scene, const Types& t, const char* id, const char* name,
                     double sim::PairParams::*field) {
  std::ostringstream s;
  s.precision(10);
  s << "fix " << id << " all property/global " << name << " peratomtypepair " << kTypes;
  for (int i = 0; i < kTypes; ++i)
    for (int j = 0; j < kTypes; ++j) s << " " << pair_of(scene, t.name[i], t.name[j]).*field;
  s << "\n";
  return s.str();
}

// An ASCII STL of the frustum between (r_bottom, z_bottom) and (r_top, z_top), `facets` around.
std::string frustum_stl(double r_bottom, double r_top, double z_bottom, double z_top,
                        int facets) {
  std::ostringstream os;
  os.precision(10);
  os << "solid container\n";
  auto point = [&](double r, double z, int k) {
    const double a = 2.0 * std::numbers::pi * k / facets;
    return std::array<double, 3>{r * std::cos(a), r * std::sin(a), z};
  };
  auto facet = [&](const std::array<double, 3>& p, const std::array<double, 3>& q,
                   const std::array<double, 3>& s) {
    const double ux = q[0] - p[0], uy = q[1] - p[1], uz = q[2] - p[2];
    const double vx = s[0] - p[0], vy = s[1] - p[1], vz = s[2] - p[2];
    double n[3] = {uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx};
    const double l = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    os << "facet normal " << n[0] / l << " " << n[1] / l << " " << n[2] / l << "\n outer loop\n";
    for (const auto* v : {&p, &q, &s})
      os << "  vertex " << (*v)[0] << " " << (*v)[1] << " " << (*v)[2] << "\n";
    os << " endloop\nendfacet\n";
  };
  for (int k = 0; k < facets; ++k) {
    const auto b0 = point(r_bottom, z_bottom, k), b1 = point(r_bottom, z_bottom, k + 1);
    const auto t0 = point(r_top, z_top, k), t1 = point(r_top, z_top, k + 1);
    facet(b0, b1, t1);
    facet(b0, t1, t0);
  }
  os << "endsolid container\n";
  return os.str();
}

// The filled sample as a LIGGGHTS data file (atom_style granular: id type diameter density
// x y z), in the deck's box. Every grain must be a sphere of the sample's material.
std::string initial_data(const SceneConfig& scene, const SnapshotParticles& s, const Types& t,
                         double density, const std::array<double, 6>& box) {
  const std::string what = "the initial state";
  if (s.x.empty()) throw InputError(what + " holds no grains");
  if (!s.body.empty() &&
      std::any_of(s.body.begin(), s.body.end(), [](std::int64_t b) { return b >= 0; }))
    throw InputError(what + " holds clumps; only sphere states are exported");
  std::ostringstream os;
  os.precision(12);
  os << "LIGGGHTS data file: scene " << scene.name << " as the twin filled it\n\n"
     << s.x.size() << " atoms\n" << kTypes << " atom types\n\n"
     << box[0] << " " << box[1] << " xlo xhi\n"
     << box[2] << " " << box[3] << " ylo yhi\n"
     << box[4] << " " << box[5] << " zlo zhi\n\nAtoms\n\n";
  for (std::size_t i = 0; i < s.x.size(); ++i) {
    const Eigen::Vector3d& x = s.x[i];
    if (!x.allFinite() || !(s.radius[i] > 0) || x.x() < box[0] || x.x() > box[1] ||
        x.y() < box[2] || x.y() > box[3] || x.z() < box[4] || x.z() > box[5])
      throw InputError(what + ": grain " + std::to_string(i) + " at (" + num(x.x()) + ", " +
                       num(x.y()) + ", " + num(x.z()) + ") m with radius " + num(s.radius[i]) +
                       " m is not a grain inside the deck's box");
    if (s.info && i < s.material.size() &&
        static_cast<std::size_t>(s.material[i]) < s.info->material_names.size() &&
        s.info->material_names[static_cast<std::size_t>(s.material[i])] != t.name[0])
      throw InputError(what + ": grain " + std::to_string(i) + " is of material \"" +
                       s.info->material_names[static_cast<std::size_t>(s.material[i])] +
                       "\", not the sample's \"" + t.name[0] + "\"");
    os << i + 1 << " 1 " << 2.0 * s.radius[i] << " " << density << " " << x.x() << " " << x.y()
       << " " << x.z() << "\n";
  }
  return os.str();
}

// The README's section on the calibration the deck carries: the value, its interval, what it was
// fitted to, and the value each calibrated key has in this deck.
std::string calibration_notes(const DeckCalibration* cal) {
  if (!cal) return "";
  const CalibratedMaterial& m = *cal->material;
  std::ostringstream md;
  md << "## The calibration it carries\n"
     << "- mu_r = " << num(m.mu_r) << ", 95% interval " << num(m.mu_r_lo) << " to "
     << num(m.mu_r_hi) << ", calibrated by `reposetwin calibrate` (`" << cal->file
     << "`) to the target angle " << num(m.target_deg) << " deg (the twin's '" << m.angle
     << "' measure).\n"
     << "- The scene: `" << m.scene << "` with the calibration test's " << m.overrides.size()
     << " override(s)"
     << (m.sieve_sheet.empty() ? std::string(", and its own sieve table")
                               : ", the sieve sheet `" + m.sieve_sheet + "` among them")
     << ".\n";
  for (const auto& [key, value] : cal->deck_values)
    md << "- " << key << " = " << num(value) << " in this deck"
       << (value == m.mu_r ? std::string(" (the calibrated value)")
                           : " (set by --set: NOT the calibrated " + num(m.mu_r) + ")")
       << ".\n";
  md << "- The interval's ends are the calibration's uncertainty: a field result that matters "
        "is run at both, each calibrated key set to "
     << num(m.mu_r_lo) << " and to " << num(m.mu_r_hi)
     << " (`reposetwin export FOLDER --set KEY=VALUE`).\n\n";
  return md.str();
}

// The material every deck carries, resolved once for grains of `size_scale` times the scene's:
// the three types, the PSD, the contact law, E, the time step and the skin. The lab deck is
// size_scale 1.
struct DeckMaterial {
  Types t;
  sim::ResolvedPsd psd;
  double scale = 1.0;         // grain diameters are the PSD's times this [-]
  double r_min = 0, r_max = 0;  // the deck's grain radii (scaled) [m]
  sim::Model model;           // build_model at those radii: dt as the twin computes it
  sim::PairParams grain;      // the grains' own pair
  bool cdt = false;
  double e_used = 0;          // E of the grains in the deck [Pa]
  bool softened = false;      // E is the scene's softened E for every material
  double density = 0;         // [kg/m^3]
  double skin = 0;            // neighbour skin (the twin's, scaled) [m]
  std::string law;            // the pair_style's model keywords
};

DeckMaterial deck_material(const SceneConfig& scene, double size_scale) {
  if (!scene.shapes.empty())
    throw InputError(scene.file + ": " + scene.shapes.front().key + " (\"" +
                     scene.shapes.front().name +
                     "\"): grain shapes are not exported yet (LIGGGHTS' multisphere templates "
                     "would carry them); export a sphere scene");
  DeckMaterial m;
  m.t.name[0] = scene.sample_material;
  m.t.name[1] = scene.container.material;
  m.t.name[2] = scene.plate_material;
  for (int i = 0; i < kTypes; ++i) {
    const int k = material_index(scene, m.t.name[i], i == 0 ? "sample.material"
                                                      : i == 1 ? "container.material"
                                                               : "plate.material");
    m.t.material[i] = &scene.materials[static_cast<std::size_t>(k)];
  }
  m.psd = sim::resolve_psd(scene.psd.spec);
  m.scale = size_scale;
  const auto [r_min, r_max] = grain_radius_range(scene, m.psd.d_min, m.psd.d_max);
  m.r_min = size_scale * r_min;
  m.r_max = size_scale * r_max;
  // The same function as the twin's run, at the deck's radii: the Rayleigh fraction of the
  // smallest grain's Rayleigh time over the materials in use (an explicit numerics.time_step_s
  // is kept as it is, and checked against the limit at these radii).
  m.model = build_model(scene, m.r_min, m.r_max);
  m.grain = pair_of(scene, m.t.name[0], m.t.name[0]);
  m.cdt = m.grain.rolling_model == sim::RollingModel::kCdt;
  m.softened = scene.settings.softened_youngs_modulus > 0;
  m.e_used = m.softened ? scene.settings.softened_youngs_modulus : m.t.material[0]->youngs_modulus;
  m.density = m.t.material[0]->density;
  // The twin's skin (0.25 of the smallest diameter unless the scene sets one), scaled with the
  // grains.
  m.skin = scene.settings.skin > 0 ? size_scale * scene.settings.skin : 0.5 * m.r_min;
  m.law = std::string("model hertz tangential history rolling_friction ") +
          (m.cdt ? "cdt" : "epsd2");
  return m;
}

// The deck's set-up up to the ground: atom style, decomposition, domain, neighbour list, the
// materials and pair tables, the law, the time step, gravity and the ground plane (z = 0, type 3).
void write_setup(std::ostream& in, const SceneConfig& scene, const DeckMaterial& m,
                 const std::string& processors, const std::array<double, 6>& box,
                 bool read_data) {
  const double e_soft = scene.settings.softened_youngs_modulus;  // 0: each material's real E
  in << "atom_style granular\natom_modify map array\nboundary f f f\nnewton off\n"
     << "communicate single vel yes\nunits si\nprocessors " << processors << "\n"
     << "region domain block " << num(box[0]) << " " << num(box[1]) << " " << num(box[2]) << " "
     << num(box[3]) << " " << num(box[4]) << " " << num(box[5]) << " units box\n"
     << (read_data ? std::string("read_data initial.data\n")
                   : "create_box " + std::to_string(kTypes) + " domain\n")
     << "neighbor " << num(m.skin) << " bin\nneigh_modify delay 0\n"
     << "soft_particles yes\n";
  in << "fix m1 all property/global youngsModulus peratomtype";
  for (int i = 0; i < kTypes; ++i)
    in << " " << num(e_soft > 0 ? e_soft : m.t.material[i]->youngs_modulus);
  in << "\nfix m2 all property/global poissonsRatio peratomtype";
  for (int i = 0; i < kTypes; ++i) in << " " << num(m.t.material[i]->poisson_ratio);
  in << "\n"
     << per_pair(scene, m.t, "m3", "coefficientRestitution", &sim::PairParams::restitution)
     << per_pair(scene, m.t, "m4", "coefficientFriction", &sim::PairParams::friction)
     << per_pair(scene, m.t, "m5", "coefficientRollingFriction",
                 &sim::PairParams::rolling_friction);
  in << "pair_style gran " << m.law << "\npair_coeff * *\n"
     << "timestep " << num(m.model.dt) << "\n"
     << "fix gravi all gravity " << num(-scene.settings.gravity.z()) << " vector 0.0 0.0 -1.0\n"
     << "fix plate all wall/gran " << m.law << " primitive type 3 zplane 0.0\n";
}

// One particletemplate/sphere per sieve interval (its middle size, scaled), mixed by mass
// fraction as `pdd`; returns the number of templates.
int write_psd(std::ostream& in, const DeckMaterial& m, std::uint64_t seed) {
  int k = 0;
  std::string mix;
  for (const sim::PsdInterval& iv : m.psd.intervals) {
    if (iv.mass_fraction <= 0) continue;
    ++k;
    in << "fix pts" << k << " all particletemplate/sphere " << prime_seed(seed, k)
       << " atom_type 1 density constant " << num(m.density) << " radius constant "
       << num(0.25 * m.scale * (iv.lower + iv.upper)) << "\n";
    mix += " pts" + std::to_string(k) + " " + num(iv.mass_fraction);
  }
  in << "fix pdd all particledistribution/discrete/massbased " << prime_seed(seed, 0) << " " << k
     << mix << "\n";
  return k;
}

void write_integration(std::ostream& in, double mass, double settle_speed) {
  in << "fix integr all nve/sphere\n"
     << "compute rke all erotate/sphere\n"
     << "thermo_style custom step atoms ke c_rke\n"
     << "thermo_modify lost ignore norm no\n"
     << "variable ke_now equal ke\n"
     << "variable ke_stop equal " << num(0.5 * mass * settle_speed * settle_speed) << "\n"
     << "thermo " << kSettleChunk << "\n";
}

long long steps_of(double seconds, double dt) {
  return static_cast<long long>(std::ceil(seconds / dt));
}

// Settling ends as the twin's does: when the kinetic energy per grain falls below
// 1/2 m_mean v^2 (v = procedure.settle_speed_m_s), that is the total below 1/2 M v^2, checked
// every kSettleChunk steps (a thermo step, so `ke` is current), or at the phase's time limit.
void write_settle(std::ostream& in, const std::string& label, double max_s, double dt) {
  const long long n = std::max(1LL, steps_of(max_s, dt) / kSettleChunk);
  in << "variable " << label << "_n loop " << n << "\n"
     << "label " << label << "\n"
     << "run " << kSettleChunk << "\n"
     << "if \"${ke_now} < ${ke_stop}\" then \"jump SELF " << label << "_done\"\n"
     << "next " << label << "_n\n"
     << "jump SELF " << label << "\n"
     << "label " << label << "_done\n"
     << "variable " << label << "_n delete\n";
}

// The README's lines on what every deck carries as it is: the law, E, the pair tables, rolling.
std::string carried_material_notes(const DeckMaterial& m) {
  std::ostringstream md;
  md << "- Hertz-Mindlin with history; E " << num(m.e_used) << " Pa"
     << (m.softened ? " (the scene's softened E, for every material, as the twin)" : "")
     << "; nu, e, mu_s and mu_r per material pair (types 1 " << m.t.name[0] << ", 2 "
     << m.t.name[1] << ", 3 " << m.t.name[2] << ").\n"
     << "- Rolling: "
     << (m.cdt ? "cdt" : "epsd2 (the twin's epsd: k_r = k_t R*^2, cap mu_r |F_n| R*)") << ".\n";
  return md.str();
}

// The README's "Not carried" lines every deck shares: the rolling dashpot, cdt's difference.
std::string not_carried_law_notes(const SceneConfig& scene, const DeckMaterial& m) {
  std::ostringstream md;
  // One line a pair as the scene names it: the contacts map holds each pair in both orders.
  for (const auto& names : scene.contact_pairs)
    if (const sim::PairParams& p = scene.contacts.at(names);
        p.rolling_model == sim::RollingModel::kEpsd && p.rolling_damping > 0)
      md << "- The rolling dashpot of contacts." << names.first << "-" << names.second
         << ": rolling_damping eta_r = " << num(p.rolling_damping)
         << " has no counterpart in epsd2; run the twin with `--set contacts." << names.first
         << "-" << names.second << ".rolling_damping=0` to compare like with like.\n";
  if (m.cdt)
    md << "- cdt: the twin's uses each body's own angular velocity and radius (EDEM Standard); "
          "LIGGGHTS' uses w_i - w_j and R*.\n";
  return md.str();
}

std::string conventions_notes(double mu_r) {
  const RollingConventions mu = rolling_conventions(mu_r);
  std::ostringstream md;
  md << "## The rolling coefficient in other conventions (equal spheres)\n"
     << "| engine | model | mu_r |\n|---|---|---|\n"
     << "| ReposeTwin | epsd (lever arm R* = R_i R_j / (R_i + R_j)) | " << num(mu.ours) << " |\n"
     << "| LIGGGHTS 3.8 | rolling_friction epsd2 / cdt (R*) | " << num(mu.liggghts) << " |\n"
     << "| LAMMPS | pair granular, rolling sds, mu_roll (R_eff = R*) | " << num(mu.lammps) << " |\n"
     << "| EDEM | rolling friction (each body's own radius R = 2 R*) | " << num(mu.edem) << " |\n\n"
     << "Between unequal spheres R* is smaller than either radius, so no single EDEM value "
        "matches every pair; the table holds for the equal spheres of a narrow sieve class.\n";
  return md.str();
}

std::string install_notes() {
  return "Installing LIGGGHTS on the machine that builds the twin: `sudo apt-get install "
         "--no-install-recommends liggghts`. With its recommended packages, Debian's liggghts "
         "pulls in paraview and python3-paraview, which conflicts with python3-vtk9: apt then "
         "removes python3-vtk9 and libvtk9-dev, and the twin no longer builds "
         "(`apt-get -s install liggghts` shows it beforehand).\n\n";
}

std::string header(const SceneConfig& scene, const LiggghtsDeckSettings& settings,
                   const std::string& what) {
  std::ostringstream in;
  in << "# LIGGGHTS 3.8 input written by `reposetwin export" << what << "` from " << scene.file
     << "\n# (scene " << scene.name << "); README.md beside it says what is carried and what not.\n";
  if (const DeckCalibration* cal = settings.calibration)
    in << "# calibrated: mu_r " << num(cal->material->mu_r) << " (95% "
       << num(cal->material->mu_r_lo) << " to " << num(cal->material->mu_r_hi) << ") from "
       << cal->file << "\n";
  return in.str();
}

// The lab's pile test: the container, the fill, the lift, the settling and the dump.
LiggghtsDeck lab_deck(const SceneConfig& scene, const LiggghtsDeckSettings& settings) {
  const DeckMaterial m = deck_material(scene, 1.0);
  const ContainerConfig& c = scene.container;
  const double mass = scene.mass * m.psd.simulated_mass_factor;
  const double density = m.density;

  // Geometry: the container's rim heights, the insertion column, the domain.
  const double rb = 0.5 * c.bottom_diameter, rt = 0.5 * c.top_diameter;
  const double zb = c.gap, zt = c.gap + c.height, d_max = m.psd.d_max;
  // Lifted by its own height, the rim stands above any pile the container could hold.
  const double lift = c.height;
  const double rin_b = std::max(rb - d_max, 0.5 * d_max), rin_t = rt - d_max;
  const double cone =
      std::numbers::pi * c.height / 3.0 * (rin_b * rin_b + rin_b * rin_t + rin_t * rin_t);
  const double needed = mass / (density * settings.insert_volume_fraction);
  const double column =
      std::max(2.0 * d_max, (needed - cone) / (std::numbers::pi * rin_t * rin_t));
  const double half = std::max(0.3, rt + 0.05), top = zt + column + lift + 0.05;
  const std::array<double, 6> box{-half, half, -half, half, -0.01, top};

  std::ostringstream in;
  in << header(scene, settings, "")
     << "# Run: liggghts -in in.pile, or mpirun -np N liggghts -in in.pile\n";
  write_setup(in, scene, m, "* * 1", box, settings.initial_state != nullptr);
  in << "fix cad all mesh/surface file container.stl type 2\n"
     << "fix walls all wall/gran " << m.law << " mesh n_meshes 1 meshes cad\n";

  // The PSD: one template per sieve interval, mixed by mass, and the sample inserted (unless it
  // is read from an initial state).
  int k = 0;
  if (!settings.initial_state) {
    k = write_psd(in, m, settings.seed);
    in << "region cone_in cone z 0 0 " << num(rin_b) << " " << num(rin_t) << " "
       << num(zb + d_max) << " " << num(zt) << " units box\n"
       << "region column cylinder z 0 0 " << num(rin_t) << " " << num(zt) << " "
       << num(zt + column) << " units box\n"
       << "region fill union 2 cone_in column\n"
       << "fix ins all insert/pack seed " << prime_seed(settings.seed, 99)
       << " distributiontemplate pdd insert_every once overlapcheck yes all_in yes "
          "vel constant 0 0 0 mass_in_region "
       << num(mass) << " region fill ntry_mc 100000\n";
  }
  const ProcedureConfig& p = scene.procedure;
  write_integration(in, mass, p.settle_speed);
  in << (settings.initial_state ? "# the twin's filled sample settles under this engine's laws\n"
                                : "# fill: the sample falls into the container and settles\n");
  write_settle(in, "fill", p.fill_settle_max, m.model.dt);
  in << "# lift at " << num(p.lift_speed) << " m/s until the rim is " << num(lift)
     << " m higher\n"
     << "fix lift all move/mesh mesh cad linear 0.0 0.0 " << num(p.lift_speed) << "\n"
     << "run " << steps_of(lift / p.lift_speed, m.model.dt) << "\n"
     << "unfix lift\n"
     << "# settle, then the grains for `reposetwin measure-particles`\n";
  write_settle(in, "final", p.final_settle_max, m.model.dt);
  in << "write_dump all custom final.dump id type x y z radius\n";

  LiggghtsDeck deck;
  deck.input = in.str();
  if (settings.initial_state)
    deck.initial_data = initial_data(scene, *settings.initial_state, m.t, density, box);
  deck.funnel_stl = frustum_stl(rb, rt, zb, zt, settings.facets);

  std::ostringstream md;
  md << "# " << scene.name << " as a LIGGGHTS 3.8 deck\n\n"
     << "Written by `reposetwin export` from `" << scene.file << "`. Run it with "
     << "`liggghts -in in.pile` or `mpirun -np N liggghts -in in.pile`; it ends with "
     << "`final.dump`, which `reposetwin measure-particles final.dump --scene SCENE` measures "
        "with the twin's own pile measure (H, D, atan(2H/D)).\n\n"
     << install_notes() << calibration_notes(settings.calibration) << "## Carried as it is\n"
     << carried_material_notes(m) << "- dt " << num(m.model.dt)
     << " s (the twin's), skin as the twin's.\n"
     << (settings.initial_state
             ? "- The sample as the twin filled it: " +
                   std::to_string(settings.initial_state->x.size()) +
                   " grains, each with its position and size, read from `initial.data`.\n"
             : "- The PSD: " + std::to_string(k) + " templates, one per sieve interval in [" +
                   num(1e3 * m.psd.d_min) + ", " + num(1e3 * m.psd.d_max) +
                   "] mm, of the interval's middle size, by mass fraction; sample mass " +
                   num(mass) + " kg.\n")
     << "- The container (" << c.kind << ", " << num(c.bottom_diameter) << " to "
     << num(c.top_diameter) << " m, " << num(c.height) << " m high, " << num(c.gap)
     << " m above the plate) as `container.stl`, lifted at " << num(p.lift_speed) << " m/s.\n\n"
     << "## Not carried\n"
     << not_carried_law_notes(scene, m);
  if (settings.initial_state)
    md << "- The filled state's contact springs: the deck reads positions and sizes only, so "
          "its grains start without tangential or rolling springs and settle again (as the "
          "twin's settling stops, or for at most procedure.fill_settle_max = "
       << num(p.fill_settle_max) << " s) before the lift.\n";
  else
    md << "- The fill: the twin pours gently (speeds capped at procedure.fill_max_speed) and "
          "stops settling when the kinetic energy is low; the deck inserts at random, lets the "
          "sample fall and settles it as the twin's settling stops (kinetic energy per grain "
          "below 1/2 m_mean v^2, checked every 1000 steps) or for at most "
          "procedure.fill_settle_max = "
       << num(p.fill_settle_max) << " s.\n"
       << "- Each interval's sizes: the twin draws a clipped normal inside it, the deck uses "
          "its middle size.\n";
  md << "- The lift's end: the deck lifts the container by its height at the lift speed; the "
        "twin removes it once it is empty.\n\n"
     << conventions_notes(m.grain.rolling_friction);
  deck.notes = md.str();
  return deck;
}

// A cone of `mass` of grains of `density` at the bulk solid fraction kAssumedSolidFraction, its
// flanks at `angle_deg`: V = pi/3 R^3 tan(a), H = R tan(a).
struct Cone {
  double height = 0, diameter = 0;  // [m]
};
Cone cone_of(double mass, double density, double angle_deg) {
  const double v = mass / (kAssumedSolidFraction * density);
  const double t = std::tan(angle_deg * std::numbers::pi / 180.0);
  const double r = std::cbrt(3.0 * v / (std::numbers::pi * t));
  return {r * t, 2.0 * r};
}

// The mean overlap / radius of a grain contact at depth h of a heap of equal Hertz spheres, an
// order-of-magnitude estimate: the pressure phi rho g h is carried by contacts of mean force
// f = pi d^2 sigma / (Z phi) = pi d^2 rho g h / Z (sigma = Z phi f / (pi d^2) for equal spheres,
// Rothenburg and Bathurst), each pressing f = 4/3 E* sqrt(R*) delta^(3/2) with R* = d/4 and
// E* = E / (2 (1 - nu^2)). delta grows as d, so delta / R depends on h / E alone: coarse grains
// change nothing here, a taller pile does. Peak forces run a few times the mean.
double base_overlap_ratio(double density, double g, double h, double e, double nu) {
  const double d = 1.0;  // any size: the ratio does not depend on it
  const double f = std::numbers::pi * d * d * density * g * h / kAssumedCoordination;
  const double e_star = e / (2.0 * (1.0 - nu * nu));
  const double delta = std::pow(3.0 * f / (4.0 * e_star * std::sqrt(0.25 * d)), 2.0 / 3.0);
  return delta / (0.5 * d);
}

// The processors grid for `ranks` over a w x l ground: px py 1 whose subdomains are the closest
// to square (the pile is flat and wide: splitting z would leave ranks above it idle).
std::array<int, 3> processor_grid(int ranks, double w, double l) {
  if (ranks <= 0) return {0, 0, 1};
  std::array<int, 3> best{ranks, 1, 1};
  double best_score = std::numeric_limits<double>::infinity();
  // From the most x-ranks down: of two grids equally square (2 x 1, 1 x 2), x is split first.
  for (int px = ranks; px >= 1; --px) {
    if (ranks % px != 0) continue;
    const int py = ranks / px;
    const double score = std::abs(std::log((w / px) / (l / py)));
    if (score < best_score - 1e-12) {
      best_score = score;
      best = {px, py, 1};
    }
  }
  return best;
}

std::string processors_line(const std::array<int, 3>& grid) {
  if (grid[0] == 0) return "* * 1";
  return std::to_string(grid[0]) + " " + std::to_string(grid[1]) + " " + std::to_string(grid[2]);
}

double downward_gravity(const SceneConfig& scene) {
  const double g = -scene.settings.gravity.z();
  if (!(g > 0))
    throw InputError(scene.file + ": numerics gravity has no downward z component (" + num(g) +
                     " m/s^2 down); a dump falls under gravity");
  return g;
}

// One row of the scaling table: what, the lab's value, the field deck's, and how it is scaled.
std::string row(const std::string& what, const std::string& lab, const std::string& field,
                const std::string& how) {
  char buf[512];
  std::snprintf(buf, sizeof buf, "%-26s %-22s %-22s %s\n", what.c_str(), lab.c_str(),
                field.c_str(), how.c_str());
  return buf;
}

std::string scaling_table(const FieldScaling& x) {
  auto mm = [](double m) { return significant(1e3 * m, 3) + " mm"; };
  auto pct = [](double r) { return significant(100.0 * r, 2) + "%"; };
  std::string t = row("quantity", "calibration (lab)", "field deck", "how");
  t += row("grain size d_min..d_max", mm(x.d_min_lab) + " .. " + mm(x.d_max_lab),
           mm(x.d_min) + " .. " + mm(x.d_max), "x S = " + significant(x.size_scale, 3) +
                                                      " (--size-scale; coarse-graining)");
  t += row("mass-mean grain", mm(x.d_mean / x.size_scale), mm(x.d_mean), "x S");
  t += row("time step dt", significant(x.dt_lab, 3) + " s", significant(x.dt, 3) + " s",
           significant(x.rayleigh_fraction, 3) +
               " x Rayleigh time of the smallest grain (the twin's build_model): grows as S");
  t += row("Young's modulus E", significant(x.youngs_modulus, 3) + " Pa",
           significant(x.youngs_modulus, 3) + " Pa", "kept (the calibration's)");
  t += row("rolling mu_r (epsd2, R*)", significant(x.mu_r, 3), significant(x.mu_r, 3),
           "kept: torque cap mu_r |F_n| R*, R* grows as S, so mu_r is nominally size-free");
  t += row("pile H (cone at " + significant(x.angle_deg, 3) + " deg)", mm(x.lab_pile_height),
           mm(x.pile_height) + ", D " + mm(x.pile_diameter),
           std::string(x.angle_calibrated ? "the calibrated angle"
                                          : "an assumed 35 deg (no calibration)") +
               ", solid fraction " + significant(kAssumedSolidFraction, 2));
  t += row("pile height in grains",
           significant(x.lab_pile_height / (x.d_mean / x.size_scale), 3),
           significant(x.grains_high, 3),
           "H / mass-mean grain; fewer than " + significant(kMinGrainsHigh, 2) + " is refused");
  t += row("overlap/R at the base", pct(x.overlap_lab), pct(x.overlap),
           "closed-form mean (Z " + significant(kAssumedCoordination, 2) +
               "): grows as (H/E)^(2/3), not with S");
  t += row("fall onto the pile", "lifted funnel",
           significant(x.impact_speed, 2) + " m/s",
           "sqrt(2 g (release top - H)); the calibration saw no such impacts");
  t += row("grains", "", significant(x.grains, 3), "dump mass / mean grain mass");
  t += row("ranks", "", "processors " + processors_line(x.grid),
           x.grid[0] == 0 ? "LIGGGHTS chooses x and y, z unsplit"
                          : "run with mpirun -np " + std::to_string(x.grid[0] * x.grid[1]));
  return t;
}

// The field's free dump: the same material block as the lab, no container, grains released at
// a rate from a cylinder above a flat ground, then settled and dumped.
LiggghtsDeck field_dump_deck(const SceneConfig& scene, const LiggghtsDeckSettings& settings) {
  const FieldDumpSettings& f = *settings.field_dump;
  if (settings.initial_state)
    throw InputError("--initial-state: the field deck releases its own grains; a filled sample "
                     "is the lab test's",
                     "--initial-state");
  const FieldScaling x = field_scaling(scene, f, settings.calibration);
  const DeckMaterial m = deck_material(scene, f.size_scale);
  const double g = downward_gravity(scene);
  const double z_lo = f.release_height, z_hi = z_lo + x.release_zone_height;
  const std::array<double, 6> box{-0.5 * f.width, 0.5 * f.width, -0.5 * f.length,
                                  0.5 * f.length, -std::max(0.01, x.d_max),
                                  z_hi + 2.0 * x.d_max};
  const double pour_s = f.mass / f.rate + std::sqrt(2.0 * z_hi / g);

  std::ostringstream in;
  in << header(scene, settings, " --field dump")
     << "# field: a free dump of " << num(f.mass) << " kg at " << num(f.rate) << " kg/s, "
     << "released at rest from a cylinder of radius " << num(x.release_radius) << " m, "
     << num(z_lo) << " to " << num(z_hi) << " m above a flat ground of " << num(f.width)
     << " x " << num(f.length) << " m\n# what is scaled and how (README.md says why):\n";
  std::istringstream table(scaling_table(x));
  for (std::string line; std::getline(table, line);) in << "#   " << line << "\n";
  for (const std::string& w : x.warnings) in << "# WARNING: " << w << "\n";
  in << "# Run: "
     << (x.grid[0] == 0 ? std::string("mpirun -np N liggghts -in in.dump (any N)")
                        : "mpirun -np " + std::to_string(x.grid[0] * x.grid[1]) +
                              " liggghts -in in.dump (that many ranks exactly: the processors "
                              "line is the grid)")
     << "\n";
  write_setup(in, scene, m, processors_line(x.grid), box, false);
  const int k = write_psd(in, m, settings.seed);
  in << "region release cylinder z 0 0 " << num(x.release_radius) << " " << num(z_lo) << " "
     << num(z_hi) << " units box\n"
     << "fix ins all insert/rate/region seed " << prime_seed(settings.seed, 99)
     << " distributiontemplate pdd mass " << num(f.mass) << " massrate " << num(f.rate)
     << " insert_every " << x.insert_every
     << " overlapcheck yes all_in yes vel constant 0 0 0 region release ntry_mc 10000\n";
  const ProcedureConfig& p = scene.procedure;
  write_integration(in, f.mass, p.settle_speed);
  in << "# release: " << num(f.mass / f.rate) << " s of pouring and the last grains' fall from "
     << num(z_hi) << " m\n"
     << "run " << steps_of(pour_s, m.model.dt) << "\n"
     << "unfix ins\n"
     << "# settle, then the grains for `reposetwin measure-particles`\n";
  write_settle(in, "final", p.final_settle_max, m.model.dt);
  in << "write_dump all custom final.dump id type x y z radius\n";

  LiggghtsDeck deck;
  deck.input_name = "in.dump";
  deck.input = in.str();
  deck.scaling = scaling_table(x);
  deck.warnings = x.warnings;

  std::ostringstream md;
  md << "# " << scene.name << ": a free dump in the field, as a LIGGGHTS 3.8 deck\n\n"
     << "Written by `reposetwin export --field dump` from `" << scene.file << "`. Run it with "
     << "`mpirun -np N liggghts -in in.dump`"
     << (x.grid[0] == 0 ? std::string(" (any N)")
                        : " with N = " + std::to_string(x.grid[0] * x.grid[1]) +
                              " exactly (`processors " + processors_line(x.grid) + "`)")
     << "; it ends with `final.dump`, which `reposetwin measure-particles final.dump --scene "
        "SCENE` measures with the twin's own pile measure (H, D, atan(2H/D)).\n\n"
     << install_notes() << calibration_notes(settings.calibration)
     << "## What is scaled and how\n```\n" << deck.scaling << "```\n\n";
  if (!x.warnings.empty()) {
    md << "## Warnings\n";
    for (const std::string& w : x.warnings) md << "- " << w << "\n";
    md << "\n";
  }
  md << "## Carried as it is\n"
     << carried_material_notes(m) << "- dt " << num(m.model.dt)
     << " s: the twin's rule (the same Rayleigh fraction) at the scaled smallest grain; skin "
        "the twin's, scaled.\n"
     << "- The PSD: " << k << " templates, one per sieve interval in ["
     << num(1e3 * m.psd.d_min) << ", " << num(1e3 * m.psd.d_max) << "] mm times S = "
     << num(f.size_scale) << ", of the interval's middle size, by mass fraction; dump mass "
     << num(f.mass) << " kg (the simulated grains).\n"
     << "- The ground: a plane at z = 0 of the plate's material with the calibration's "
        "grain-plate contact (type 3), the only ground the calibration knows.\n"
     << "- Settling: as the twin's (kinetic energy per grain below 1/2 m_mean v^2, v = "
     << num(p.settle_speed) << " m/s), or at most procedure.final_settle_max = "
     << num(p.final_settle_max) << " s after the release.\n\n"
     << "## Assumptions and what is not carried\n"
     << "- mu_r's size-independence: with epsd2 the rolling torque's cap mu_r |F_n| R* and the "
        "gravity torque on a grain both grow as S^4, so a coarse-grained pile keeps its "
        "quasi-static balance at the same mu_r. This is the model's scaling, not a measurement: "
        "the calibration saw grains of "
     << num(1e3 * x.d_min_lab) << " to " << num(1e3 * x.d_max_lab)
     << " mm only, and a pile's angle is the bulk's only when it is many grains high "
        "(fewer than " << num(kMinGrainsHigh) << " is refused, S above " << num(kWarnSizeScale)
     << " is warned of).\n"
     << "- The stiffness: E is the calibration's. The mean overlap at the pile's base grows as "
        "(H/E)^(2/3) (the table's estimate); a field pile much taller than the lab's needs a "
        "stiffer E (`--set numerics.softened_youngs_modulus_pa=...`, times H/H_lab for the lab's "
        "overlap), which shortens dt as E^(-1/2) and which the calibration did not test.\n"
     << "- The procedure: the calibration's pile formed as a funnel was lifted, grains leaving "
        "it slowly; the dump's grains fall onto the pile at about "
     << significant(x.impact_speed, 2)
     << " m/s, and a pile formed under impacts lies flatter the higher its release. mu_r was "
        "calibrated for the lift test: a field dump's angle is a prediction under that "
        "assumption, to be checked against the field's own slopes.\n"
     << "- The release: grains at rest from a cylinder of radius " << num(x.release_radius)
     << " m, inserted every " << x.insert_every
     << " steps (the time to fall through it), not a truck's tipping face or a conveyor's "
        "trajectory.\n"
     << "- The domain's sides are open (`boundary f f f`): a grain that crosses them is lost "
        "(`thermo_modify lost ignore`); the ground is checked to be at least 1.25 times the "
        "expected base.\n"
     << not_carried_law_notes(scene, m)
     << "- Each interval's sizes: the twin draws a clipped normal inside it, the deck uses its "
        "middle size.\n\n"
     << conventions_notes(m.grain.rolling_friction);
  deck.notes = md.str();
  return deck;
}

}  // namespace

RollingConventions rolling_conventions(double mu_r) { return {mu_r, mu_r, mu_r, 0.5 * mu_r}; }

FieldScaling field_scaling(const SceneConfig& scene, const FieldDumpSettings& f,
                           const DeckCalibration* calibration) {
  auto refuse = [](const std::string& option, double value, const std::string& why) {
    throw InputError(option + " " + num(value) + ": " + why, option);
  };
  auto positive = [&](const char* option, double v, const char* unit) {
    if (!(v > 0.0 && std::isfinite(v)))
      refuse(option, v, std::string("must be a positive number [") + unit + "]");
  };
  positive("--dump-mass-kg", f.mass, "kg");
  positive("--dump-rate-kg-s", f.rate, "kg/s");
  positive("--dump-height-m", f.release_height, "m");
  positive("--domain-width-m", f.width, "m");
  positive("--domain-length-m", f.length, "m");
  positive("--size-scale", f.size_scale, "-");
  if (!(f.release_radius >= 0.0 && std::isfinite(f.release_radius)))
    refuse("--release-radius-m", f.release_radius, "must be 0 (chosen) or positive [m]");
  if (f.ranks < 0) refuse("--ranks", f.ranks, "must be 0 (LIGGGHTS chooses) or positive");

  const DeckMaterial lab = deck_material(scene, 1.0);
  const DeckMaterial m = deck_material(scene, f.size_scale);
  const double g = downward_gravity(scene);
  const double S = f.size_scale, rho = m.density, nu = m.t.material[0]->poisson_ratio;
  FieldScaling x;
  x.size_scale = S;
  x.d_min_lab = 2.0 * lab.r_min;
  x.d_max_lab = 2.0 * lab.r_max;
  x.d_min = 2.0 * m.r_min;
  x.d_max = 2.0 * m.r_max;
  for (const sim::PsdInterval& iv : m.psd.intervals) {
    const double d = 0.5 * S * (iv.lower + iv.upper);
    x.d_mean += iv.mass_fraction * d;
    x.grains += iv.mass_fraction * f.mass / (rho * std::numbers::pi * d * d * d / 6.0);
  }
  x.dt_lab = lab.model.dt;
  x.dt = m.model.dt;
  x.rayleigh_fraction = m.model.dt / m.model.rayleigh_time;
  x.youngs_modulus = m.e_used;
  x.angle_calibrated = calibration && calibration->material;
  x.angle_deg = x.angle_calibrated ? calibration->material->target_deg : 35.0;
  const Cone pile = cone_of(f.mass, rho, x.angle_deg);
  const Cone lab_pile = cone_of(scene.mass * m.psd.simulated_mass_factor, rho, x.angle_deg);
  x.pile_height = pile.height;
  x.pile_diameter = pile.diameter;
  x.lab_pile_height = lab_pile.height;
  x.grains_high = pile.height / x.d_mean;
  x.overlap = base_overlap_ratio(rho, g, pile.height, m.e_used, nu);
  x.overlap_lab = base_overlap_ratio(rho, g, lab_pile.height, m.e_used, nu);
  x.mu_r = m.grain.rolling_friction;
  x.grid = processor_grid(f.ranks, f.width, f.length);

  // The release cylinder: 4 largest grains high; an insertion every time a grain at rest takes
  // to fall through it, so each finds the cylinder clear; wide enough to hold one insertion's
  // mass at the insertion volume fraction (with a half grain of wall clearance, all_in).
  x.release_zone_height = 4.0 * x.d_max;
  x.insert_every =
      std::max(1LL, steps_of(std::sqrt(2.0 * x.release_zone_height / g), m.model.dt));
  const double per_insertion = f.rate * static_cast<double>(x.insert_every) * m.model.dt;
  const double vf = LiggghtsDeckSettings{}.insert_volume_fraction;
  const double needed_radius =
      std::max(2.0 * x.d_max, std::sqrt(per_insertion / (vf * rho * std::numbers::pi *
                                                         x.release_zone_height)) +
                                  0.5 * x.d_max);
  if (f.release_radius > 0 && f.release_radius < needed_radius)
    refuse("--release-radius-m", f.release_radius,
           "cannot take " + significant(f.rate, 3) + " kg/s: each insertion (every " +
               std::to_string(x.insert_every) + " steps) is " + significant(per_insertion, 3) +
               " kg, which needs a radius of at least " + significant(needed_radius, 3) +
               " m at the insertion volume fraction " + significant(vf, 2) +
               " (or a lower --dump-rate-kg-s)");
  x.release_radius = f.release_radius > 0 ? f.release_radius : needed_radius;

  x.impact_speed =
      std::sqrt(2.0 * g * std::max(0.0, f.release_height + x.release_zone_height - pile.height));

  // Refusals, each with its numbers.
  const std::string cone_text = "the dump's cone at " + significant(x.angle_deg, 3) + " deg (" +
                                (x.angle_calibrated ? "the calibrated angle" : "an assumed angle") +
                                ") is about " + significant(1e3 * pile.height, 3) + " mm high and " +
                                significant(1e3 * pile.diameter, 3) + " mm across";
  if (x.grains_high < kMinGrainsHigh) {
    const double s_max = S * x.grains_high / kMinGrainsHigh;
    const double m_min = f.mass * std::pow(kMinGrainsHigh / x.grains_high, 3.0);
    const bool scaled = S > 1.0;
    refuse(scaled ? "--size-scale" : "--dump-mass-kg", scaled ? S : f.mass,
           cone_text + ", only " + significant(x.grains_high, 3) +
               " grains high (mass-mean grain " + significant(1e3 * x.d_mean, 3) +
               " mm); a pile fewer than " +
               significant(kMinGrainsHigh, 2) +
               " grains high has the angle of a few grains' stack, not the bulk's the calibration "
               "measured. Give --size-scale at most " +
               significant(s_max, 3) + " for " + significant(f.mass, 3) +
               " kg, or --dump-mass-kg at least " + significant(m_min, 3) + " kg at this scale");
  }
  const double ground = std::min(f.width, f.length);
  if (ground < 1.25 * pile.diameter)
    refuse(f.width <= f.length ? "--domain-width-m" : "--domain-length-m", ground,
           cone_text + "; the ground must be at least 1.25 times its base (" +
               significant(1.25 * pile.diameter, 3) +
               " m), or grains leave the open domain (a flatter pile spreads wider)");
  if (x.release_radius + x.d_max > 0.5 * ground)
    refuse("--release-radius-m", x.release_radius,
           "the release cylinder does not fit the ground (half of " + significant(ground, 3) +
               " m)");
  if (f.release_height < pile.height + x.d_max)
    refuse("--dump-height-m", f.release_height,
           cone_text + "; the release must start above its top (at least " +
               significant(pile.height + x.d_max, 3) + " m)");

  // Warnings, each with its numbers.
  if (S > kWarnSizeScale)
    x.warnings.push_back(
        "--size-scale " + significant(S, 3) + " is above " + significant(kWarnSizeScale, 2) +
        ": the deck's grains (" + significant(1e3 * x.d_min, 3) + " to " +
        significant(1e3 * x.d_max, 3) + " mm) are far outside the sizes the calibration saw (" +
        significant(1e3 * x.d_min_lab, 3) + " to " + significant(1e3 * x.d_max_lab, 3) +
        " mm); mu_r's size-independence is the model's scaling, untested there");
  if (x.overlap > 0.01 && x.overlap > 2.0 * x.overlap_lab)
    x.warnings.push_back(
        "the mean overlap at the pile's base is about " + significant(100.0 * x.overlap, 2) +
        "% of a radius against " + significant(100.0 * x.overlap_lab, 2) +
        "% in the lab pile (E " + significant(x.youngs_modulus, 3) +
        " Pa, closed-form estimate): the soft stiffness the calibration used is strained; E " +
        significant(x.youngs_modulus * pile.height / lab_pile.height, 3) +
        " Pa (--set numerics.softened_youngs_modulus_pa=...) would give the lab's overlap, at "
        "a dt " + significant(std::sqrt(lab_pile.height / pile.height), 3) + " times this one");
  if (x.impact_speed > kWarnImpactSpeed)
    x.warnings.push_back(
        "grains fall onto the pile at about " + significant(x.impact_speed, 2) +
        " m/s (from " + significant(f.release_height + x.release_zone_height, 3) +
        " m onto its expected top): the calibration's pile formed from a lifted funnel without "
        "such impacts, and a dump's pile lies flatter the higher its release (measured: "
        "docs/calibration.md, To the field); mu_r is the lift test's, not a dump's");
  if (m.grain.rolling_size_exponent != 0.0) {
    const double ratio =
        std::pow(x.d_mean / m.grain.rolling_reference_diameter, m.grain.rolling_size_exponent);
    x.warnings.push_back(
        "the scene's rolling law is size-dependent (rolling_size_exponent " +
        significant(m.grain.rolling_size_exponent, 3) + ", reference " +
        significant(1e3 * m.grain.rolling_reference_diameter, 3) +
        " mm): the twin would use mu_r x " + significant(ratio, 3) +
        " at the deck's mass-mean grain; LIGGGHTS' epsd2 carries the constant " +
        significant(x.mu_r, 3));
  }
  return x;
}

LiggghtsDeck liggghts_deck(const SceneConfig& scene, const LiggghtsDeckSettings& settings) {
  if (settings.field_dump) return field_dump_deck(scene, settings);
  return lab_deck(scene, settings);
}

}  // namespace reposetwin::experiments
