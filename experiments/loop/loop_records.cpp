#include "experiments/loop/loop_records.hpp"

#include <cmath>
#include <stdexcept>

#include "experiments/io/json_fields.hpp"
#include "experiments/io/json_read.hpp"

namespace reposetwin::experiments {
using nlohmann::json;

namespace {

json optional_number(const std::optional<double>& v) { return v ? json(*v) : json(); }

}  // namespace

RoleRmse rmse_by_role(const std::vector<ResidualRow>& rows) {
  std::vector<double> c, v;
  RoleRmse out;
  for (const ResidualRow& r : rows) {
    if (!r.no_pile.empty()) {
      ++out.n_no_pile;
      continue;
    }
    (r.role == Role::kCalibrate ? c : v).push_back(r.residual_deg);
  }
  out.calibrate_deg = rmse(c);
  if (!v.empty()) out.validate_deg = rmse(v);
  out.n_calibrate = c.size();
  out.n_validate = v.size();
  return out;
}

json to_json(const ResidualRow& r) {
  // A test predicted no pile has null predictions (NaN in the record).
  auto value = [](double v) { return std::isfinite(v) ? json(v) : json(); };
  json j = {{"id", r.id},
            {"role", role_name(r.role)},
            {"measured_deg", r.measured_deg},
            {"predicted_deg", value(r.predicted_deg)},
            {"residual_deg", value(r.residual_deg)},
            {"sigma_deg", r.sigma_deg},
            {"predicted_se_deg", r.predicted_se_deg},
            {"predicted_H_mm", value(r.predicted_h_mm)},
            {"predicted_D_mm", value(r.predicted_d_mm)}};
  if (r.residual_h_mm) j["residual_H_mm"] = *r.residual_h_mm;
  if (r.residual_d_mm) j["residual_D_mm"] = *r.residual_d_mm;
  if (r.predicted_crest_mm) j["predicted_crest_mm"] = *r.predicted_crest_mm;
  if (r.residual_crest_mm) j["residual_crest_mm"] = *r.residual_crest_mm;
  if (!r.no_pile.empty()) j["no_pile"] = r.no_pile;
  return j;
}

json to_json(const RoleRmse& r) {
  return {{"calibrate_deg", r.calibrate_deg},
          {"n_calibrate", r.n_calibrate},
          {"n_validate", r.n_validate},
          {"n_no_pile", r.n_no_pile},
          {"validate_deg", optional_number(r.validate_deg)}};
}

json to_json(const BaselineCurve& c) {
  return {{"id", c.id},
          {"mu_r", c.mu},
          {"angle_deg", c.angle_deg},
          {"angle_seeds_deg", c.angle_seeds_deg},
          {"pour_seeds", c.pour_seeds},
          {"clogged_pours", c.clogged_pours}};
}

json to_json(const BaselineRecord& b) {
  return {{"mu_r", b.fit.mu},
          {"mu_r_se", b.fit.mu_se},
          {"mu_r_at_grid_edge", b.fit.at_edge},
          {"seed_sd_deg", b.seed_sd_deg},
          {"seed_se_deg", b.seed_se_deg},
          {"residuals", to_json_array(b.residuals)},
          {"rmse", to_json(b.rmse)},
          {"curves", to_json_array(b.curves)}};
}

const char* channel_name(Channel c) {
  switch (c) {
    case Channel::kAngle: return "angle";
    case Channel::kH: return "H";
    case Channel::kD: return "D";
    case Channel::kCrest: return "crest";
  }
  throw std::logic_error("loop: no channel " + std::to_string(static_cast<int>(c)));
}

const char* channel_unit(Channel c) { return c == Channel::kAngle ? "deg" : "mm"; }

Channel channel_from_name(const std::string& name) {
  for (Channel c : kAllChannels)
    if (name == channel_name(c)) return c;
  throw std::logic_error("loop: no channel named '" + name + "'");
}

json to_json(const FingerprintRecord& f) {
  json j = {{"name", f.name},
            {"probe", f.probe},
            {"mu_r", f.mu_r},
            {"angle_deg", f.change[Channel::kAngle]},
            {"angle_se_deg", f.angle_se_deg},
            {"H_mm", f.change[Channel::kH]},
            {"D_mm", f.change[Channel::kD]},
            {"probes_tried", f.probes_tried}};
  if (!f.change[Channel::kCrest].empty()) j["crest_mm"] = f.change[Channel::kCrest];
  if (f.surface.empty()) return j;
  json nodes = json::array();
  for (const FingerprintNode& n : f.surface) {
    json node = {{"mu_r", n.mu_r}};
    if (!n.missing.empty()) {
      node["missing"] = n.missing;
    } else {
      node["angle_deg"] = n.change[Channel::kAngle];
      node["H_mm"] = n.change[Channel::kH];
      node["D_mm"] = n.change[Channel::kD];
      if (!n.change[Channel::kCrest].empty()) node["crest_mm"] = n.change[Channel::kCrest];
    }
    nodes.push_back(std::move(node));
  }
  j["surface"] = std::move(nodes);
  return j;
}

json to_json(const GridRecord& g) {
  json j = {{"initial", g.initial}, {"final", g.final_grid}, {"added", g.added},
            {"policy", g.policy},   {"mu_r_at_bound", g.at_bound}, {"statement", g.statement}};
  if (g.prior)
    j["mu_r_prior"] = {{"range", {g.prior->first, g.prior->second}},
                       {"reason", g.prior_reason},
                       {"mu_r_alone_beyond_it", g.beyond_prior}};
  return j;
}

json to_json(const UnavailableCandidate& u) { return {{"name", u.name}, {"why", u.why}}; }

json to_json(const RefitTrialRecord& t) {
  return {{"simulated_at", t.simulated_at},
          {"response_fraction", t.response_fraction},
          {"t", t.t},
          {"mu_r", t.mu_r},
          {"rmse_calibrate_deg", t.rmse_calibrate_deg},
          {"no_pile", t.no_pile}};
}

namespace {

// The fields ChosenEffect and NotConfirmed share.
json refit_fields(const RefitSummary& r) {
  return {{"name", r.name},
          {"linear_estimate", r.linear_estimate},
          {"simulated_at", r.simulated_at},
          {"t", r.t},
          {"mu_r", r.mu_r},
          {"trials", to_json_array(r.trials)},
          {"refit_notes", r.refit_notes}};
}

}  // namespace

json to_json(const ChosenEffect& c) {
  json j = refit_fields(c.refit);
  j.update({{"kind", c.kind},
            {"key", c.key},
            {"units", c.units},
            {"off", c.off},
            {"probe", c.probe},
            {"value", c.value},
            {"value_se", c.value_se},
            {"t_at_limit", c.t_at_limit},
            {"mu_r_se", c.mu_r_se},
            {"declared", c.declared}});
  if (c.region) {
    j["joint_region"] = to_json(*c.region);
    j["joint_region"]["value_range"] = {c.value_lo, c.value_hi};
  }
  if (!c.next_tests.empty()) {
    j["next_tests"] = json::array();
    for (const NextTestGain& g : c.next_tests) j["next_tests"].push_back(to_json(g));
  }
  return j;
}

json to_json(const NotConfirmed& n) {
  json j = refit_fields(n.refit);
  j.update({{"rmse_calibrate_deg", n.rmse_calibrate_deg}, {"reason", n.reason}});
  return j;
}

json to_json(const RefitFailed& f) {
  return {
      {"name", f.name}, {"refit_failed", f.refit_failed}, {"linear_estimate", f.linear_estimate}};
}

json to_json(const IterationRecord& it) {
  json j = {{"iteration", it.iteration},
            {"mu_r", it.mu_r},
            {"null", to_json(it.null)},
            {"candidates", to_json_array(it.candidates)},
            {"channels", it.channels},
            {"channels_left_out", it.channels_left_out},
            {"tests_left_out", it.tests_left_out},
            {"joint", to_json_array(it.joint)},
            {"offset", it.offset ? to_json(*it.offset) : json()},
            {"mu_only", it.mu_only ? to_json(*it.mu_only) : json()},
            {"decision", to_json(it.decision)}};
  if (it.chosen)
    j["chosen"] = to_json(*it.chosen);
  else if (it.refit_failed)
    j["chosen"] = to_json(*it.refit_failed);
  else
    j["chosen"] = nullptr;
  if (it.stopped) j["stopped"] = *it.stopped;
  if (it.declared) j["declared"] = *it.declared;
  if (it.not_confirmed) j["not_confirmed"] = to_json(*it.not_confirmed);
  if (it.set_aside) j["set_aside"] = to_json(*it.set_aside);
  return j;
}

json to_json(const FinalRecord& f) {
  return {{"mu_r", f.fit.mu},
          {"mu_r_se", f.fit.mu_se},
          {"effects", to_json_array(f.effects)},
          {"residuals", to_json_array(f.residuals)},
          {"rmse", to_json(f.rmse)}};
}

json to_json(const LoopProvenance& p) {
  json j = {{"code_version", p.code_version},
            {"data", p.data},
            {"seeds", p.seeds},
            {"angle_measure", p.angle_measure},
            {"angle_method", p.angle_method},
            {"lab_angle_source", p.lab_angle_source},
            {"mu_grid", p.mu_grid},
            {"mu_key", p.mu_key},
            {"image", p.image},
            {"max_pours", p.max_pours},
            {"cache", p.cache},
            {"finished", p.finished},
            {"scenes", p.scenes}};
  if (p.refit_follow_ups) j["refit_follow_ups"] = *p.refit_follow_ups;
  if (p.run) j["run"] = *p.run;
  return j;
}

json to_json(const SimulationCounts& s) {
  return {{"pile_runs_started", s.pile_runs_started},
          {"photos_started", s.photos_started},
          {"wall_s", s.wall_s}};
}

json to_json(const PhotoView& v) {
  return {{"photo", v.photo},         {"overlay", v.overlay},   {"source", v.source},
          {"mm_per_px", v.mm_per_px}, {"width_px", v.width_px}, {"height_px", v.height_px},
          {"angle_deg", v.angle_deg}};
}

json to_json(const PhotoPair& p) {
  json effects = json::object();
  for (const auto& [name, value] : p.effects) effects[name] = value;
  return {{"id", p.id},
          {"lab", p.lab ? to_json(*p.lab) : json()},
          {"twin", p.twin ? to_json(*p.twin) : json()},
          {"mu_r", p.mu_r},
          {"seed", p.seed},
          {"effects", effects},
          {"note", p.note}};
}

namespace {

// The fields ChosenEffect and NotConfirmed share.
RefitSummary refit_from_json(const json& j) {
  RefitSummary r;
  r.name = field<std::string>(j, "name");
  r.linear_estimate = number_field(j, "linear_estimate");
  r.simulated_at = number_field(j, "simulated_at");
  r.t = number_field(j, "t");
  r.mu_r = number_field(j, "mu_r");
  r.trials = each(j, "trials", refit_trial_record_from_json);
  r.refit_notes = field<std::string>(j, "refit_notes");
  return r;
}

// j[key] when present and not null.
template <class T>
std::optional<T> optional_field(const json& j, const char* key) {
  if (!j.contains(key) || j.at(key).is_null()) return std::nullopt;
  return field<T>(j, key);
}

}  // namespace

ResidualRow residual_row_from_json(const json& j) {
  ResidualRow r;
  r.id = field<std::string>(j, "id");
  r.role = nested(j, "role", role_from_json);
  r.measured_deg = number_field(j, "measured_deg");
  r.predicted_deg = number_field(j, "predicted_deg");
  r.residual_deg = number_field(j, "residual_deg");
  r.sigma_deg = number_field(j, "sigma_deg");
  r.predicted_se_deg = number_field(j, "predicted_se_deg");
  r.predicted_h_mm = number_field(j, "predicted_H_mm");
  r.predicted_d_mm = number_field(j, "predicted_D_mm");
  r.residual_h_mm = optional_number_field(j, "residual_H_mm");
  r.residual_d_mm = optional_number_field(j, "residual_D_mm");
  r.predicted_crest_mm = optional_number_field(j, "predicted_crest_mm");
  r.residual_crest_mm = optional_number_field(j, "residual_crest_mm");
  r.no_pile = optional_field<std::string>(j, "no_pile").value_or("");
  return r;
}

RoleRmse role_rmse_from_json(const json& j) {
  RoleRmse r;
  r.calibrate_deg = number_field(j, "calibrate_deg");
  r.validate_deg = optional_number_field(j, "validate_deg");
  r.n_calibrate = field<std::size_t>(j, "n_calibrate");
  r.n_validate = field<std::size_t>(j, "n_validate");
  // Absent: none left out (a loop.json written before the twin could predict no pile).
  r.n_no_pile = optional_field<std::size_t>(j, "n_no_pile").value_or(0);
  return r;
}

BaselineCurve baseline_curve_from_json(const json& j) {
  BaselineCurve c;
  c.id = field<std::string>(j, "id");
  c.mu = field<std::vector<double>>(j, "mu_r");
  c.angle_deg = numbers_field(j, "angle_deg");
  c.angle_seeds_deg = each(j, "angle_seeds_deg", number_values);
  c.pour_seeds = field<std::vector<std::vector<std::uint64_t>>>(j, "pour_seeds");
  c.clogged_pours = field<std::vector<int>>(j, "clogged_pours");
  return c;
}

BaselineRecord baseline_record_from_json(const json& j) {
  BaselineRecord b;
  b.fit.mu = number_field(j, "mu_r");
  b.fit.mu_se = number_field(j, "mu_r_se");
  b.fit.at_edge = field<bool>(j, "mu_r_at_grid_edge");
  b.seed_sd_deg = number_field(j, "seed_sd_deg");
  b.seed_se_deg = number_field(j, "seed_se_deg");
  b.residuals = each(j, "residuals", residual_row_from_json);
  b.rmse = nested(j, "rmse", role_rmse_from_json);
  b.curves = each(j, "curves", baseline_curve_from_json);
  return b;
}

FingerprintRecord fingerprint_record_from_json(const json& j) {
  FingerprintRecord f;
  f.name = field<std::string>(j, "name");
  f.probe = number_field(j, "probe");
  f.mu_r = number_field(j, "mu_r");
  f.change[Channel::kAngle] = numbers_field(j, "angle_deg");
  f.angle_se_deg = numbers_field(j, "angle_se_deg");
  f.change[Channel::kH] = numbers_field(j, "H_mm");
  f.change[Channel::kD] = numbers_field(j, "D_mm");
  // Absent: no test has a measured crest.
  if (j.contains("crest_mm")) f.change[Channel::kCrest] = numbers_field(j, "crest_mm");
  f.probes_tried = numbers_field(j, "probes_tried");
  // Absent: written before the loop simulated fingerprints at every grid point.
  if (j.contains("surface"))
    f.surface = each(j, "surface", [](const json& n) {
      FingerprintNode node;
      node.mu_r = number_field(n, "mu_r");
      if (n.contains("missing")) {
        node.missing = field<std::string>(n, "missing");
        return node;
      }
      node.change[Channel::kAngle] = numbers_field(n, "angle_deg");
      node.change[Channel::kH] = numbers_field(n, "H_mm");
      node.change[Channel::kD] = numbers_field(n, "D_mm");
      if (n.contains("crest_mm")) node.change[Channel::kCrest] = numbers_field(n, "crest_mm");
      return node;
    });
  return f;
}

GridRecord grid_record_from_json(const json& j) {
  GridRecord g;
  g.initial = field<std::vector<double>>(j, "initial");
  g.final_grid = field<std::vector<double>>(j, "final");
  g.added = field<std::vector<double>>(j, "added");
  g.policy = field<std::string>(j, "policy");
  g.at_bound = field<bool>(j, "mu_r_at_bound");
  g.statement = field<std::string>(j, "statement");
  // Absent: mu_r's range was not declared.
  if (j.contains("mu_r_prior")) {
    nested(j, "mu_r_prior", [&g](const json& p) {
      const std::vector<double> range = field<std::vector<double>>(p, "range");
      if (range.size() != 2) throw JsonFieldError("/range", "is not the two ends of a range");
      g.prior = std::make_pair(range[0], range[1]);
      g.prior_reason = field<std::string>(p, "reason");
      g.beyond_prior = field<bool>(p, "mu_r_alone_beyond_it");
      return 0;
    });
  }
  return g;
}

UnavailableCandidate unavailable_candidate_from_json(const json& j) {
  return {field<std::string>(j, "name"), field<std::string>(j, "why")};
}

RefitTrialRecord refit_trial_record_from_json(const json& j) {
  // no_pile absent: none (a loop.json written before the twin could predict no pile).
  return {
      number_field(j, "simulated_at"),
      number_field(j, "response_fraction"),
      number_field(j, "t"),
      number_field(j, "mu_r"),
      number_field(j, "rmse_calibrate_deg"),
      optional_field<std::vector<std::string>>(j, "no_pile").value_or(std::vector<std::string>{})};
}

ChosenEffect chosen_effect_from_json(const json& j) {
  ChosenEffect c;
  c.refit = refit_from_json(j);
  c.kind = field<std::string>(j, "kind");
  c.key = field<std::string>(j, "key");
  c.units = field<std::string>(j, "units");
  c.off = number_field(j, "off");
  c.probe = number_field(j, "probe");
  c.value = number_field(j, "value");
  c.value_se = number_field(j, "value_se");
  c.t_at_limit = field<bool>(j, "t_at_limit");
  c.mu_r_se = number_field(j, "mu_r_se");
  // Absent: chosen by the trace (a loop.json written before declared hypotheses).
  c.declared = optional_field<bool>(j, "declared").value_or(false);
  // Absent: no region computed (a loop.json written before the joint region).
  if (j.contains("joint_region")) {
    c.region = nested(j, "joint_region", joint_region_from_json);
    const std::vector<double> range = nested(j, "joint_region", [](const json& r) {
      const std::vector<double> v = numbers_field(r, "value_range");
      if (v.size() != 2) throw JsonFieldError("/value_range", "is not the two ends of a range");
      return v;
    });
    c.value_lo = range[0];
    c.value_hi = range[1];
  }
  if (j.contains("next_tests")) c.next_tests = each(j, "next_tests", next_test_gain_from_json);
  return c;
}

NotConfirmed not_confirmed_from_json(const json& j) {
  return {refit_from_json(j), number_field(j, "rmse_calibrate_deg"),
          field<std::string>(j, "reason")};
}

RefitFailed refit_failed_from_json(const json& j) {
  return {field<std::string>(j, "name"), field<std::string>(j, "refit_failed"),
          number_field(j, "linear_estimate")};
}

namespace {

// An iteration's joint trace: the channels, the scores and the decision.
void read_joint_trace(const json& j, IterationRecord& it) {
  it.channels = field<std::vector<std::string>>(j, "channels");
  it.channels_left_out = field<std::vector<std::string>>(j, "channels_left_out");
  // Absent: every test traced (a loop.json written before the twin could predict no pile).
  if (j.contains("tests_left_out"))
    it.tests_left_out = field<std::vector<std::string>>(j, "tests_left_out");
  it.joint = each(j, "joint", joint_score_from_json);
  if (!field<json>(j, "offset").is_null()) it.offset = nested(j, "offset", joint_score_from_json);
  if (!field<json>(j, "mu_only").is_null())
    it.mu_only = nested(j, "mu_only", joint_score_from_json);
  it.decision = nested(j, "decision", trace_decision_from_json);
}

}  // namespace

IterationRecord iteration_record_from_json(const json& j) {
  IterationRecord it;
  it.iteration = field<int>(j, "iteration");
  it.mu_r = number_field(j, "mu_r");
  it.null = nested(j, "null", null_score_from_json);
  it.candidates = each(j, "candidates", candidate_score_from_json);
  // `chosen` is null, the refit's failure (it has the field refit_failed) or the chosen effect.
  const json& chosen = field<json>(j, "chosen");
  if (chosen.is_object() && chosen.contains("refit_failed"))
    it.refit_failed = nested(j, "chosen", refit_failed_from_json);
  else if (!chosen.is_null())
    it.chosen = nested(j, "chosen", chosen_effect_from_json);
  it.stopped = optional_field<std::string>(j, "stopped");
  it.declared = optional_field<std::string>(j, "declared");
  if (j.contains("not_confirmed"))
    it.not_confirmed = nested(j, "not_confirmed", not_confirmed_from_json);
  if (j.contains("set_aside")) it.set_aside = nested(j, "set_aside", not_confirmed_from_json);
  read_joint_trace(j, it);
  return it;
}

FinalRecord final_record_from_json(const json& j) {
  FinalRecord f;
  f.fit.mu = number_field(j, "mu_r");
  f.fit.mu_se = number_field(j, "mu_r_se");
  f.effects = each(j, "effects", chosen_effect_from_json);
  f.residuals = each(j, "residuals", residual_row_from_json);
  f.rmse = nested(j, "rmse", role_rmse_from_json);
  return f;
}

LoopProvenance loop_provenance_from_json(const json& j) {
  LoopProvenance p;
  p.code_version = field<std::string>(j, "code_version");
  p.data = field<std::string>(j, "data");
  p.seeds = field<std::vector<std::uint64_t>>(j, "seeds");
  p.angle_measure = field<std::string>(j, "angle_measure");
  p.angle_method = field<std::string>(j, "angle_method");
  p.lab_angle_source = field<std::string>(j, "lab_angle_source");
  p.mu_grid = field<std::vector<double>>(j, "mu_grid");
  p.mu_key = field<std::string>(j, "mu_key");
  p.image = field<std::string>(j, "image");
  p.max_pours = field<int>(j, "max_pours");
  p.refit_follow_ups = optional_field<int>(j, "refit_follow_ups");
  p.cache = field<std::string>(j, "cache");
  p.finished = field<std::string>(j, "finished");
  p.scenes = field<std::vector<std::string>>(j, "scenes");
  // Absent: the baseline has no pile whose run to name.
  if (j.contains("run")) p.run = field<json>(j, "run");
  return p;
}

SimulationCounts simulation_counts_from_json(const json& j) {
  return {field<int>(j, "pile_runs_started"), field<int>(j, "photos_started"),
          number_field(j, "wall_s")};
}

PhotoView photo_view_from_json(const json& j) {
  return {field<std::string>(j, "photo"),  field<std::string>(j, "overlay"),
          field<std::string>(j, "source"), number_field(j, "mm_per_px"),
          field<int>(j, "width_px"),       field<int>(j, "height_px"),
          number_field(j, "angle_deg")};
}

PhotoPair photo_pair_from_json(const json& j) {
  PhotoPair p;
  p.id = field<std::string>(j, "id");
  if (!field<json>(j, "lab").is_null()) p.lab = nested(j, "lab", photo_view_from_json);
  if (!field<json>(j, "twin").is_null()) p.twin = nested(j, "twin", photo_view_from_json);
  p.mu_r = number_field(j, "mu_r");
  p.seed = field<std::uint64_t>(j, "seed");
  nested(j, "effects", [&p](const json& e) {
    if (!e.is_object())
      throw JsonFieldError("", std::string("is ") + e.type_name() + ", not an object");
    for (const auto& [name, value] : e.items())
      p.effects.emplace_back(name, number_field(e, name.c_str()));
    return 0;
  });
  p.note = field<std::string>(j, "note");
  return p;
}

}  // namespace reposetwin::experiments
