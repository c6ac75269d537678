// The loop's summary (loop.json's `summary`): summarise decides the verdict and the statement
// from the finished records; to_json writes them as decided and loop_summary_from_json reads
// them back (loop_records.hpp). And the whole of loop.json: to_json of a LoopRecord and the one
// reader, loop_record_from_json, through which the page reads it back.
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "experiments/io/format.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/json_fields.hpp"
#include "experiments/io/json_read.hpp"
#include "experiments/loop/loop_effects.hpp"
#include "experiments/loop/loop_records.hpp"

namespace reposetwin::experiments {
using nlohmann::json;

const char* verdict_name(Verdict v) {
  switch (v) {
    case Verdict::kNothing: return "nothing";
    case Verdict::kNamed: return "named";
    case Verdict::kIndistinguishable: return "indistinguishable";
    case Verdict::kMeasurementSuspected: return "measurement_suspected";
    case Verdict::kDeclared: return "declared";
    case Verdict::kNotConfirmed: return "not_confirmed";
    case Verdict::kRefitFailed: return "refit_failed";
    case Verdict::kNotTraced: return "not_traced";
  }
  throw std::logic_error("loop: no verdict " + std::to_string(static_cast<int>(v)));
}

Verdict parse_verdict(const std::string& text) {
  for (Verdict v : {Verdict::kNothing, Verdict::kNamed, Verdict::kIndistinguishable,
                    Verdict::kMeasurementSuspected, Verdict::kDeclared, Verdict::kNotConfirmed,
                    Verdict::kRefitFailed, Verdict::kNotTraced})
    if (text == verdict_name(v)) return v;
  throw std::invalid_argument("loop summary: \"" + text + "\" is not a verdict");
}

Verdict verdict_of(TraceVerdict v) {
  switch (v) {
    case TraceVerdict::kNothing: return Verdict::kNothing;
    case TraceVerdict::kNamed: return Verdict::kNamed;
    case TraceVerdict::kIndistinguishable: return Verdict::kIndistinguishable;
    case TraceVerdict::kMeasurementSuspected: return Verdict::kMeasurementSuspected;
  }
  throw std::logic_error("loop: no trace verdict " + std::to_string(static_cast<int>(v)));
}

namespace {

// Every test's residual, the predictions included: with one calibration test the calibration
// RMSE is zero by construction, and the prediction residuals are what the loop traced.
double rmse_all(const std::vector<ResidualRow>& rows) {
  std::vector<double> r;
  for (const ResidualRow& x : rows)
    if (x.no_pile.empty()) r.push_back(x.residual_deg);
  return rmse(r);
}

// An effect chosen makes the verdict "named" ("declared" for the user's hypothesis, which the
// trace did not name; the statement keeps the trace's own verdict); otherwise it is the last
// iteration's: the trace's, or "not_confirmed" / "refit_failed" when the trace named a
// candidate (or the user declared one) that the simulated refit then did not bear out.
Verdict loop_verdict(const LoopRecord& loop) {
  const IterationRecord& last = loop.iterations.back();
  if (!loop.final_model.effects.empty())
    return loop.final_model.effects.back().declared ? Verdict::kDeclared : Verdict::kNamed;
  if (last.not_confirmed) return Verdict::kNotConfirmed;
  if (last.refit_failed) return Verdict::kRefitFailed;
  return verdict_of(last.decision.verdict);
}

// Every iteration's decision and the fate of its refit, in order.
std::string iterations_statement(const std::vector<IterationRecord>& iterations) {
  std::string text;
  for (const IterationRecord& it : iterations) {
    text += (text.empty() ? "" : " | ") + ("iteration " + std::to_string(it.iteration) + ": ") +
            it.decision.statement + (it.declared ? "; " + *it.declared : "");
    if (it.set_aside)
      text +=
          "; " + it.set_aside->refit.name + "'s simulated refit set aside: " + it.set_aside->reason;
    if (it.not_confirmed)
      text += "; " + it.not_confirmed->refit.name +
              " not confirmed by the simulated refit: " + it.not_confirmed->reason;
    if (it.refit_failed)
      text += "; " + it.refit_failed->name +
              "'s refit could not be simulated: " + it.refit_failed->refit_failed;
  }
  return text;
}

}  // namespace

LoopSummary summarise(const LoopRecord& loop) {
  LoopSummary s;
  for (const ChosenEffect& c : loop.final_model.effects) s.effects.push_back(c.refit.name);
  if (!s.effects.empty()) s.chosen = s.effects.back();
  if (!loop.iterations.empty()) {
    s.verdict = loop_verdict(loop);
    s.statement = iterations_statement(loop.iterations);
    // Each value with its joint region, and what would separate it from mu_r.
    for (const ChosenEffect& c : loop.final_model.effects)
      if (c.region) {
        *s.statement += " | " + c.refit.name + " " + significant(c.value, 3) + " (95% region " +
                        significant(c.value_lo, 3) + "-" + significant(c.value_hi, 3) + " " +
                        c.units + "): " + c.region->statement;
        if (!c.next_tests.empty())
          *s.statement += "; " + c.next_tests.front().name + " would shrink the interval to " +
                          significant(100.0 * c.next_tests.front().t_interval_ratio, 3) + "%";
      }
  }
  if (loop.not_traced) {
    s.verdict = Verdict::kNotTraced;
    s.statement = *loop.not_traced;
  }
  // A held-out test the final model predicts no pile for (its twin pours jammed) is a
  // prediction that failed where the lab poured a pile: said in the statement, not hidden in
  // an RMSE over fewer tests.
  for (const ResidualRow& r : loop.final_model.residuals)
    if (!r.no_pile.empty()) s.no_pile_predicted.push_back(r.id);
  if (!s.no_pile_predicted.empty()) {
    std::string ids;
    for (const std::string& id : s.no_pile_predicted) ids += (ids.empty() ? "" : ", ") + id;
    s.statement = (s.statement ? *s.statement + " | " : std::string()) +
                  "no pile predicted for " + ids +
                  " (held out): the final model's pours jammed where the lab's formed a pile; "
                  "the RMSEs leave it out";
  }
  s.rmse_all_before_deg = rmse_all(loop.baseline.residuals);
  s.rmse_all_after_deg = rmse_all(loop.final_model.residuals);
  s.rmse_calibrate_before_deg = loop.baseline.rmse.calibrate_deg;
  s.rmse_calibrate_after_deg = loop.final_model.rmse.calibrate_deg;
  s.rmse_validate_before_deg = loop.baseline.rmse.validate_deg;
  s.rmse_validate_after_deg = loop.final_model.rmse.validate_deg;
  const double before = s.rmse_calibrate_before_deg, after = s.rmse_calibrate_after_deg;
  s.reduction = before > 0.0 ? 1.0 - after / before : 0.0;
  return s;
}

json to_json(const LoopSummary& s) {
  auto optional_number = [](const std::optional<double>& v) { return v ? json(*v) : json(); };
  auto text_or_null = [](const std::optional<std::string>& t) { return t ? json(*t) : json(); };
  return {{"chosen", text_or_null(s.chosen)},
          {"verdict", s.verdict ? json(verdict_name(*s.verdict)) : json()},
          {"statement", text_or_null(s.statement)},
          {"rmse_all_before_deg", s.rmse_all_before_deg},
          {"rmse_all_after_deg", s.rmse_all_after_deg},
          {"effects", s.effects},
          {"rmse_calibrate_before_deg", s.rmse_calibrate_before_deg},
          {"rmse_calibrate_after_deg", s.rmse_calibrate_after_deg},
          {"rmse_validate_before_deg", optional_number(s.rmse_validate_before_deg)},
          {"rmse_validate_after_deg", optional_number(s.rmse_validate_after_deg)},
          {"reduction", s.reduction},
          {"no_pile_predicted", s.no_pile_predicted}};
}

LoopSummary loop_summary_from_json(const json& j) {
  auto text_of = [&](const char* key) -> std::optional<std::string> {
    if (field<json>(j, key).is_null()) return std::nullopt;
    return field<std::string>(j, key);
  };
  LoopSummary s;
  s.chosen = text_of("chosen");
  if (!field<json>(j, "verdict").is_null())
    s.verdict =
        nested(j, "verdict", [](const json& v) { return parse_verdict(v.get<std::string>()); });
  s.statement = text_of("statement");
  s.rmse_all_before_deg = number_field(j, "rmse_all_before_deg");
  s.rmse_all_after_deg = number_field(j, "rmse_all_after_deg");
  s.effects = field<std::vector<std::string>>(j, "effects");
  s.rmse_calibrate_before_deg = number_field(j, "rmse_calibrate_before_deg");
  s.rmse_calibrate_after_deg = number_field(j, "rmse_calibrate_after_deg");
  s.rmse_validate_before_deg = optional_number_field(j, "rmse_validate_before_deg");
  s.rmse_validate_after_deg = optional_number_field(j, "rmse_validate_after_deg");
  s.reduction = number_field(j, "reduction");
  // Absent: none (a loop.json written before the twin could predict no pile).
  if (j.contains("no_pile_predicted"))
    s.no_pile_predicted = field<std::vector<std::string>>(j, "no_pile_predicted");
  return s;
}

namespace {

constexpr const char* kRuleText =
    "accept the best-ranked candidate with |c|/se > min_t and a leave-one-"
    "test-out RMSE (over every test, the predicted ones included) below the "
    "mu_r-only LOO RMSE by more than the seed standard error of a predicted "
    "angle; among those, name the one whose joint chi^2 over angle, H and D "
    "is lower than every other's by more than min_delta_chi2, else report "
    "them as indistinguishable; a significant uniform offset that mu_r cannot "
    "take up and no candidate beats is flagged as a suspected measurement "
    "error, nothing named";

// loop.json holds the LOO margin in degrees, loo_margin_factor x the baseline's seed standard
// error; the factor is their quotient, moved by an ulp or two where the division does not undo
// the product, so that it writes the same margin again.
AcceptanceRule rule_from_json(const json& j, double seed_se_deg) {
  AcceptanceRule r;
  r.min_t = number_field(j, "min_t");
  r.min_delta_chi2 = number_field(j, "min_delta_chi2");
  (void)field<std::string>(j, "text");
  const double margin = number_field(j, "loo_margin_deg");
  if (seed_se_deg > 0.0) {
    double f = margin / seed_se_deg;
    for (int k = 0; k < 4 && f * seed_se_deg != margin; ++k)
      f = std::nextafter(f, f * seed_se_deg < margin ? std::numeric_limits<double>::infinity()
                                                     : -std::numeric_limits<double>::infinity());
    r.loo_margin_factor = f;
  } else if (margin != 0.0) {
    throw JsonFieldError("/loo_margin_deg", "is not 0 while the seed standard error is");
  }
  return r;
}

// Every test has its row before and after, in the tests' order.
void check_rows(const LoopRecord& loop) {
  for (const auto& [name, rows] : {std::pair{"/baseline/residuals", &loop.baseline.residuals},
                                   std::pair{"/final/residuals", &loop.final_model.residuals}}) {
    if (rows->size() != loop.tests.size())
      throw JsonFieldError(name, "has " + std::to_string(rows->size()) + " rows for " +
                                     std::to_string(loop.tests.size()) + " tests");
    for (std::size_t i = 0; i < rows->size(); ++i)
      if ((*rows)[i].id != loop.tests[i].id)
        throw JsonFieldError(std::string(name) + "/" + std::to_string(i) + "/id",
                             "is \"" + (*rows)[i].id + "\", not test " + loop.tests[i].id);
  }
}

}  // namespace

const char* acceptance_rule_text() { return kRuleText; }

json to_json(const LoopRecord& loop) {
  const json rule = {{"min_t", loop.rule.min_t},
                     {"loo_margin_deg", loop.rule.loo_margin_factor * loop.baseline.seed_se_deg},
                     {"text", kRuleText},
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

LoopRecord loop_record_from_json(const json& j, const std::string& path) {
  LoopRecord loop;
  try {
    loop.tests = each(j, "tests", lab_test_from_json);
    loop.design = nested(j, "design", design_record_from_json);
    loop.grid = nested(j, "grid", grid_record_from_json);
    if (!field<json>(j, "not_traced").is_null())
      loop.not_traced = field<std::string>(j, "not_traced");
    loop.unavailable = each(j, "unavailable_candidates", unavailable_candidate_from_json);
    loop.baseline = nested(j, "baseline", baseline_record_from_json);
    const double seed_se = loop.baseline.seed_se_deg;
    loop.rule = nested(j, "rule", [seed_se](const json& r) { return rule_from_json(r, seed_se); });
    loop.fingerprints = each(j, "fingerprints", fingerprint_record_from_json);
    loop.iterations = each(j, "iterations", iteration_record_from_json);
    loop.final_model = nested(j, "final", final_record_from_json);
    loop.summary = nested(j, "summary", loop_summary_from_json);
    loop.simulations = nested(j, "simulations", simulation_counts_from_json);
    loop.provenance = nested(j, "provenance", loop_provenance_from_json);
    loop.photo_pairs = each(j, "photo_pairs", photo_pair_from_json);
    check_rows(loop);
  } catch (const JsonFieldError& e) {
    throw InputError(path + ": " + (e.pointer().empty() ? "the document" : e.pointer()) + ": " +
                     e.problem());
  }
  return loop;
}

}  // namespace reposetwin::experiments
