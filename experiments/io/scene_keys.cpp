#include "experiments/io/scene_keys.hpp"

#include <cctype>

#include "experiments/io/format.hpp"
#include "experiments/io/grain_shape.hpp"
#include "experiments/io/scene.hpp"

namespace reposetwin::experiments {
namespace {

std::string n(double v) { return significant(v); }
std::string q(const std::string& s) { return "\"" + s + "\""; }

// [scene].
std::vector<SceneKey> scene_table_keys() {
  const SceneConfig scene;
  return {
      {"scene.name", "string", "required", "-", "the scene's name (run folders and reports)"},
      {"scene.description", "string", q(""), "-", "one line on what the scene is"},
      {"scene.seed", "integer", std::to_string(scene.seed), "-",
       "seed of the PSD draw and the fill lattice (same seed, same run)"},
  };
}

// [materials.<name>].
std::vector<SceneKey> material_keys() {
  const sim::Material m;
  return {
      {"materials.<name>", "table", "required (one at least)", "-",
       "a material, named by its key; sample, container and plate name one"},
      {"materials.<name>.density_kg_m3", "number", n(m.density), "kg/m^3",
       "solid density (ignored for wall materials)"},
      {"materials.<name>.youngs_modulus_pa", "number", n(m.youngs_modulus), "Pa",
       "the material's real Young's modulus (numerics.softened_youngs_modulus_pa replaces it)"},
      {"materials.<name>.poisson_ratio", "number", n(m.poisson_ratio), "-",
       "Poisson's ratio, in (-1, 0.5)"},
  };
}

// [sample] and its sieve table (the grain shapes are shape_keys()).
std::vector<SceneKey> sample_keys() {
  const sim::PsdSpec psd;
  const SceneConfig scene;
  return {
      {"sample.mass_kg", "number", "required", "kg", "mass of the (scalped) sample poured"},
      {"sample.material", "string", q(scene.sample_material), "-", "the sample's material"},
      {"sample.psd_file", "string", "-", "-",
       "sieve-table file: TOML with a [psd] table, or a CSV sieve sheet with the header "
       "sieve_mm,passing_percent; relative to the scene file's folder (typed with --set: to the "
       "working folder); or an inline [sample.psd]"},
      {"sample.psd", "table", "-", "-", "inline sieve table (or sample.psd_file), keys below"},
      {"sample.psd.name", "string", q(""), "-", "name of the grading"},
      {"sample.psd.provenance", "string", q(""), "-", "where the sieve table comes from"},
      {"sample.psd.assumption", "string", q(""), "-", "what in it is assumed, not measured"},
      {"sample.psd.sieve_mm", "array of numbers", "required", "mm", "sieve sizes, increasing"},
      {"sample.psd.passing_percent", "array of numbers", "required", "%",
       "cumulative percent passing each sieve, increasing to 100"},
      {"sample.psd.d_max_mm", "number", "the largest sieve", "mm",
       "scalping size: coarser material removed, curve renormalised at d_max"},
      {"sample.psd.d_min_mm", "number", "the smallest sieve", "mm",
       "cut-off: finer material is not simulated (the particle count grows as d_min^-3)"},
      {"sample.psd.fines", "string", q(sim::to_string(psd.fines)), "-",
       "\"renormalise\" (the simulated sizes make up the whole mass) or \"drop\" (the mass "
       "below d_min is left out)"},
      {"sample.psd.interval_sd_fraction", "number", n(psd.interval_sd_fraction), "-",
       "sd of the clipped normal drawn in each sieve interval, as a fraction of its width"},
      {"sample.d_min_mm", "number", "the PSD's d_min_mm", "mm",
       "overrides the sieve table's cut-off (the key a large run is shrunk with)"},
      {"sample.d_max_mm", "number", "the PSD's d_max_mm", "mm",
       "overrides the sieve table's scalping size"},
  };
}

// The keys of one grain shape (io/grain_shape.hpp), under `table` ("sample.shape" or
// "sample.shapes[<k>]"); `mass_fraction_default` differs between the two.
std::vector<SceneKey> one_shape_keys(const std::string& table,
                                     const std::string& mass_fraction_default) {
  const GrainShape g;
  const std::string t = table + ".";
  return {
      {t + "name", "string", q("shape <k>") + " (k from 0)", "-",
       "the shape's name in results and messages"},
      {t + "kind", "string", "required", "-",
       "\"template\" (offsets and radii as given), \"generated\" (rods and slabs: elongation, "
       "flatness, spheres, roundness) or \"blocky\" (rounded boxes: elongation, flatness, "
       "angularity)"},
      {t + "mass_fraction", "number", mass_fraction_default, "-",
       "share of the sample's mass drawn as this shape, in [0, 1]; the shapes' shares sum to 1"},
      {t + "offsets", "array of [x, y, z]", "required (template)", "any length",
       "component centres; the template is scaled so its intermediate extent is the sieve size"},
      {t + "radii", "array of numbers", "required (template)", "as offsets",
       "component radii, > 0, one per offset; the components must make one connected body"},
      {t + "elongation", "number", n(g.elongation), "-",
       "generated, blocky: L/I, longest over intermediate principal extent, >= 1"},
      {t + "flatness", "number", n(g.flatness), "-",
       "generated, blocky: I/S, intermediate over shortest extent, >= 1 (generated: > 1 makes "
       "two rows of spheres)"},
      {t + "spheres", "integer", "required (generated)", "-",
       "generated: component spheres, 1 to 64 (even for flatness > 1; 2 per row at least for "
       "elongation > 1)"},
      {t + "roundness", "number", n(g.roundness), "-",
       "generated: end radius / thickest radius, in (0, 1] (1: capsule; smaller: tapered ends)"},
      {t + "angularity", "number", n(g.angularity), "-",
       "blocky: 1 - edge radius / (S/2), in [0, 1) (0: edges rounded with half the shortest "
       "extent; higher: sharper edges, built of more spheres)"},
  };
}

// [sample.shape] and [[sample.shapes]]: absent, the grains are spheres.
std::vector<SceneKey> shape_keys() {
  std::vector<SceneKey> keys = {
      {"sample.shape", "table", "-", "-",
       "every grain a rigid clump of this one shape, keys below (with neither this nor "
       "sample.shapes, every grain is a sphere)"},
  };
  for (SceneKey& k : one_shape_keys("sample.shape", "1")) keys.push_back(std::move(k));
  keys.push_back({"sample.shapes", "array of tables", "-", "-",
                  "a mix of clump shapes by mass fraction, one [[sample.shapes]] each (not with "
                  "sample.shape); keys below"});
  for (SceneKey& k :
       one_shape_keys("sample.shapes[<k>]", "required (1 when there is one shape)"))
    keys.push_back(std::move(k));
  return keys;
}

// [contacts.<a>-<b>].
std::vector<SceneKey> contact_keys() {
  const sim::PairParams pp;
  return {
      {"contacts.<a>-<b>", "table", "required for every pair the test uses", "-",
       "contact parameters of materials a and b (symmetric)"},
      {"contacts.<a>-<b>.restitution", "number", n(pp.restitution), "-",
       "coefficient of restitution e, in (0, 1]"},
      {"contacts.<a>-<b>.friction", "number", n(pp.friction), "-", "sliding friction mu_s"},
      {"contacts.<a>-<b>.rolling_friction", "number", n(pp.rolling_friction), "-",
       "rolling friction mu_r (its meaning depends on rolling_model: README)"},
      {"contacts.<a>-<b>.rolling_model", "string", q("epsd"), "-",
       "\"epsd\" (elastic-plastic spring-dashpot, lever R*) or \"cdt\" (constant torque, EDEM)"},
      {"contacts.<a>-<b>.rolling_damping", "number", n(pp.rolling_damping), "-",
       "EPSD viscous damping ratio eta_r"},
      {"contacts.<a>-<b>.cohesion_energy_density", "number", n(pp.cohesion_energy_density), "J/m^3",
       "simplified-JKR cohesion k_c; 0 = none"},
      {"contacts.<a>-<b>.rolling_size_exponent", "number", n(pp.rolling_size_exponent), "-",
       "alpha of mu_r,eff = mu_r (d_c/d_ref)^alpha; 0 = mu_r at every size"},
      {"contacts.<a>-<b>.rolling_reference_diameter_m", "number", n(pp.rolling_reference_diameter),
       "m", "d_ref of the size-dependent rolling (> 0 if alpha != 0)"},
  };
}

// [container] and [plate].
std::vector<SceneKey> container_keys() {
  const ContainerConfig c;
  const SceneConfig scene;
  return {
      {"container.kind", "string", q(c.kind), "-", "\"funnel\" (frustum) or \"cylinder\""},
      {"container.material", "string", q(c.material), "-", "the container's material"},
      {"container.bottom_diameter_m", "number", n(c.bottom_diameter), "m", "outlet diameter W"},
      {"container.top_diameter_m", "number", n(c.top_diameter), "m",
       "top diameter (funnel only; a cylinder's is its bottom)"},
      {"container.height_m", "number", n(c.height), "m", "the container's height"},
      {"container.gap_m", "number", n(c.gap), "m", "clearance between its rim and the plate"},
      {"plate.material", "string", q(scene.plate_material), "-", "the base plate's material"},
  };
}

// [procedure].
std::vector<SceneKey> procedure_keys() {
  const ProcedureConfig p;
  return {
      {"procedure.lift_speed_m_s", "number", n(p.lift_speed), "m/s", "container lift speed"},
      {"procedure.settle_speed_m_s", "number", n(p.settle_speed), "m/s",
       "settled when KE per particle < 1/2 m_mean v^2 with this v"},
      {"procedure.fill_settle_max_s", "number", n(p.fill_settle_max), "s",
       "longest settling inside the container"},
      {"procedure.final_settle_max_s", "number", n(p.final_settle_max), "s",
       "longest settling after the container is empty"},
      {"procedure.max_time_s", "number", n(p.max_time), "s", "simulated-time limit of the run"},
      {"procedure.clog_window_s", "number", n(p.clog_window), "s",
       "flow stopped if the count inside does not change for this long"},
      {"procedure.max_retained_fraction", "number", n(p.max_retained_fraction), "-",
       "at most this fraction stuck inside is lifted away; more is a clog"},
      {"procedure.lattice_gap", "number", n(p.lattice_gap), "-",
       "fill lattice spacing = d_max (1 + this)"},
      {"procedure.fill_jitter", "number", n(p.fill_jitter), "-",
       "grains moved off the lattice by up to this fraction of their room (seeded)"},
      {"procedure.fill_max_speed_m_s", "number", n(p.fill_max_speed), "m/s",
       "speeds capped at this while filling (a gentle pour)"},
  };
}

// [numerics].
std::vector<SceneKey> numerics_keys() {
  const sim::Settings s;
  return {
      {"numerics.rayleigh_fraction", "number", n(s.rayleigh_fraction), "-",
       "dt as a fraction of the smallest particle's Rayleigh time (clumps: of the sphere of the "
       "smallest grain's volume, at most 0.5 of its smallest sphere's)"},
      {"numerics.time_step_s", "number", n(s.time_step), "s",
       "explicit dt; 0 = from rayleigh_fraction"},
      {"numerics.softened_youngs_modulus_pa", "number", n(s.softened_youngs_modulus), "Pa",
       "E used for every material; 0 = each material's real E"},
      {"numerics.skin_m", "number", n(s.skin), "m",
       "Verlet skin; 0 = a quarter of the smallest diameter"},
      {"numerics.threads", "integer", std::to_string(s.threads), "-",
       "OpenMP threads; 0 = OpenMP's default (run --threads overrides)"},
      {"numerics.gravity_m_s2", "number", n(-s.gravity.z()), "m/s^2",
       "gravity, downward (> 0: no pile forms without it)"},
      {"numerics.max_overlap_ratio", "number", n(s.max_overlap_ratio), "-",
       "overlap / smaller radius above this stops the run (blow-up guard)"},
      {"numerics.initial_overlap_tolerance", "number", n(s.initial_overlap_tolerance), "-",
       "largest overlap allowed at the start"},
      {"numerics.escape_distance_m", "number", "max(1, 10 x container height)", "m",
       "a particle farther than this from the origin has escaped (a physics stop)"},
  };
}

// [output].
std::vector<SceneKey> output_keys() {
  const OutputConfig o;
  return {
      {"output.frame_interval_s", "number", n(o.frame_interval), "s",
       "simulated time between series.pvd frames; 0 = the final state only"},
      {"output.checkpoint_interval_s", "number", n(o.checkpoint_interval), "s",
       "wall time between checkpoints"},
      {"output.progress_interval_s", "number", n(o.progress_interval), "s",
       "wall time between progress lines"},
      {"output.contact_forces", "boolean", o.contact_forces ? "true" : "false", "-",
       "also write every frame's particle contacts (force per pair) for ParaView; the last "
       "frame always has them"},
  };
}

// [measure].
std::vector<SceneKey> measure_keys() {
  const sim::PileGeometrySettings g;
  return {
      {"measure.slice_azimuths", "integer", std::to_string(g.slice_azimuths), "-",
       "protractor slices over 180 degrees (>= 8)"},
      {"measure.flank_low", "number", n(g.flank_low), "-",
       "lower end of the flank fit, fraction of H"},
      {"measure.flank_high", "number", n(g.flank_high), "-",
       "upper end of the flank fit, fraction of H"},
      {"measure.sectors", "integer", std::to_string(g.sectors), "-",
       "azimuth sectors of the footprint (>= 4)"},
  };
}

std::vector<SceneKey> build_keys() {
  std::vector<SceneKey> keys;
  for (auto* table : {scene_table_keys, material_keys, sample_keys, shape_keys, contact_keys,
                      container_keys, procedure_keys, numerics_keys, output_keys, measure_keys})
    for (SceneKey& k : table()) keys.push_back(std::move(k));
  return keys;
}

// "|" would end a Markdown table cell.
std::string cell(std::string s) {
  for (std::size_t i = 0; (i = s.find('|', i)) != std::string::npos; i += 2) s.replace(i, 1, "\\|");
  return s;
}

}  // namespace

const std::vector<SceneKey>& scene_keys() {
  static const std::vector<SceneKey> keys = build_keys();
  return keys;
}

std::string scene_key_pattern(const std::string& dotted) {
  // The k-th of [[sample.shapes]]: "sample.shapes[1].elongation" (as the reader names it) and
  // "sample.shapes.1.elongation" (as an override writes it).
  for (const std::string prefix : {"sample.shapes[", "sample.shapes."}) {
    if (dotted.rfind(prefix, 0) != 0) continue;
    std::size_t end = prefix.size();
    while (end < dotted.size() && std::isdigit(static_cast<unsigned char>(dotted[end]))) ++end;
    if (end == prefix.size()) break;
    const bool bracket = prefix.back() == '[';
    if (bracket && (end == dotted.size() || dotted[end] != ']')) break;
    return "sample.shapes[<k>]" + dotted.substr(bracket ? end + 1 : end);
  }
  for (const auto& [table, placeholder] :
       {std::pair{"materials.", "<name>"}, std::pair{"contacts.", "<a>-<b>"}}) {
    const std::string prefix = table;
    if (dotted.rfind(prefix, 0) != 0 || dotted.size() == prefix.size()) continue;
    const std::size_t end = dotted.find('.', prefix.size());
    return prefix + placeholder + (end == std::string::npos ? "" : dotted.substr(end));
  }
  return dotted;
}

bool is_scene_table(const std::string& dotted) {
  const std::string under = scene_key_pattern(dotted) + ".";
  for (const SceneKey& k : scene_keys())
    if (k.key.rfind(under, 0) == 0) return true;
  return false;
}

std::string scene_keys_markdown() {
  std::string t =
      "# Scene keys\n\n"
      "Generated by `reposetwin keys --markdown` from the parser's key table "
      "(experiments/io/scene_keys.cpp); a test fails when the parser accepts a key missing here "
      "and when this file is not current. Unknown keys are refused. Tables `[procedure]`, "
      "`[numerics]`, `[output]` and `[measure]` are optional; `--set key=value` overrides "
      "any key. Without `[sample.shape]` or `[[sample.shapes]]` every grain is a sphere; with "
      "one, every grain is a rigid clump of spheres (the k-th of a mix is overridden as "
      "`--set sample.shapes.<k>.elongation=2`). " +
      std::string(kRelativePathRule) +
      "\n\n"
      "| key | type | default | unit | meaning |\n|---|---|---|---|---|\n";
  for (const SceneKey& k : scene_keys())
    t += "| `" + k.key + "` | " + k.type + " | " + cell(k.default_text) + " | " + k.unit + " | " +
         cell(k.meaning) + " |\n";
  return t;
}

}  // namespace reposetwin::experiments
