#include "experiments/export/liggghts_deck.hpp"

#include <algorithm>
#include <array>
#include <cmath>
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

}  // namespace

RollingConventions rolling_conventions(double mu_r) { return {mu_r, mu_r, mu_r, 0.5 * mu_r}; }

LiggghtsDeck liggghts_deck(const SceneConfig& scene, const LiggghtsDeckSettings& settings) {
  if (!scene.shapes.empty())
    throw InputError(scene.file + ": " + scene.shapes.front().key + " (\"" +
                     scene.shapes.front().name +
                     "\"): grain shapes are not exported yet (LIGGGHTS' multisphere templates "
                     "would carry them); export a sphere scene");
  const ContainerConfig& c = scene.container;
  Types t;
  t.name[0] = scene.sample_material;
  t.name[1] = c.material;
  t.name[2] = scene.plate_material;
  for (int i = 0; i < kTypes; ++i) {
    const int k = material_index(scene, t.name[i], i == 0 ? "sample.material"
                                                    : i == 1 ? "container.material"
                                                             : "plate.material");
    t.material[i] = &scene.materials[static_cast<std::size_t>(k)];
  }
  const sim::ResolvedPsd psd = sim::resolve_psd(scene.psd.spec);
  const auto [r_min, r_max] = grain_radius_range(scene, psd.d_min, psd.d_max);
  const sim::Model model = build_model(scene, r_min, r_max);
  const sim::PairParams& grain = pair_of(scene, t.name[0], t.name[0]);
  const bool cdt = grain.rolling_model == sim::RollingModel::kCdt;
  const double e_soft = scene.settings.softened_youngs_modulus;  // 0: each material's real E
  const double density = t.material[0]->density;
  const double mass = scene.mass * psd.simulated_mass_factor;

  // Geometry: the container's rim heights, the insertion column, the domain.
  const double rb = 0.5 * c.bottom_diameter, rt = 0.5 * c.top_diameter;
  const double zb = c.gap, zt = c.gap + c.height, d_max = psd.d_max;
  // Lifted by its own height, the rim stands above any pile the container could hold.
  const double lift = c.height;
  const double rin_b = std::max(rb - d_max, 0.5 * d_max), rin_t = rt - d_max;
  const double cone = std::numbers::pi * c.height / 3.0 * (rin_b * rin_b + rin_b * rin_t + rin_t * rin_t);
  const double needed = mass / (density * settings.insert_volume_fraction);
  const double column =
      std::max(2.0 * d_max, (needed - cone) / (std::numbers::pi * rin_t * rin_t));
  const double half = std::max(0.3, rt + 0.05), top = zt + column + lift + 0.05;

  std::ostringstream in;
  in << "# LIGGGHTS 3.8 input written by `reposetwin export` from " << scene.file << "\n"
     << "# (scene " << scene.name << "); README.md beside it says what is carried and what not.\n";
  if (const DeckCalibration* cal = settings.calibration)
    in << "# calibrated: mu_r " << num(cal->material->mu_r) << " (95% "
       << num(cal->material->mu_r_lo) << " to " << num(cal->material->mu_r_hi) << ") from "
       << cal->file << "\n";
  in << "# Run: liggghts -in in.pile, or mpirun -np N liggghts -in in.pile\n"
     << "atom_style granular\natom_modify map array\nboundary f f f\nnewton off\n"
     << "communicate single vel yes\nunits si\nprocessors * * 1\n"
     << "region domain block " << num(-half) << " " << num(half) << " " << num(-half) << " "
     << num(half) << " " << num(-0.01) << " " << num(top) << " units box\n"
     << (settings.initial_state ? std::string("read_data initial.data\n")
                                : "create_box " + std::to_string(kTypes) + " domain\n")
     << "neighbor " << num(model.settings.skin > 0 ? model.settings.skin : 0.5 * r_min)
     << " bin\nneigh_modify delay 0\n"
     << "soft_particles yes\n";
  in << "fix m1 all property/global youngsModulus peratomtype";
  for (int i = 0; i < kTypes; ++i)
    in << " " << num(e_soft > 0 ? e_soft : t.material[i]->youngs_modulus);
  in << "\nfix m2 all property/global poissonsRatio peratomtype";
  for (int i = 0; i < kTypes; ++i) in << " " << num(t.material[i]->poisson_ratio);
  in << "\n"
     << per_pair(scene, t, "m3", "coefficientRestitution", &sim::PairParams::restitution)
     << per_pair(scene, t, "m4", "coefficientFriction", &sim::PairParams::friction)
     << per_pair(scene, t, "m5", "coefficientRollingFriction", &sim::PairParams::rolling_friction);
  const std::string law = std::string("model hertz tangential history rolling_friction ") +
                          (cdt ? "cdt" : "epsd2");
  in << "pair_style gran " << law << "\npair_coeff * *\n"
     << "timestep " << num(model.dt) << "\n"
     << "fix gravi all gravity " << num(-scene.settings.gravity.z()) << " vector 0.0 0.0 -1.0\n"
     << "fix plate all wall/gran " << law << " primitive type 3 zplane 0.0\n"
     << "fix cad all mesh/surface file container.stl type 2\n"
     << "fix walls all wall/gran " << law << " mesh n_meshes 1 meshes cad\n";

  // The PSD: one template per sieve interval, mixed by mass, and the sample inserted (unless it
  // is read from an initial state).
  int k = 0;
  if (!settings.initial_state) {
    std::string mix;
    for (const sim::PsdInterval& iv : psd.intervals) {
      if (iv.mass_fraction <= 0) continue;
      ++k;
      in << "fix pts" << k << " all particletemplate/sphere " << prime_seed(settings.seed, k)
         << " atom_type 1 density constant " << num(density) << " radius constant "
         << num(0.25 * (iv.lower + iv.upper)) << "\n";
      mix += " pts" + std::to_string(k) + " " + num(iv.mass_fraction);
    }
    in << "fix pdd all particledistribution/discrete/massbased " << prime_seed(settings.seed, 0)
       << " " << k << mix << "\n";
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
  in << "fix integr all nve/sphere\n"
     << "compute rke all erotate/sphere\n"
     << "thermo_style custom step atoms ke c_rke\n"
     << "thermo_modify lost ignore norm no\n";
  auto steps = [&](double seconds) { return static_cast<long long>(std::ceil(seconds / model.dt)); };
  const ProcedureConfig& p = scene.procedure;
  // Settling ends as the twin's does: when the kinetic energy per grain falls below
  // 1/2 m_mean v^2 (v = procedure.settle_speed_m_s), that is the total below 1/2 M v^2, checked
  // every `chunk` steps (a thermo step, so `ke` is current), or at the phase's time limit.
  const long long chunk = 1000;
  auto settle = [&](const std::string& label, double max_s) {
    const long long n = std::max(1LL, steps(max_s) / chunk);
    in << "variable " << label << "_n loop " << n << "\n"
       << "label " << label << "\n"
       << "run " << chunk << "\n"
       << "if \"${ke_now} < ${ke_stop}\" then \"jump SELF " << label << "_done\"\n"
       << "next " << label << "_n\n"
       << "jump SELF " << label << "\n"
       << "label " << label << "_done\n"
       << "variable " << label << "_n delete\n";
  };
  in << "variable ke_now equal ke\n"
     << "variable ke_stop equal " << num(0.5 * mass * p.settle_speed * p.settle_speed) << "\n"
     << "thermo " << chunk << "\n"
     << (settings.initial_state ? "# the twin's filled sample settles under this engine's laws\n"
                                : "# fill: the sample falls into the container and settles\n");
  settle("fill", p.fill_settle_max);
  in << "# lift at " << num(p.lift_speed) << " m/s until the rim is " << num(lift)
     << " m higher\n"
     << "fix lift all move/mesh mesh cad linear 0.0 0.0 " << num(p.lift_speed) << "\n"
     << "run " << steps(lift / p.lift_speed) << "\n"
     << "unfix lift\n"
     << "# settle, then the grains for `reposetwin measure-particles`\n";
  settle("final", p.final_settle_max);
  in << "write_dump all custom final.dump id type x y z radius\n";

  LiggghtsDeck deck;
  deck.input = in.str();
  if (settings.initial_state)
    deck.initial_data = initial_data(scene, *settings.initial_state, t, density,
                                     {-half, half, -half, half, -0.01, top});
  deck.funnel_stl = frustum_stl(rb, rt, zb, zt, settings.facets);

  const RollingConventions mu = rolling_conventions(grain.rolling_friction);
  std::ostringstream md;
  md << "# " << scene.name << " as a LIGGGHTS 3.8 deck\n\n"
     << "Written by `reposetwin export` from `" << scene.file << "`. Run it with "
     << "`liggghts -in in.pile` or `mpirun -np N liggghts -in in.pile`; it ends with "
     << "`final.dump`, which `reposetwin measure-particles final.dump --scene SCENE` measures "
        "with the twin's own pile measure (H, D, atan(2H/D)).\n\n"
     << "Installing LIGGGHTS on the machine that builds the twin: `sudo apt-get install "
        "--no-install-recommends liggghts`. With its recommended packages, Debian's liggghts "
        "pulls in paraview and python3-paraview, which conflicts with python3-vtk9: apt then "
        "removes python3-vtk9 and libvtk9-dev, and the twin no longer builds "
        "(`apt-get -s install liggghts` shows it beforehand).\n\n"
     << calibration_notes(settings.calibration)
     << "## Carried as it is\n"
     << "- Hertz-Mindlin with history; E " << num(e_soft > 0 ? e_soft : t.material[0]->youngs_modulus)
     << " Pa" << (e_soft > 0 ? " (the scene's softened E, for every material, as the twin)" : "")
     << "; nu, e, mu_s and mu_r per material pair (types 1 " << t.name[0] << ", 2 " << t.name[1]
     << ", 3 " << t.name[2] << ").\n"
     << "- Rolling: " << (cdt ? "cdt" : "epsd2 (the twin's epsd: k_r = k_t R*^2, cap mu_r |F_n| R*)")
     << ".\n- dt " << num(model.dt) << " s (the twin's), skin as the twin's.\n"
     << (settings.initial_state
             ? "- The sample as the twin filled it: " +
                   std::to_string(settings.initial_state->x.size()) +
                   " grains, each with its position and size, read from `initial.data`.\n"
             : "- The PSD: " + std::to_string(k) + " templates, one per sieve interval in [" +
                   num(1e3 * psd.d_min) + ", " + num(1e3 * psd.d_max) +
                   "] mm, of the interval's middle size, by mass fraction; sample mass " +
                   num(mass) + " kg.\n")
     << "- The container (" << c.kind << ", " << num(c.bottom_diameter) << " to "
     << num(c.top_diameter) << " m, " << num(c.height) << " m high, " << num(c.gap)
     << " m above the plate) as `container.stl`, lifted at " << num(p.lift_speed) << " m/s.\n\n"
     << "## Not carried\n";
  // One line a pair as the scene names it: the contacts map holds each pair in both orders.
  for (const auto& names : scene.contact_pairs)
    if (const sim::PairParams& p = scene.contacts.at(names);
        p.rolling_model == sim::RollingModel::kEpsd && p.rolling_damping > 0)
      md << "- The rolling dashpot of contacts." << names.first << "-" << names.second
         << ": rolling_damping eta_r = " << num(p.rolling_damping)
         << " has no counterpart in epsd2; run the twin with `--set contacts." << names.first
         << "-" << names.second << ".rolling_damping=0` to compare like with like.\n";
  if (cdt)
    md << "- cdt: the twin's uses each body's own angular velocity and radius (EDEM Standard); "
          "LIGGGHTS' uses w_i - w_j and R*.\n";
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
     << "## The rolling coefficient in other conventions (equal spheres)\n"
     << "| engine | model | mu_r |\n|---|---|---|\n"
     << "| ReposeTwin | epsd (lever arm R* = R_i R_j / (R_i + R_j)) | " << num(mu.ours) << " |\n"
     << "| LIGGGHTS 3.8 | rolling_friction epsd2 / cdt (R*) | " << num(mu.liggghts) << " |\n"
     << "| LAMMPS | pair granular, rolling sds, mu_roll (R_eff = R*) | " << num(mu.lammps) << " |\n"
     << "| EDEM | rolling friction (each body's own radius R = 2 R*) | " << num(mu.edem) << " |\n\n"
     << "Between unequal spheres R* is smaller than either radius, so no single EDEM value "
        "matches every pair; the table holds for the equal spheres of a narrow sieve class.\n";
  deck.notes = md.str();
  return deck;
}

}  // namespace reposetwin::experiments
