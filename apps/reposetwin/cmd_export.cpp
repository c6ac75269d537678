// `export`: the calibrated scene as a LIGGGHTS deck; `measure-particles`: another engine's
// grains measured by the twin's pile measure (experiments/export/).
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "apps/reposetwin/commands.hpp"
#include "apps/reposetwin/validators.hpp"
#include "experiments/calibration/calibration_file.hpp"
#include "experiments/io/calibration_record.hpp"
#include "experiments/io/format.hpp"
#include "experiments/io/hash.hpp"
#include "experiments/pile/headline.hpp"
#include "experiments/export/liggghts_deck.hpp"
#include "experiments/export/particle_dump.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/io/scene_overrides.hpp"
#include "experiments/pile/run_folder.hpp"
#include "sim/pile_geometry.hpp"

namespace reposetwin::cli {
namespace fs = std::filesystem;

void add_export_command(CLI::App& app) {
  struct Args {
    std::string scene, out, initial;
    std::vector<std::string> sets;
    std::uint64_t seed = 1;
    bool force = false;
    std::string field;
    experiments::FieldDumpSettings dump;
  };
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "export", "Write a calibration's material (its folder) or a scene as a LIGGGHTS 3.8 input "
                "deck: in.pile, container.stl and README.md (the calibrated mu_r and its "
                "interval, what is carried, and mu_r in other conventions); with --field dump, "
                "a field-scale free dump (in.dump) and what it scales");
  cmd->add_option("scene", a->scene,
                  "A calibration's folder (the --out of `reposetwin calibrate`: its scene, "
                  "sieve sheet and calibrated mu_r, nothing retyped), or a scene file")
      ->required();
  cmd->add_option("--out,-o", a->out,
                  "Folder for the deck (default for a calibration folder: FOLDER/liggghts)");
  cmd->add_option("--set", a->sets, "Override a scene key: dotted.key=value (repeatable)");
  cmd->add_option("--seed", a->seed, "Seed of LIGGGHTS' random streams")
      ->check(seed_number())  // checked as typed: -1 would wrap to 2^64 - 1
      ->capture_default_str();
  cmd->add_option("--initial-state", a->initial,
                  "Start from the twin's filled sample (a run's frames/filled.vtp) instead of "
                  "inserting one: the two engines then compare the pour from one state");
  cmd->add_flag("--force", a->force, "Replace a deck already in --out");
  // The field deck (experiments/export/liggghts_deck.hpp): its geometry in SI units, defaults a
  // small verification dump, each refused by field_scaling naming the option and the value.
  auto* field =
      cmd->add_option("--field", a->field,
                      "Write a field-scale deck instead of the lab test: 'dump' (a free dump "
                      "forming a large pile on a flat ground, in.dump). It carries the calibrated "
                      "material as the lab deck does and prints what is scaled and how (grain "
                      "size, dt, E, mu_r's convention), refusing a pile fewer than 10 grains "
                      "high. Default --out for a calibration folder: FOLDER/liggghts_dump");
  cmd->add_option("--dump-mass-kg", a->dump.mass, "Field dump: total mass released [kg]")
      ->check(plain_number())
      ->capture_default_str()
      ->needs(field);
  cmd->add_option("--dump-rate-kg-s", a->dump.rate, "Field dump: release rate [kg/s]")
      ->check(plain_number())
      ->capture_default_str()
      ->needs(field);
  cmd->add_option("--dump-height-m", a->dump.release_height,
                  "Field dump: height of the release above the ground [m]")
      ->check(plain_number())
      ->capture_default_str()
      ->needs(field);
  cmd->add_option("--release-radius-m", a->dump.release_radius,
                  "Field dump: radius of the release cylinder; 0: the smallest that takes the "
                  "rate [m]")
      ->check(plain_number())
      ->capture_default_str()
      ->needs(field);
  cmd->add_option("--domain-width-m", a->dump.width, "Field dump: the ground along x [m]")
      ->check(plain_number())
      ->capture_default_str()
      ->needs(field);
  cmd->add_option("--domain-length-m", a->dump.length, "Field dump: the ground along y [m]")
      ->check(plain_number())
      ->capture_default_str()
      ->needs(field);
  cmd->add_option("--size-scale", a->dump.size_scale,
                  "Field dump: coarse-graining factor S, every grain's diameter times S; dt "
                  "grows as S, mu_r is kept (warned above 3) [-]")
      ->check(plain_number())
      ->capture_default_str()
      ->needs(field);
  cmd->add_option("--ranks", a->dump.ranks,
                  "Field dump: MPI ranks the deck is split for (processors px py 1, run with "
                  "exactly that many); 0: processors * * 1, any number")
      ->check(integer_number())
      ->capture_default_str()
      ->needs(field);
  cmd->footer(
      "To the field: `reposetwin export CAL_FOLDER --field dump --ranks 2` writes "
      "CAL_FOLDER/liggghts_dump/in.dump; run it with `mpirun -np 2 liggghts -in in.dump`. The "
      "table it prints says what is scaled (grain size by --size-scale, dt with it, E and mu_r "
      "kept) and what the scaling strains. Install LIGGGHTS with `apt-get install "
      "--no-install-recommends liggghts`: its recommended paraview removes the VTK the twin "
      "builds with. scripts/verify_field_deck.sh runs a reduced dump on 1 and 2 ranks.");
  cmd->callback([a]() {
    if (!a->field.empty() && a->field != "dump")
      throw experiments::InputError("--field " + a->field +
                                        ": not a field deck this version writes; the one written "
                                        "is 'dump' (a free dump forming a pile)",
                                    "--field");
    if (!a->field.empty() && !a->initial.empty())
      throw experiments::InputError("--initial-state " + a->initial +
                                        ": the field deck releases its own grains; a filled "
                                        "sample is the lab test's (drop --initial-state or "
                                        "--field)",
                                    "--initial-state");
    const bool field = !a->field.empty();
    std::error_code dir_ec;
    const bool from_calibration = fs::is_directory(a->scene, dir_ec);
    std::optional<experiments::CalibratedMaterial> material;
    experiments::DeckCalibration calibration;
    std::string out_folder = a->out;
    std::vector<std::string> inputs = {a->scene};
    experiments::SceneConfig scene;
    if (from_calibration) {
      material = experiments::read_calibrated_material(a->scene);
      calibration.material = &*material;
      calibration.file = (fs::path(a->scene) / experiments::kCalibrationRecordFile).string();
      experiments::SceneDoc doc(material->scene, material->scene_overrides(),
                                "the calibration " + calibration.file);
      doc.apply_command_line(a->sets);
      scene = doc.config_after_command_line();
      for (const std::string& key : material->keys)
        calibration.deck_values.emplace_back(key, doc.number(key).value_or(material->mu_r));
      if (out_folder.empty())
        out_folder = (fs::path(a->scene) / (field ? "liggghts_dump" : "liggghts")).string();
      inputs = {calibration.file, material->scene};
      if (!material->sieve_sheet.empty()) inputs.push_back(material->sieve_sheet);
    } else {
      std::error_code ec;
      if (!fs::exists(a->scene, ec))
        throw experiments::InputError(a->scene + ": no such calibration folder or scene file");
      if (out_folder.empty())
        throw experiments::InputError("export " + a->scene +
                                      ": --out is required with a scene file (the folder for "
                                      "the deck)");
      scene = experiments::load_scene(a->scene, a->sets);
    }
    experiments::check_output_folder(out_folder);
    experiments::LiggghtsDeckSettings s;
    s.seed = a->seed;
    if (from_calibration) s.calibration = &calibration;
    if (field) s.field_dump = &a->dump;
    std::optional<experiments::SnapshotParticles> initial;
    if (!a->initial.empty()) {
      try {
        initial = experiments::read_vtp(a->initial);
      } catch (const std::exception& e) {
        throw experiments::InputError(std::string("--initial-state: ") + e.what());
      }
      // The filled sample of another scene (another PSD, container or material) would start
      // this scene's pour from a state it cannot make: refused by the scene identity the
      // snapshot records.
      const std::string here = experiments::fnv1a_hex(scene.resolved_toml);
      const std::string recorded = initial->info ? initial->info->scene_fnv1a : std::string();
      if (recorded.empty())
        throw experiments::InputError(
            a->initial + ": --initial-state: the snapshot records no scene identity (not a "
                         "twin's frames/filled.vtp, or made by an older version); run the scene "
                         "again and give its frames/filled.vtp");
      if (recorded != here)
        throw experiments::InputError(
            a->initial + ": --initial-state: the snapshot is of another scene (resolved scene "
                         "hash " + recorded + ", " + a->scene + " with these --set is " + here +
            "); give the filled.vtp of a run of this scene");
      s.initial_state = &*initial;
    }
    experiments::LiggghtsDeck deck;
    try {
      deck = experiments::liggghts_deck(scene, s);
    } catch (const experiments::InputError& e) {
      if (a->initial.empty()) throw;
      throw experiments::InputError(a->initial + ": " + e.what());
    }
    const fs::path out(out_folder);
    if (fs::exists(out / deck.input_name) && !a->force)
      throw experiments::InputError(out_folder + ": holds a deck already (" + deck.input_name +
                                    "); --force replaces it");
    // --out may be a folder of the user's (`--out .` beside their own README.md): every file of
    // the deck is checked against the inputs and the folder before one is written.
    const std::vector<std::pair<std::string, const std::string*>> files = {
        {deck.input_name, &deck.input},
        {"container.stl", deck.funnel_stl.empty() ? nullptr : &deck.funnel_stl},
        {"README.md", &deck.notes},
        {"initial.data", deck.initial_data.empty() ? nullptr : &deck.initial_data}};
    experiments::OutputPlan plan(a->force);
    for (const std::string& in : inputs) plan.add_input(in);
    if (!a->initial.empty()) plan.add_input(a->initial);
    for (const auto& [name, text] : files)
      if (text) plan.add_output((out / name).string(), "--out");
    plan.check();
    std::error_code ec;
    fs::create_directories(out, ec);
    if (ec)
      throw experiments::InputError(out_folder + ": cannot create the folder: " + ec.message());
    for (const auto& [name, text] : files)
      if (text) plan.write((out / name).string(), *text);
    if (field) {
      std::cout << "What the field deck scales and how:\n" << deck.scaling;
      for (const std::string& w : deck.warnings) std::cout << "WARNING: " << w << "\n";
      std::cout << "LIGGGHTS field deck (free dump) of " << scene.name;
      if (material)
        std::cout << " at the calibrated mu_r " << experiments::significant(material->mu_r, 3)
                  << " (95% " << experiments::significant(material->mu_r_lo, 3) << " to "
                  << experiments::significant(material->mu_r_hi, 3) << ")";
      std::cout << " in " << out_folder << ": run `"
                << (a->dump.ranks > 0 ? "mpirun -np " + std::to_string(a->dump.ranks)
                                      : std::string("mpirun -np N"))
                << " liggghts -in in.dump` there\n";
      return;
    }
    std::cout << "LIGGGHTS deck of " << scene.name;
    if (material)
      std::cout << " at the calibrated mu_r " << experiments::significant(material->mu_r, 3)
                << " (95% " << experiments::significant(material->mu_r_lo, 3) << " to "
                << experiments::significant(material->mu_r_hi, 3) << ", " << calibration.file
                << ")";
    std::cout << " in " << out_folder
              << ": run `liggghts -in in.pile` there (mpirun -np N for more cores)\n";
  });
}

