#include "experiments/loop/loop_decision.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "experiments/io/format.hpp"
#include "experiments/io/json_fields.hpp"
#include "experiments/io/json_read.hpp"

namespace reposetwin::experiments {

bool add_optional_channel(JointProblem& p, const OptionalChannel& obs,
                          std::vector<std::string>& left_out) {
  const TraceChannel& ch = obs.channel;
  const std::size_t n = obs.measured.size();
  const std::size_t have =
      static_cast<std::size_t>(std::count(obs.measured.begin(), obs.measured.end(), true));
  if (have == 0) return false;
  if (have < n) {
    left_out.push_back(ch.name + ": measured on " + std::to_string(have) + " of " +
                       std::to_string(n) + " traced tests");
    return false;
  }
  if (static_cast<std::size_t>(ch.residual.size()) != n ||
      static_cast<std::size_t>(ch.sigma.size()) != n ||
      static_cast<std::size_t>(ch.mu_sensitivity.size()) != n)
    throw std::invalid_argument("joint trace: channel " + ch.name + " has a different size");
  if (!ch.residual.allFinite() || !ch.sigma.allFinite() || !ch.mu_sensitivity.allFinite()) {
    left_out.push_back(ch.name + ": the twin's photographs do not all record it");
    return false;
  }
  if (!(ch.sigma.minCoeff() > 0.0)) {
    left_out.push_back(ch.name + ": its seed noise is zero (the twin's value does not vary)");
    return false;
  }
  p.channels.push_back(ch);
  return true;
}

std::string trace_verdict_name(TraceVerdict v) {
  switch (v) {
    case TraceVerdict::kNothing:
      return "nothing";
    case TraceVerdict::kNamed:
      return "named";
    case TraceVerdict::kIndistinguishable:
      return "indistinguishable";
    case TraceVerdict::kMeasurementSuspected:
      return "measurement_suspected";
  }
  return "nothing";
}

namespace {

std::string describe(const JointScore& s) {
  return s.name + " (c = " + significant(s.coef, 3) + " +- " + significant(s.coef_se, 3) +
         ", joint chi^2 " + significant(s.chi2, 3) + " over " + std::to_string(s.rows) +
         " values, leave-one-out " + significant(s.loo_chi2, 3) + ")";
}

}  // namespace

std::string outside_range(double coef, double coef_se, double off, double probe, double lo,
                          double hi, const std::string& units) {
  const double value = off + coef * (probe - off);
  const double band = 2.0 * coef_se * std::abs(probe - off);
  if (value + band >= lo && value - band <= hi) return "";
  const bool below = value + band < lo;
  return "c = " + significant(coef, 3) + " +- " + significant(coef_se, 3) + " puts it at " +
         significant(value, 3) + " +- " + significant(0.5 * band, 3) + " " + units + ", " +
         (below ? "below" : "above") + " its range's end " + significant(below ? lo : hi, 3) + " " +
         units;
}

bool accepted_jointly(const JointScore& j, const JointScore& mu_only, const AcceptanceRule& rule) {
  return j.chi2_by_channel.size() > 1 && j.identifiable && j.t > rule.min_t &&
         mu_only.loo_chi2 - j.loo_chi2 > rule.min_delta_chi2;
}

namespace {

// The candidates that meet the acceptance rule, on the angle or jointly (design note), and
// those that met it with a fit outside the effect's range, in words.
struct Contenders {
  std::vector<const JointScore*> list;  // sorted by joint chi^2
  std::vector<std::string> joint_only;  // contend by the joint rule alone
  std::vector<std::string> outside;     // met the rule outside the effect's range
};

Contenders gather_contenders(const std::vector<CandidateScore>& angle,
                             const std::vector<JointScore>& joint, const JointScore& mu_only,
                             const AcceptanceRule& rule) {
  Contenders c;
  for (const CandidateScore& a : angle) {
    if (!a.accepted) continue;
    const auto it = std::find_if(joint.begin(), joint.end(),
                                 [&](const JointScore& j) { return j.name == a.name; });
    if (it == joint.end())
      throw std::invalid_argument("decide_trace: no joint score for " + a.name);
    if (!a.out_of_range.empty())
      c.outside.push_back(a.name + " (on the angle: " + a.out_of_range + ")");
    else
      c.list.push_back(&*it);
  }
  for (const JointScore& j : joint) {
    const bool on_angle = std::any_of(angle.begin(), angle.end(), [&](const CandidateScore& a) {
      return a.accepted && a.name == j.name;
    });
    if (on_angle || !accepted_jointly(j, mu_only, rule)) continue;
    if (!j.out_of_range.empty()) {
      c.outside.push_back(j.name + " (jointly: " + j.out_of_range + ")");
      continue;
    }
    c.list.push_back(&j);
    c.joint_only.push_back(j.name);
  }
  std::stable_sort(c.list.begin(), c.list.end(),
                   [](const JointScore* x, const JointScore* y) { return x->chi2 < y->chi2; });
  return c;
}

// The verdict among the contenders, the offset hypothesis and the mu_r correction alone.
TraceDecision decide_among(const Contenders& c, const JointScore& offset, const JointScore& mu_only,
                           const AcceptanceRule& rule) {
  const std::vector<const JointScore*>& contenders = c.list;
  const bool offset_flag = offset.identifiable && offset.t > rule.min_t &&
                           mu_only.chi2 - offset.chi2 > rule.min_delta_chi2;
  TraceDecision d;
  for (const JointScore* x : contenders) d.contenders.push_back(x->name);
  const std::string offset_words =
      "a uniform offset of " + significant(offset.coef, 3) + " +- " +
      significant(offset.coef_se, 3) + " deg on every test (|c|/se " + significant(offset.t, 3) +
      "), beyond mu_r's reach (joint chi^2 " + significant(offset.chi2, 3) + " against " +
      significant(mu_only.chi2, 3) + " with the mu_r correction alone" +
      (offset.mu_shift_at_bound ? ", which stops at the grid's bound)" : ")");
  if (offset_flag &&
      (contenders.empty() || offset.chi2 - contenders.front()->chi2 <= rule.min_delta_chi2)) {
    d.verdict = TraceVerdict::kMeasurementSuspected;
    d.statement = "suspected measurement or declared-condition error, no physical effect named: " +
                  offset_words +
                  (contenders.empty() ? std::string("; no candidate meets the acceptance rule")
                                      : "; the best candidate, " + describe(*contenders.front()) +
                                            ", does not beat it by more than " +
                                            significant(rule.min_delta_chi2, 3));
    return d;
  }
  if (contenders.empty()) {
    d.statement = c.outside.empty() ? "no candidate meets the acceptance rule"
                                    : "no candidate meets the acceptance rule within its range";
    return d;
  }
  const double best = contenders.front()->chi2;
  for (const JointScore* x : contenders)
    if (x->chi2 - best <= rule.min_delta_chi2) d.tied.push_back(x->name);
  if (d.tied.size() > 1) {
    d.verdict = TraceVerdict::kIndistinguishable;
    d.statement = "indistinguishable within the noise, none named:";
    for (const JointScore* x : contenders)
      if (x->chi2 - best <= rule.min_delta_chi2) d.statement += " " + describe(*x) + ";";
    d.statement += " their joint chi^2 differ by " + significant(rule.min_delta_chi2, 3) +
                   " or less; a further observable or test must decide";
    return d;
  }
  d.tied.clear();
  d.verdict = TraceVerdict::kNamed;
  d.named = contenders.front()->name;
  d.statement = "named " + describe(*contenders.front());
  if (std::find(c.joint_only.begin(), c.joint_only.end(), d.named) != c.joint_only.end())
    d.statement += " (accepted on the joint fit, not on the angle alone: leave-one-out " +
                   significant(contenders.front()->loo_chi2, 3) + " against " +
                   significant(mu_only.loo_chi2, 3) + " with the mu_r correction alone)";
  if (contenders.size() > 1)
    d.statement += "; next " + describe(*contenders[1]) + ", worse by " +
                   significant(contenders[1]->chi2 - best, 3) + " > " +
                   significant(rule.min_delta_chi2, 3);
  if (offset_flag) d.statement += "; it beats " + offset_words;
  return d;
}

}  // namespace

TraceDecision decide_trace(const std::vector<CandidateScore>& angle,
                           const std::vector<JointScore>& joint, const JointScore& offset,
                           const JointScore& mu_only, const AcceptanceRule& rule) {
  const Contenders c = gather_contenders(angle, joint, mu_only, rule);
  TraceDecision d = decide_among(c, offset, mu_only, rule);
  if (!c.outside.empty()) {
    d.statement += "; met the rule with a fit outside the effect's range, so not a contender:";
    for (const std::string& o : c.outside) d.statement += " " + o + ";";
  }
  return d;
}

RefitPick pick_refit(const std::vector<CandidateScore>& ranked, const TraceDecision& d,
                     const std::string& declared, const std::set<std::string>& used) {
  auto index_of = [&](const std::string& name) {
    for (std::size_t q = 0; q < ranked.size(); ++q)
      if (ranked[q].name == name) return static_cast<int>(q);
    return -1;
  };
  RefitPick pick;
  if (d.verdict == TraceVerdict::kNamed) pick.index = index_of(d.named);
  if (declared.empty() || used.count(declared)) return pick;
  const std::string verdict = "the trace's own verdict: " + trace_verdict_name(d.verdict) +
                              (d.statement.empty() ? "" : " (" + d.statement + ")");
  if (pick.index >= 0 && d.named == declared) {
    pick.declared = declared + " was declared for refit (--refit) and the trace names it too";
    return pick;
  }
  const int q = index_of(declared);
  if (q < 0) {
    pick.declared = declared +
                    " was declared for refit (--refit) but has no score to refit from (see the "
                    "unavailable candidates), so the trace decides; " + verdict;
    return pick;
  }
  pick.index = q;
  pick.declared = declared + " is refitted because it was declared (--refit), not because the "
                  "trace names it; " + verdict;
  return pick;
}

DesignRecord describe_design(int n_cal, int n_val) {
  if (n_cal < 1)
    throw std::invalid_argument("the loop needs at least one calibration test to fit mu_r");
  DesignRecord d;
  d.n_calibrate = n_cal;
  d.n_validate = n_val;
  const int n = n_cal + n_val;
  d.can_trace = n >= 4;
  d.refit_on_all = n_cal < 3;
  const std::string ncal = std::to_string(n_cal), nall = std::to_string(n);
  d.can.push_back("mu_r is fitted on the " + ncal + " calibration test(s)");
  if (n_cal == 1)
    d.cannot.push_back(
        "the one calibration test is matched exactly by mu_r (where the grid lets it): its "
        "residual is then zero by construction and says nothing of the model; the evidence is "
        "in the predictions");
  if (n_val == 0)
    d.cannot.push_back("no test is held out: the out-of-sample evidence is the leave-one-out");
  if (d.can_trace)
    d.can.push_back("the residuals of all " + nall + " tests (" + ncal + " calibration, " +
                    std::to_string(n_val) +
                    " predicted) are traced with a mu_r correction, each candidate judged by "
                    "leave-one-test-out over all of them with the seed noise known");
  else
    d.cannot.push_back("with " + nall +
                       " test(s) nothing can be traced: a leave-one-out check of a mu_r "
                       "correction and one effect needs at least 4 tests; the residuals are "
                       "reported as they are");
  // The statement why nothing can be traced stays the last one (the loop quotes it).
  if (d.can_trace && d.refit_on_all)
    d.cannot.push_back(
        "a joint refit of mu_r and an effect on fewer than 3 calibration tests is not "
        "determined, so it uses every test: the held-out RMSE after the refit is in-sample, "
        "the leave-one-out is the out-of-sample measure");
  else if (d.can_trace && n_val > 0)
    d.can.push_back("the refit uses the calibration tests: the held-out RMSE after it is "
                    "out-of-sample");
  return d;
}

nlohmann::json to_json(const JointScore& s) {
  return {{"name", s.name},
          {"identifiable", s.identifiable},
          {"coef", s.coef},
          {"coef_se", s.coef_se},
          {"t", s.t},
          {"mu_shift", s.mu_shift},
          {"mu_shift_at_bound", s.mu_shift_at_bound},
          {"chi2", s.chi2},
          {"loo_chi2", s.loo_chi2},
          {"values", s.rows},
          {"chi2_by_channel", s.chi2_by_channel},
          {"out_of_range", text_or_null(s.out_of_range)}};
}

nlohmann::json to_json(const TraceDecision& d) {
  nlohmann::json j = {{"verdict", trace_verdict_name(d.verdict)},
                      {"named", text_or_null(d.named)},
                      {"indistinguishable", d.tied},
                      {"statement", d.statement}};
  if (!d.contenders.empty()) j["contenders"] = d.contenders;  // absent: none met the rule
  return j;
}

nlohmann::json to_json(const DesignRecord& d) {
  return {{"n_calibrate", d.n_calibrate}, {"n_validate", d.n_validate},
          {"can_trace", d.can_trace},     {"refit_on_all_tests", d.refit_on_all},
          {"can", d.can},                 {"cannot", d.cannot}};
}

JointScore joint_score_from_json(const nlohmann::json& j) {
  JointScore s;
  s.name = field<std::string>(j, "name");
  s.identifiable = field<bool>(j, "identifiable");
  s.coef = number_field(j, "coef");
  s.coef_se = number_field(j, "coef_se");
  s.t = number_field(j, "t");
  s.mu_shift = number_field(j, "mu_shift");
  s.mu_shift_at_bound = field<bool>(j, "mu_shift_at_bound");
  s.chi2 = number_field(j, "chi2");
  s.loo_chi2 = number_field(j, "loo_chi2");
  s.rows = field<int>(j, "values");
  s.chi2_by_channel = numbers_field(j, "chi2_by_channel");
  // Absent or null: within the range (a loop.json written before the range gate has none).
  if (j.contains("out_of_range") && !j["out_of_range"].is_null())
    s.out_of_range = field<std::string>(j, "out_of_range");
  return s;
}

TraceDecision trace_decision_from_json(const nlohmann::json& j) {
  TraceDecision d;
  d.verdict = nested(j, "verdict", [](const nlohmann::json& v) {
    const std::string word = v.get<std::string>();
    for (TraceVerdict k : {TraceVerdict::kNothing, TraceVerdict::kNamed,
                           TraceVerdict::kIndistinguishable, TraceVerdict::kMeasurementSuspected})
      if (trace_verdict_name(k) == word) return k;
    throw JsonFieldError("", "\"" + word + "\" is no trace verdict");
  });
  if (!field<nlohmann::json>(j, "named").is_null()) d.named = field<std::string>(j, "named");
  d.tied = field<std::vector<std::string>>(j, "indistinguishable");
  // Absent: none met the rule, or written before the decision listed them.
  if (j.contains("contenders")) d.contenders = field<std::vector<std::string>>(j, "contenders");
  d.statement = field<std::string>(j, "statement");
  return d;
}

DesignRecord design_record_from_json(const nlohmann::json& j) {
  DesignRecord d;
  d.n_calibrate = field<int>(j, "n_calibrate");
  d.n_validate = field<int>(j, "n_validate");
  d.can_trace = field<bool>(j, "can_trace");
  d.refit_on_all = field<bool>(j, "refit_on_all_tests");
  d.can = field<std::vector<std::string>>(j, "can");
  d.cannot = field<std::vector<std::string>>(j, "cannot");
  return d;
}

}  // namespace reposetwin::experiments
