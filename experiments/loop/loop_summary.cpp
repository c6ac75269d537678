// The loop's summary (loop.json's `summary`): summarise decides the verdict and the statement
// from the finished records; to_json writes them as decided and loop_summary_from_json reads
// them back (loop_records.hpp).
#include <cmath>
#include <stdexcept>
#include <string>

#include "experiments/io/format.hpp"
#include "experiments/io/json_fields.hpp"
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
    const json& v = j.at(key);
    return v.is_null() ? std::nullopt : std::optional<std::string>(v.get<std::string>());
  };
  LoopSummary s;
  s.chosen = text_of("chosen");
  if (const std::optional<std::string> v = text_of("verdict")) s.verdict = parse_verdict(*v);
  s.statement = text_of("statement");
  auto num = [&](const char* key) { return json_number(j.at(key)); };
  auto optional_of = [&](const char* key) -> std::optional<double> {
    const auto it = j.find(key);
    if (it == j.end() || it->is_null()) return std::nullopt;
    return it->get<double>();
  };
  s.rmse_all_before_deg = num("rmse_all_before_deg");
  s.rmse_all_after_deg = num("rmse_all_after_deg");
  s.effects = j.at("effects").get<std::vector<std::string>>();
  s.rmse_calibrate_before_deg = num("rmse_calibrate_before_deg");
  s.rmse_calibrate_after_deg = num("rmse_calibrate_after_deg");
  s.rmse_validate_before_deg = optional_of("rmse_validate_before_deg");
  s.rmse_validate_after_deg = optional_of("rmse_validate_after_deg");
  s.reduction = num("reduction");
  s.no_pile_predicted = j.value("no_pile_predicted", std::vector<std::string>{});
  return s;
}

}  // namespace reposetwin::experiments
