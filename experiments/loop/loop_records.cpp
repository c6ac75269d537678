#include "experiments/loop/loop_records.hpp"

#include <cmath>
#include <stdexcept>

#include "experiments/io/json_fields.hpp"
#include "experiments/loop/loop_effects.hpp"

namespace reposetwin::experiments {
using nlohmann::json;

namespace {

json optional_number(const std::optional<double>& v) { return v ? json(*v) : json(); }

json to_json_array(const auto& records) {
  json a = json::array();
  for (const auto& r : records) a.push_back(to_json(r));
  return a;
}

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

json to_json(const LoopRecord& loop) {
  const json rule = {{"min_t", loop.rule.min_t},
                     {"loo_margin_deg", loop.rule.loo_margin_factor * loop.baseline.seed_se_deg},
                     {"text",
                      "accept the best-ranked candidate with |c|/se > min_t and a leave-one-"
                      "test-out RMSE (over every test, the predicted ones included) below the "
                      "mu_r-only LOO RMSE by more than the seed standard error of a predicted "
                      "angle; among those, name the one whose joint chi^2 over angle, H and D "
                      "is lower than every other's by more than min_delta_chi2, else report "
                      "them as indistinguishable; a significant uniform offset that mu_r cannot "
                      "take up and no candidate beats is flagged as a suspected measurement "
                      "error, nothing named"},
                     {"min_delta_chi2", loop.rule.min_delta_chi2}};
  return {{"tests", to_json_array(loop.tests)},
          {"design", to_json(loop.design)},
          {"grid", to_json(loop.grid)},
          {"not_traced", loop.not_traced ? json(*loop.not_traced) : json()},
          {"candidate_registry", to_json_array(candidate_effects())},
          {"unavailable_candidates", to_json_array(loop.unavailable)},
          {"rule", rule},
          {"baseline", to_json(loop.baseline)},
          {"fingerprints", to_json_array(loop.fingerprints)},
          {"iterations", to_json_array(loop.iterations)},
          {"final", to_json(loop.final_model)},
          {"summary", to_json(loop.summary)},
          {"simulations", to_json(loop.simulations)},
          {"provenance", to_json(loop.provenance)},
          {"photo_pairs", to_json_array(loop.photo_pairs)}};
}

namespace {

double num(const json& j, const char* key) { return json_number(j.at(key)); }

std::optional<double> optional_of(const json& j, const char* key) {
  const auto it = j.find(key);
  if (it == j.end() || it->is_null()) return std::nullopt;
  return it->get<double>();
}

template <typename T, typename F>
std::vector<T> array_from_json(const json& a, F from) {
  std::vector<T> out;
  for (const json& e : a) out.push_back(from(e));
  return out;
}

// The fields ChosenEffect and NotConfirmed share.
RefitSummary refit_from_json(const json& j) {
  RefitSummary r;
  r.name = j.at("name").get<std::string>();
  r.linear_estimate = num(j, "linear_estimate");
  r.simulated_at = num(j, "simulated_at");
  r.t = num(j, "t");
  r.mu_r = num(j, "mu_r");
  r.trials = array_from_json<RefitTrialRecord>(j.at("trials"), refit_trial_record_from_json);
  r.refit_notes = j.at("refit_notes").get<std::string>();
  return r;
}

}  // namespace

ResidualRow residual_row_from_json(const json& j) {
  ResidualRow r;
  r.id = j.at("id").get<std::string>();
  const std::string role = j.at("role").get<std::string>();
  const std::optional<Role> parsed = parse_role(role);
  if (!parsed)
    throw std::invalid_argument("residual row: role \"" + role +
                                "\" is not calibrate or validate");
  r.role = *parsed;
  r.measured_deg = num(j, "measured_deg");
  r.predicted_deg = num(j, "predicted_deg");
  r.residual_deg = num(j, "residual_deg");
  r.sigma_deg = num(j, "sigma_deg");
  r.predicted_se_deg = num(j, "predicted_se_deg");
  r.predicted_h_mm = num(j, "predicted_H_mm");
  r.predicted_d_mm = num(j, "predicted_D_mm");
  r.residual_h_mm = optional_of(j, "residual_H_mm");
  r.residual_d_mm = optional_of(j, "residual_D_mm");
  r.predicted_crest_mm = optional_of(j, "predicted_crest_mm");
  r.residual_crest_mm = optional_of(j, "residual_crest_mm");
  r.no_pile = j.value("no_pile", std::string());
  return r;
}

RoleRmse role_rmse_from_json(const json& j) {
  RoleRmse r;
  r.calibrate_deg = num(j, "calibrate_deg");
  r.validate_deg = optional_of(j, "validate_deg");
  r.n_calibrate = j.at("n_calibrate").get<std::size_t>();
  r.n_validate = j.at("n_validate").get<std::size_t>();
  r.n_no_pile = j.value("n_no_pile", std::size_t{0});
  return r;
}

BaselineCurve baseline_curve_from_json(const json& j) {
  BaselineCurve c;
  c.id = j.at("id").get<std::string>();
  c.mu = j.at("mu_r").get<std::vector<double>>();
  for (const json& v : j.at("angle_deg")) c.angle_deg.push_back(json_number(v));
  for (const json& row : j.at("angle_seeds_deg")) {
    c.angle_seeds_deg.emplace_back();
    for (const json& v : row) c.angle_seeds_deg.back().push_back(json_number(v));
  }
  c.pour_seeds = j.at("pour_seeds").get<std::vector<std::vector<std::uint64_t>>>();
  c.clogged_pours = j.at("clogged_pours").get<std::vector<int>>();
  return c;
}

BaselineRecord baseline_record_from_json(const json& j) {
  BaselineRecord b;
  b.fit.mu = num(j, "mu_r");
  b.fit.mu_se = num(j, "mu_r_se");
  b.fit.at_edge = j.at("mu_r_at_grid_edge").get<bool>();
  b.seed_sd_deg = num(j, "seed_sd_deg");
  b.seed_se_deg = num(j, "seed_se_deg");
  b.residuals = array_from_json<ResidualRow>(j.at("residuals"), residual_row_from_json);
  b.rmse = role_rmse_from_json(j.at("rmse"));
  b.curves = array_from_json<BaselineCurve>(j.at("curves"), baseline_curve_from_json);
  return b;
}

FingerprintRecord fingerprint_record_from_json(const json& j) {
  FingerprintRecord f;
  f.name = j.at("name").get<std::string>();
  f.probe = num(j, "probe");
  f.mu_r = num(j, "mu_r");
  auto numbers = [&](const char* key) {
    std::vector<double> v;
    for (const json& e : j.at(key)) v.push_back(json_number(e));
    return v;
  };
  f.change[Channel::kAngle] = numbers("angle_deg");
  f.angle_se_deg = numbers("angle_se_deg");
  f.change[Channel::kH] = numbers("H_mm");
  f.change[Channel::kD] = numbers("D_mm");
  if (j.contains("crest_mm")) f.change[Channel::kCrest] = numbers("crest_mm");
  if (j.contains("probes_tried")) f.probes_tried = numbers("probes_tried");
  return f;
}

GridRecord grid_record_from_json(const json& j) {
  GridRecord g;
  g.initial = j.at("initial").get<std::vector<double>>();
  g.final_grid = j.at("final").get<std::vector<double>>();
  g.added = j.at("added").get<std::vector<double>>();
  g.policy = j.at("policy").get<std::string>();
  g.at_bound = j.at("mu_r_at_bound").get<bool>();
  g.statement = j.at("statement").get<std::string>();
  if (j.contains("mu_r_prior")) {
    const json& p = j.at("mu_r_prior");
    g.prior = std::make_pair(p.at("range").at(0).get<double>(), p.at("range").at(1).get<double>());
    g.prior_reason = p.at("reason").get<std::string>();
    g.beyond_prior = p.at("mu_r_alone_beyond_it").get<bool>();
  }
  return g;
}

UnavailableCandidate unavailable_candidate_from_json(const json& j) {
  return {j.at("name").get<std::string>(), j.at("why").get<std::string>()};
}

RefitTrialRecord refit_trial_record_from_json(const json& j) {
  return {num(j, "simulated_at"), num(j, "response_fraction"), num(j, "t"), num(j, "mu_r"),
          num(j, "rmse_calibrate_deg"), j.value("no_pile", std::vector<std::string>{})};
}

ChosenEffect chosen_effect_from_json(const json& j) {
  ChosenEffect c;
  c.refit = refit_from_json(j);
  c.kind = j.at("kind").get<std::string>();
  c.key = j.at("key").get<std::string>();
  c.units = j.at("units").get<std::string>();
  c.off = num(j, "off");
  c.probe = num(j, "probe");
  c.value = num(j, "value");
  c.value_se = num(j, "value_se");
  c.t_at_limit = j.at("t_at_limit").get<bool>();
  c.mu_r_se = num(j, "mu_r_se");
  // Written by a loop that knew declared hypotheses; older loop.json files have none.
  c.declared = j.value("declared", false);
  // Written by a loop that reports the joint region; older loop.json files have none.
  if (j.contains("joint_region")) {
    c.region = joint_region_from_json(j.at("joint_region"));
    c.value_lo = j.at("joint_region").at("value_range").at(0).get<double>();
    c.value_hi = j.at("joint_region").at("value_range").at(1).get<double>();
  }
  if (j.contains("next_tests"))
    for (const json& g : j.at("next_tests"))
      c.next_tests.push_back({g.at("test").get<std::string>(),
                              g.at("effect_interval_ratio").get<double>(),
                              g.at("mu_r_interval_ratio").get<double>(),
                              g.at("region_area_ratio").get<double>()});
  return c;
}

NotConfirmed not_confirmed_from_json(const json& j) {
  return {refit_from_json(j), num(j, "rmse_calibrate_deg"), j.at("reason").get<std::string>()};
}

RefitFailed refit_failed_from_json(const json& j) {
  return {j.at("name").get<std::string>(), j.at("refit_failed").get<std::string>(),
          num(j, "linear_estimate")};
}

IterationRecord iteration_record_from_json(const json& j) {
  IterationRecord it;
  it.iteration = j.at("iteration").get<int>();
  it.mu_r = num(j, "mu_r");
  it.null = null_score_from_json(j.at("null"));
  it.candidates = array_from_json<CandidateScore>(j.at("candidates"), candidate_score_from_json);
  const json& chosen = j.at("chosen");
  if (chosen.is_object() && chosen.contains("refit_failed")) {
    it.refit_failed = refit_failed_from_json(chosen);
  } else if (!chosen.is_null()) {
    it.chosen = chosen_effect_from_json(chosen);
  }
  if (j.contains("stopped")) it.stopped = j.at("stopped").get<std::string>();
  if (j.contains("declared")) it.declared = j.at("declared").get<std::string>();
  if (j.contains("not_confirmed")) it.not_confirmed = not_confirmed_from_json(j.at("not_confirmed"));
  // Written by a loop that traced jointly; older loop.json files have none of these.
  if (j.contains("channels")) {
    it.channels = j.at("channels").get<std::vector<std::string>>();
    it.channels_left_out = j.at("channels_left_out").get<std::vector<std::string>>();
    it.tests_left_out = j.value("tests_left_out", std::vector<std::string>{});
    it.joint = array_from_json<JointScore>(j.at("joint"), joint_score_from_json);
    if (!j.at("offset").is_null()) it.offset = joint_score_from_json(j.at("offset"));
    if (!j.at("mu_only").is_null()) it.mu_only = joint_score_from_json(j.at("mu_only"));
    it.decision = trace_decision_from_json(j.at("decision"));
  }
  return it;
}

FinalRecord final_record_from_json(const json& j) {
  FinalRecord f;
  f.fit.mu = num(j, "mu_r");
  f.fit.mu_se = num(j, "mu_r_se");
  f.effects = array_from_json<ChosenEffect>(j.at("effects"), chosen_effect_from_json);
  f.residuals = array_from_json<ResidualRow>(j.at("residuals"), residual_row_from_json);
  f.rmse = role_rmse_from_json(j.at("rmse"));
  return f;
}

LoopProvenance loop_provenance_from_json(const json& j) {
  LoopProvenance p;
  p.code_version = j.at("code_version").get<std::string>();
  p.data = j.at("data").get<std::string>();
  p.seeds = j.at("seeds").get<std::vector<std::uint64_t>>();
  p.angle_measure = j.at("angle_measure").get<std::string>();
  p.angle_method = j.at("angle_method").get<std::string>();
  p.lab_angle_source = j.at("lab_angle_source").get<std::string>();
  p.mu_grid = j.at("mu_grid").get<std::vector<double>>();
  p.mu_key = j.at("mu_key").get<std::string>();
  p.image = j.at("image").get<std::string>();
  p.max_pours = j.at("max_pours").get<int>();
  p.cache = j.at("cache").get<std::string>();
  p.finished = j.at("finished").get<std::string>();
  p.scenes = j.at("scenes").get<std::vector<std::string>>();
  if (j.contains("run")) p.run = j.at("run");
  return p;
}

SimulationCounts simulation_counts_from_json(const json& j) {
  return {j.at("pile_runs_started").get<int>(), j.at("photos_started").get<int>(),
          num(j, "wall_s")};
}

PhotoView photo_view_from_json(const json& j) {
  return {j.at("photo").get<std::string>(),
          j.at("overlay").get<std::string>(),
          j.at("source").get<std::string>(),
          num(j, "mm_per_px"),
          j.at("width_px").get<int>(),
          j.at("height_px").get<int>(),
          num(j, "angle_deg")};
}

PhotoPair photo_pair_from_json(const json& j) {
  PhotoPair p;
  p.id = j.at("id").get<std::string>();
  if (!j.at("lab").is_null()) p.lab = photo_view_from_json(j["lab"]);
  if (!j.at("twin").is_null()) p.twin = photo_view_from_json(j["twin"]);
  p.mu_r = num(j, "mu_r");
  p.seed = j.at("seed").get<std::uint64_t>();
  for (const auto& [name, value] : j.at("effects").items())
    p.effects.emplace_back(name, json_number(value));
  p.note = j.at("note").get<std::string>();
  return p;
}

}  // namespace reposetwin::experiments
