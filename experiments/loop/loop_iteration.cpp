// One iteration of the loop (loop.hpp's design note): the residual of the current model traced
// on the angle and jointly on every measured observable (loop_decision.hpp), the decision what to
// refit, the refit by simulation (loop_refit.cpp) and its confirmation.
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "experiments/io/format.hpp"
#include "experiments/loop/loop_joint_surface.hpp"
#include "experiments/loop/loop_stages.hpp"

namespace reposetwin::experiments::loop_detail {

namespace {

// The slope of the current model's value of a channel against mu_r at the fit, over a tenth of
// the grid span (the monotone fit is piecewise linear).
double mu_slope(const LoopContext& ctx, const LoopState& state, std::size_t i, Channel channel) {
  const std::vector<double>& grid = ctx.grid;
  const double span = grid.back() - grid.front();
  const double a = std::max(grid.front(), state.fit.mu - 0.05 * span);
  const double b = std::min(grid.back(), state.fit.mu + 0.05 * span);
  return (state.model.value(i, b, channel) - state.model.value(i, a, channel)) / (b - a);
}

// One channel over `tests`: the residual, its noise and its slope against mu_r.
TraceChannel trace_channel(const LoopContext& ctx, const LoopState& state,
                           const std::vector<std::size_t>& tests, Channel c) {
  const Eigen::Index n = static_cast<Eigen::Index>(tests.size());
  TraceChannel ch{channel_name(c), channel_unit(c), Eigen::VectorXd(n), Eigen::VectorXd(n),
                  Eigen::VectorXd(n)};
  for (Eigen::Index k = 0; k < n; ++k) {
    const std::size_t i = tests[k];
    ch.residual[k] = ctx.observed(i, c) - state.model.value(i, state.fit.mu, c);
    ch.sigma[k] = ctx.sigma(i, c);
    ch.mu_sensitivity[k] = mu_slope(ctx, state, i, c);
  }
  return ch;
}

// The observables traced jointly over `tests`: the angle always; H and D when every traced test
// has them measured; the crest width when the lab data give it on every traced test (absent
// from every test: the problem is the one without it).
JointProblem joint_problem(const LoopContext& ctx, const LoopState& state,
                           const std::vector<std::size_t>& tests,
                           std::vector<std::string>& left_out) {
  JointProblem p;
  p.mu_shift_lo = ctx.grid.front() - state.fit.mu;
  p.mu_shift_hi = ctx.grid.back() - state.fit.mu;
  bool hd = true;
  for (std::size_t i : tests)
    hd = hd && ctx.tests()[i].height_mm.has_value() && ctx.tests()[i].diameter_mm.has_value();
  if (!hd) left_out.push_back("H and D: not measured on every test");
  std::vector<Channel> always = {Channel::kAngle};
  if (hd) always.insert(always.end(), {Channel::kH, Channel::kD});
  for (Channel c : always) {
    TraceChannel ch = trace_channel(ctx, state, tests, c);
    // A flat mu_r response (all slopes ~0) still leaves mu_r free as a constant shift.
    if (c == Channel::kAngle && ch.mu_sensitivity.cwiseAbs().maxCoeff() < 1e-6)
      ch.mu_sensitivity.setOnes();
    p.channels.push_back(std::move(ch));
  }
  if (!ctx.noise.crest_measured) return p;
  const Channel cr = Channel::kCrest;
  OptionalChannel crest{trace_channel(ctx, state, tests, cr), std::vector<bool>(tests.size())};
  for (std::size_t k = 0; k < tests.size(); ++k) {
    const bool measured = ctx.tests()[tests[k]].crest_mm.has_value();
    crest.measured[k] = measured;
    if (!measured) crest.channel.residual[static_cast<Eigen::Index>(k)] = 0.0;
  }
  add_optional_channel(p, crest, left_out);
  return p;
}

// The traced tests the model predicts a pile for and every unused candidate has a fingerprint
// for. A held-out test whose twin pours jammed has no residual to trace (its "no pile" is
// reported with the residuals); a test the baseline formed no pile for has no fingerprint (a
// refit of weight 1 can give it a prediction while the baseline gives none). Both are named in
// left_out.
std::vector<std::size_t> traced_tests(const LoopContext& ctx, const LoopState& state,
                                      const std::vector<FingerprintRecord>& fps,
                                      std::vector<std::string>& left_out) {
  std::vector<std::size_t> predicted;
  for (std::size_t i : ctx.roles.traced) {
    const std::string why = state.model.no_pile(i);
    if (why.empty())
      predicted.push_back(i);
    else
      left_out.push_back(ctx.tests()[i].id + ": " + why);
  }
  std::vector<std::size_t> tests;
  for (std::size_t i : predicted) {
    bool fingerprinted = true;
    for (const FingerprintRecord& f : fps)
      fingerprinted = fingerprinted &&
                      (state.used.count(f.name) || std::isfinite(f.change[Channel::kAngle][i]));
    if (fingerprinted)
      tests.push_back(i);
    else
      left_out.push_back(ctx.tests()[i].id +
                         ": no fingerprint (the baseline formed no pile for it)");
  }
  return tests;
}

// A crest fingerprint from photographs cached before the crest was recorded has no value: the
// channel then leaves this trace rather than carry NaN into every score.
void drop_unrecorded_crest(const LoopContext& ctx, const LoopState& state,
                           const std::vector<FingerprintRecord>& fps,
                           const std::vector<std::size_t>& tests, JointProblem& joint,
                           std::vector<std::string>& left_out) {
  if (joint.channels.back().name != channel_name(Channel::kCrest)) return;
  for (const FingerprintRecord& f : fps) {
    if (state.used.count(f.name)) continue;
    const std::vector<double>& crest = f.change[Channel::kCrest];
    bool finite = crest.size() == ctx.tests().size();
    for (std::size_t i : tests) finite = finite && std::isfinite(crest[i]);
    if (finite) continue;
    joint.channels.pop_back();
    left_out.push_back("crest: the photographs of " + f.name + "'s fingerprint do not record it");
    return;
  }
}

// The mu_r samples the joint fits run over: the grid's span in steps of at most a two-hundredth
// of it, every grid point among them.
std::vector<double> mu_samples(const std::vector<double>& grid) {
  const int kPerSpan = 200;
  std::vector<double> mu = {grid.front()};
  const double span = grid.back() - grid.front();
  for (std::size_t q = 1; q < grid.size(); ++q) {
    const double a = grid[q - 1], b = grid[q];
    const int steps = std::max(1, static_cast<int>(std::ceil(kPerSpan * (b - a) / span)));
    for (int k = 1; k <= steps; ++k) mu.push_back(k == steps ? b : a + (b - a) * k / steps);
  }
  return mu;
}

// The traced channels on the surfaces: the lab's values, their noise and the current model at
// every mu_r sample (loop_joint_surface.hpp).
SurfaceProblem surface_problem(const LoopContext& ctx, const LoopState& state,
                               const std::vector<std::size_t>& tests, const JointProblem& joint) {
  SurfaceProblem sp;
  sp.mu = mu_samples(ctx.grid);
  sp.mu_fit = state.fit.mu;
  const Eigen::Index n = static_cast<Eigen::Index>(tests.size());
  const Eigen::Index k = static_cast<Eigen::Index>(sp.mu.size());
  for (const TraceChannel& ch : joint.channels) {
    const Channel c = channel_from_name(ch.name);
    SurfaceChannel sc{ch.name, Eigen::VectorXd(n), ch.sigma, Eigen::MatrixXd(k, n)};
    for (Eigen::Index i = 0; i < n; ++i) {
      sc.observed[i] = ctx.observed(tests[static_cast<std::size_t>(i)], c);
      for (Eigen::Index q = 0; q < k; ++q)
        sc.predicted(q, i) = state.model.value(tests[static_cast<std::size_t>(i)],
                                               sp.mu[static_cast<std::size_t>(q)], c);
    }
    sp.channels.push_back(std::move(sc));
  }
  return sp;
}

// A fingerprint on the surface problem's samples (fingerprint_at).
SurfaceFingerprint surface_fingerprint(const FingerprintRecord& f, const SurfaceProblem& sp,
                                       const std::vector<std::size_t>& tests) {
  const Eigen::Index n = static_cast<Eigen::Index>(tests.size());
  const Eigen::Index k = static_cast<Eigen::Index>(sp.mu.size());
  SurfaceFingerprint out;
  for (const SurfaceChannel& ch : sp.channels) {
    const Channel c = channel_from_name(ch.name);
    Eigen::MatrixXd m(k, n);
    for (Eigen::Index q = 0; q < k; ++q)
      for (Eigen::Index i = 0; i < n; ++i)
        m(q, i) = fingerprint_at(f, c, tests[static_cast<std::size_t>(i)],
                                 sp.mu[static_cast<std::size_t>(q)]);
    out.push_back(std::move(m));
  }
  return out;
}

// Every unused fingerprint scored against the residual: on the angle at its grid point (the
// acceptance rule) and jointly with mu_r on the surfaces, with the strength each fit asks for
// against what the effect can do.
void score_fingerprints(const LoopContext& ctx, const LoopState& state,
                        const std::vector<FingerprintRecord>& fps,
                        const std::vector<std::size_t>& tests, const SurfaceProblem& sp,
                        const TraceProblem& p, IterationRecord& rec) {
  const Eigen::Index n = p.residual.size();
  for (const FingerprintRecord& f : fps) {
    if (state.used.count(f.name)) continue;
    Eigen::VectorXd angle(n);
    for (Eigen::Index k = 0; k < n; ++k)
      angle[k] = f.change[Channel::kAngle][tests[static_cast<std::size_t>(k)]];
    rec.candidates.push_back(score_candidate(p, f.name, angle, rec.null, ctx.s().rule));
    rec.joint.push_back(score_joint_on_surfaces(sp, f.name, surface_fingerprint(f, sp, tests)));
    const CandidateEffect& e = find_effect(f.name);
    const double off = ctx.effect_off(e);
    CandidateScore& a = rec.candidates.back();
    JointScore& j = rec.joint.back();
    a.out_of_range = outside_range(a.coef, a.coef_se, off, f.probe, e.lo, e.hi, e.units);
    if (j.identifiable)
      j.out_of_range = outside_range(j.coef, j.coef_se, off, f.probe, e.lo, e.hi, e.units);
  }
}

}  // namespace

// The residual of the current model regressed on every unused fingerprint: on the angle (the
// acceptance rule) and jointly on every measured observable (the decision), over every test.
IterationRecord trace(const LoopContext& ctx, int it, const LoopState& state,
                      const std::vector<FingerprintRecord>& fps) {
  IterationRecord rec;
  rec.iteration = it;
  rec.mu_r = state.fit.mu;
  const std::vector<std::size_t> tests = traced_tests(ctx, state, fps, rec.tests_left_out);
  // The design's own bound (describe_design): fewer tests than that leave nothing to judge a
  // candidate by; the iteration then says so and traces nothing.
  if (tests.size() < 4) {
    rec.decision.statement = "nothing traced: " + std::to_string(tests.size()) +
                             " test(s) have a prediction (the twin forms no pile for the "
                             "others); a leave-one-out check of a mu_r correction and one effect "
                             "needs at least 4";
    return rec;
  }
  JointProblem joint = joint_problem(ctx, state, tests, rec.channels_left_out);
  drop_unrecorded_crest(ctx, state, fps, tests, joint, rec.channels_left_out);
  for (const TraceChannel& ch : joint.channels) rec.channels.push_back(ch.name);
  TraceProblem p;
  p.residual = joint.channels[0].residual;
  p.sigma = joint.channels[0].sigma;
  p.mu_sensitivity = joint.channels[0].mu_sensitivity;
  p.seed_noise_deg = ctx.noise.se;
  p.mu_shift_lo = joint.mu_shift_lo;
  p.mu_shift_hi = joint.mu_shift_hi;
  rec.null = score_null(p);
  const SurfaceProblem sp = surface_problem(ctx, state, tests, joint);
  score_fingerprints(ctx, state, fps, tests, sp, p, rec);
  rec.offset = score_offset_on_surfaces(sp);
  rec.mu_only = score_joint_on_surfaces(sp, "mu_r only", {});
  return rec;
}

namespace {

// The decision on the iteration's record: the acceptance rule names contenders; the joint
// decision names one, or none when the data cannot tell them apart or point at the measurement
// (loop_decision.hpp); a declared hypothesis (--refit) may take the pick.
RefitPick decide(const LoopContext& ctx, const LoopState& state, IterationRecord& iter) {
  rank_candidates(iter.candidates);
  if (iter.offset)  // else too few tests had a prediction to trace (trace's statement)
    iter.decision =
        decide_trace(iter.candidates, iter.joint, *iter.offset, *iter.mu_only, ctx.s().rule);
  const RefitPick choice = pick_refit(iter.candidates, iter.decision, ctx.s().refit, state.used);
  iter.declared = choice.declared;
  if (choice.declared)
    ctx.say("iteration " + std::to_string(iter.iteration) + ": " + *choice.declared);
  return choice;
}

// Why the iteration ends without a refit: the decision's statement, or the effect limit that
// stops the loop before a candidate's refit (--max-effects 0 traces and ranks only).
void stop_before_refit(const LoopContext& ctx, const RefitPick& choice, IterationRecord& iter) {
  const std::string at = "iteration " + std::to_string(iter.iteration) + ": ";
  if (choice.index < 0) {
    ctx.say(at + iter.decision.statement);
    return;
  }
  iter.stopped = "max_effects (" + std::to_string(ctx.s().max_effects) +
                 ") reached: " + iter.candidates[static_cast<std::size_t>(choice.index)].name +
                 (choice.declared ? " was declared for refit" : " meets the acceptance rule") +
                 " but was not refitted";
  ctx.say(at + *iter.stopped);
}

// The refit of the pick: its strength, channels and linear estimate. A candidate admitted on the
// joint evidence alone (loop_decision.hpp) is refitted on it: its strength is the joint fit's,
// and mu_r and the effect are fitted to every traced observable. One that passed on the angle
// keeps the angle's strength and fit. Nothing, with the record's reason, when the estimate is
// the effect's off value.
std::optional<RefitPlan> plan_refit(const LoopContext& ctx, const RefitPick& choice,
                                    const std::vector<FingerprintRecord>& fps, double mu_node,
                                    IterationRecord& iter) {
  const CandidateScore sc = iter.candidates[static_cast<std::size_t>(choice.index)];
  const CandidateEffect& e = find_effect(sc.name);
  RefitPlan plan{.effect = &e,
                 .off = ctx.effect_off(e),
                 .coef = sc.coef,
                 .mu_at = mu_node,
                 .channels = {Channel::kAngle},
                 .declared = choice.declared.has_value()};
  plan.fingerprint =
      &*std::find_if(fps.begin(), fps.end(), [&](const auto& f) { return f.name == e.name; });
  plan.column = plan.fingerprint->change;
  if (!sc.accepted) {
    // The joint fit's strength, at the mu_r it was fitted at on the surfaces.
    for (const JointScore& j : iter.joint)
      if (j.name == sc.name) {
        plan.coef = j.coef;
        plan.mu_at = iter.mu_r + j.mu_shift;
      }
    for (const std::string& ch : iter.channels)
      if (const Channel c = channel_from_name(ch); c != Channel::kAngle) plan.channels.push_back(c);
    for (Channel c : plan.channels) {
      plan.column[c].assign(ctx.tests().size(), std::numeric_limits<double>::quiet_NaN());
      for (std::size_t i = 0; i < ctx.tests().size(); ++i)
        plan.column[c][i] = fingerprint_at(*plan.fingerprint, c, i, plan.mu_at);
    }
  }
  // c is in units of the probe the fingerprint was simulated at (scaled when the registry's
  // probe was lost in the seed noise).
  const double off = plan.off;
  plan.p1 = std::clamp(off + plan.coef * (plan.fingerprint->probe - off), e.lo, e.hi);
  const std::string at = "iteration " + std::to_string(iter.iteration) + ": ";
  if (plan.p1 == off) {
    // Only a declared hypothesis gets here (the rule's contenders lie in their range): its
    // traced strength points to the far side of its off value, where the effect cannot go.
    iter.stopped = e.name + ": its traced strength c = " + std::to_string(plan.coef) +
                   " of its probe puts it at or beyond its off value " + std::to_string(off) + " " +
                   e.units + " (range " + std::to_string(e.lo) + " to " + std::to_string(e.hi) +
                   "); nothing to refit";
    ctx.say(at + *iter.stopped);
    return std::nullopt;
  }
  ctx.say(at + e.name + " accepted (" + (sc.accepted ? sc.why : "on the joint fit") +
          "); linear estimate " + std::to_string(plan.p1) + " " + e.units +
          ", simulating the grid");
  return plan;
}

// The joint region of a chosen effect's value, and what would separate it from mu_r: a repeat
// of each fitted test, as an independent observation with that test's noise (the lab's repeat
// and the twin's seeds alike). The region is read over every trial of the refit at the best
// one's likelihood (value_region): trials that land at other (mu_r, value) pairs with chi^2
// alike are as likely, and a region read off the best trial's chord alone misses them (rods:
// trials at L/I 1.92 and 2.37 fitted within 0.02 deg of each other at mu_r 0.25 and 0.4).
void add_region(const LoopContext& ctx, const CandidateEffect& e, const Refit& refit,
                const Trial& best, ChosenEffect& c) {
  const MuFit& joint = best.joint;
  c.region = joint.region;
  std::vector<ChordScan> chords;
  for (const Trial& tr : refit.trials)
    if (tr.joint.region && !tr.joint.profile.empty())
      chords.push_back({tr.p, tr.joint.t_max, tr.joint.profile, *tr.joint.region});
  const ValueRegion v = value_region(chords, c.off);
  c.value_lo = v.value_lo;
  c.value_hi = v.value_hi;
  if (chords.size() > 1) {
    c.region->mu_lo = v.mu_lo;
    c.region->mu_hi = v.mu_hi;
    c.region->mu_at_bound = c.region->mu_at_bound || v.mu_at_bound;
    c.region->t_at_bound = c.region->t_at_bound || v.t_at_bound;
    c.region->separated = c.region->separated && !v.mu_at_bound && !v.t_at_bound;
    c.region->statement +=
        "; read over the refit's " + std::to_string(chords.size()) +
        " simulated trials at one likelihood (chi^2 <= " + significant(v.chi2_limit, 3) + ", " +
        std::to_string(v.chords) + " of them inside): mu_r " + significant(v.mu_lo, 3) + "-" +
        significant(v.mu_hi, 3);
  }
  ctx.say(e.name + ": " + c.region->statement + "; the value " + significant(c.value_lo, 3) + "-" +
          significant(c.value_hi, 3) + " " + e.units);
  std::vector<NextTest> repeats;
  for (const auto& [i, part] : joint.test_info)
    repeats.push_back({"a repeat of " + ctx.tests()[i].id, part});
  c.next_tests = rank_next_tests(joint.info, repeats);
  if (!c.next_tests.empty())
    ctx.say(e.name + ": " + c.next_tests.front().name + " would shrink its interval to " +
            significant(100.0 * c.next_tests.front().t_interval_ratio, 3) + "% (mu_r's to " +
            significant(100.0 * c.next_tests.front().mu_interval_ratio, 3) + "%)");
}

// The record of a refit: its estimate, best trial and every trial.
RefitSummary refit_summary(const RefitPlan& plan, const Refit& refit) {
  const Trial& best = best_trial(refit);
  RefitSummary summary{plan.effect->name, plan.p1, best.p,     best.joint.t,
                       best.joint.mu,     {},      refit.notes};
  for (const Trial& tr : refit.trials)
    summary.trials.push_back({tr.p, tr.fraction, tr.joint.t, tr.joint.mu, tr.rmse, tr.no_pile});
  return summary;
}

// The calibration misfit of a trial on the angle: the fitted tests' squared residuals over their
// noise, and its degrees of freedom (the residuals less the two fitted values, mu_r and t).
struct Misfit {
  double chi2 = 0.0;
  int dof = 0;
};

Misfit calibration_misfit(const LoopContext& ctx, const Trial& tr) {
  Misfit m;
  int values = 0;
  for (std::size_t i : ctx.roles.fitted) {
    const double r = ctx.observed(i, Channel::kAngle) - tr.model.angle(i, tr.joint.mu);
    if (!std::isfinite(r)) continue;  // a test the trial predicts no pile for
    m.chi2 += std::pow(r / ctx.sigma(i, Channel::kAngle), 2);
    ++values;
  }
  m.dof = values - 2;
  return m;
}

// The trace ranks candidates on fingerprints scaled linearly from one probe; an effect whose
// response bends (rods of L/I 2.6 traced from a probe at 1.5) can be ranked below one that fits
// the linear picture better but the simulated piles worse. The simulated refit is the judge: when
// the named candidate's best refit still misfits the calibration tests beyond their noise (chi^2
// above its 95% point), the next contender by joint chi^2 is refitted by simulation too, and the
// refit with the lower calibration RMSE is kept; the other is recorded as set aside. A declared
// hypothesis is the user's and is not replaced.
void refit_next_contender(const LoopContext& ctx, PileStore& store,
                          const std::vector<FingerprintRecord>& fps, std::size_t node,
                          const LoopState& state, const RefitPick& choice, IterationRecord& iter,
                          RefitPlan& plan, Refit& refit) {
  if (choice.declared || iter.decision.verdict != TraceVerdict::kNamed) return;
  const Misfit m = calibration_misfit(ctx, best_trial(refit));
  if (m.dof < 1 || m.chi2 <= chi2_95(m.dof)) return;
  const std::vector<std::string>& cs = iter.decision.contenders;
  const auto next = std::find_if(cs.begin(), cs.end(), [&](const std::string& n) {
    return n != plan.effect->name && !state.used.count(n);
  });
  if (next == cs.end()) return;
  int index = -1;
  for (std::size_t q = 0; q < iter.candidates.size(); ++q)
    if (iter.candidates[q].name == *next) index = static_cast<int>(q);
  if (index < 0) return;
  const double rmse = best_trial(refit).rmse;
  char misfit[200];
  std::snprintf(misfit, sizeof misfit,
                "its best refit leaves calibration chi^2 %.3g over %d degrees of freedom (95%% "
                "point %.3g; RMSE %.3g deg)",
                m.chi2, m.dof, chi2_95(m.dof), rmse);
  ctx.say("iteration " + std::to_string(iter.iteration) + ": " + plan.effect->name + ": " + misfit +
          "; refitting the next contender, " + *next);
  const std::optional<RefitPlan> alt_plan =
      plan_refit(ctx, RefitPick{index, std::nullopt}, fps, ctx.grid[node], iter);
  if (!alt_plan) return;
  Refit alt = refit_by_simulation(ctx, store, *alt_plan, state);
  if (alt.trials.empty() || best_trial(alt).rmse >= rmse) {
    refit.notes += std::string(misfit) + "; the next contender, " + *next + ", refitted to " +
                   (alt.trials.empty() ? std::string("no simulated trial")
                                       : "RMSE " + significant(best_trial(alt).rmse, 3) + " deg") +
                   ", no better; ";
    return;
  }
  iter.set_aside =
      NotConfirmed{refit_summary(plan, refit), rmse,
                   std::string(misfit) + "; the next contender, " + *next + ", refits to RMSE " +
                       significant(best_trial(alt).rmse, 3) + " deg, and is kept"};
  plan = *alt_plan;
  refit = std::move(alt);
}

// The confirmation the simulations must give (unconfirmed_reason): the chosen effect with its
// value, or nothing with the record's reason.
std::optional<ChosenEffect> confirm(const LoopContext& ctx, const RefitPlan& plan,
                                    const Refit& refit, const LoopState& state,
                                    IterationRecord& iter) {
  const CandidateEffect& e = *plan.effect;
  const Trial& best = best_trial(refit);
  const MuFit& joint = best.joint;
  const RefitSummary summary = refit_summary(plan, refit);
  const std::string reason = unconfirmed_reason(ctx, best, state);
  if (!reason.empty()) {
    iter.not_confirmed = NotConfirmed{summary, best.rmse, reason};
    ctx.say(e.name + ": not confirmed by the simulated refit (" + reason + "); not chosen");
    return std::nullopt;
  }
  ChosenEffect c;
  c.refit = summary;
  c.kind = e.kind == EffectKind::kPhysics ? "physics" : "measurement";
  c.key = e.key;
  c.units = e.units;
  c.off = plan.off;
  c.probe = plan.fingerprint->probe;
  c.value = plan.off + joint.t * (best.p - plan.off);
  c.value_se = joint.t_se * std::abs(best.p - plan.off);
  c.t_at_limit = joint.t <= 0.0 || joint.t >= ctx.s().t_max;
  c.mu_r_se = joint.mu_se;
  c.declared = plan.declared && iter.decision.named != e.name;
  if (joint.region) add_region(ctx, e, refit, best, c);
  return c;
}

}  // namespace

bool iterate(const LoopContext& ctx, PileStore& store, int it, LoopState& state,
             const std::vector<FingerprintRecord>& fps, std::size_t node,
             std::vector<IterationRecord>& iterations) {
  IterationRecord& iter = iterations.emplace_back(trace(ctx, it, state, fps));
  const RefitPick choice = decide(ctx, state, iter);
  if (choice.index < 0 || it == ctx.s().max_effects) {
    stop_before_refit(ctx, choice, iter);
    return false;
  }
  std::optional<RefitPlan> plan = plan_refit(ctx, choice, fps, ctx.grid[node], iter);
  if (!plan) return false;
  Refit refit = refit_by_simulation(ctx, store, *plan, state);
  if (refit.trials.empty()) {
    iter.refit_failed = RefitFailed{plan->effect->name, refit.notes, plan->p1};
    return false;
  }
  refit_next_contender(ctx, store, fps, node, state, choice, iter, *plan, refit);
  const std::optional<ChosenEffect> chosen = confirm(ctx, *plan, refit, state, iter);
  if (!chosen) return false;
  const Trial& best = best_trial(refit);
  state.model = best.model;
  state.fit = best.joint;
  state.effects.push_back({plan->effect, chosen->value});
  state.used.insert(plan->effect->name);
  state.chosen.push_back(*chosen);
  iter.chosen = *chosen;
  return true;
}

FinalRecord final_record(const LoopContext& ctx, const LoopState& state) {
  FinalRecord f;
  f.fit = state.fit;
  f.effects = state.chosen;
  f.residuals = residuals(ctx, state.model, state.fit.mu);
  f.rmse = rmse_by_role(f.residuals);
  return f;
}

}  // namespace reposetwin::experiments::loop_detail