void add_measure_particles_command(CLI::App& app) {
  struct Args {
    std::string dump, scene;
    std::vector<std::string> sets;
    bool json = false;
  };
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "measure-particles",
      "Measure a pile from another engine's grains (a LAMMPS/LIGGGHTS dump custom with x y z "
      "radius) or a twin snapshot (.vtp) with the twin's particle measure: H, D, atan(2H/D)");
  cmd->add_option("dump", a->dump, "Dump file (the last snapshot is measured)")->required();
  cmd->add_option("--scene", a->scene, "Scene whose [measure] settings apply")->required();
  cmd->add_option("--set", a->sets, "Override a scene key (repeatable)");
  cmd->add_flag("--json", a->json, "Print the measurement as JSON");
  cmd->callback([a]() {
    const experiments::SceneConfig scene = experiments::load_scene(a->scene, a->sets);
    const experiments::ParticleDump d = experiments::read_particles(a->dump);
    const sim::PileGeometry g = sim::measure_pile(d.x, d.radius, scene.pile);
    // The run's own rule (pile/headline.hpp): a pile too small or degenerate to fit a flank
    // (one grain, a flat layer) has no angle, never a number from its bounding box.
    const std::optional<experiments::NoHeadline> none =
        experiments::no_headline(experiments::RunStop{}, experiments::pile_measure(g));
    const double deg = 180.0 / 3.14159265358979323846;
    if (a->json) {
      std::cout << nlohmann::json{{"dump", a->dump},
                                  {"timestep", d.timestep},
                                  {"particles", d.x.size()},
                                  {"status", sim::to_string(g.status)},
                                  {"height_m", g.height},
                                  {"base_diameter_m", g.base_diameter},
                                  {"theta_hd_deg", g.theta_hd * deg},
                                  {"slice_angle_mean_deg", g.slice_angle_mean * deg},
                                  {"pile_count", g.pile_count},
                                  {"no_headline", none ? nlohmann::json(none->message)
                                                       : nlohmann::json()}}
                       .dump(2)
                << "\n";
      if (none) set_exit_code(ExitCode::kNoPile);
      return;
    }
    if (none) {
      std::cout << "no angle: " << a->dump << " " << none->message << "\n";
      set_exit_code(ExitCode::kNoPile);
      return;
    }
    std::printf("particle atan(2H/D) %.2f deg; H %.1f mm, D %.1f mm; %zu of %zu grains in the "
                "pile; slice angle %.2f deg\n",
                g.theta_hd * deg, 1e3 * g.height, 1e3 * g.base_diameter, g.pile_count,
                d.x.size(), g.slice_angle_mean * deg);
  });
}

}  // namespace reposetwin::cli
