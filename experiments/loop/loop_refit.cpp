// The refit by simulation of an accepted candidate (loop.hpp's design note): the linear estimate
// simulated on the whole grid, secant refinement when the response misses the traced strength,
// trials where the fit lands until it lands on a simulated value, and the confirmation the
// simulations must give.
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>

#include "experiments/loop/loop_stages.hpp"

namespace reposetwin::experiments::loop_detail {

namespace {

// Two effect values the refit takes for one: within 1e-3 of the known one (relative above 1).
bool same_value(double known, double p) {
  return std::abs(known - p) <= 1e-3 * std::max(1.0, std::abs(known));
}

// The next value to simulate: c interpolated between the known responses `pts` (value,
// response fraction; sorted), preferring the bracket next to the last trial's value. NaN when no
// bracket holds c.
double secant_value(const std::vector<std::pair<double, double>>& pts, double coef, double last_p) {
  double next = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t q = 0; q + 1 < pts.size(); ++q) {
    const auto [pa, fa] = pts[q];
    const auto [pb, fb] = pts[q + 1];
    if (fa == fb || (coef - fa) * (coef - fb) > 0.0) continue;
    next = pa + (coef - fa) / (fb - fa) * (pb - pa);
    if (pa == last_p || pb == last_p) break;
  }
  return next;
}

// The simulated response where the strength was fitted (plan.mu_at) in units of the fingerprint
// there, over the refit's channels, each over its noise.
double response_fraction(const LoopContext& ctx, const RefitPlan& plan, const Surface& surf,
                         const LoopState& state) {
  const Model alone{{{1.0, &surf}}};
  const double mu = plan.mu_at;
  double num = 0.0, den = 0.0;
  for (std::size_t i : ctx.roles.fitted)
    for (Channel c : plan.channels) {
      const double f = plan.column[c][i];
      const double change = alone.value(i, mu, c) - state.model.value(i, mu, c);
      if (!std::isfinite(f) || !std::isfinite(change)) continue;
      const double w =
          c == Channel::kAngle ? 1.0 : std::pow(ctx.sigma(i, Channel::kAngle) / ctx.sigma(i, c), 2);
      num += w * change * f;
      den += w * f * f;
    }
  return den > 0.0 ? num / den : 0.0;
}

// One trial at p, appended to refit.trials. The value may overshoot into piles the measurement
// cannot see (a smooth plate spreads a small sample into a monolayer) or into pours a
// calibration test's outlet jams: then it steps back halfway towards `toward` (off, or the best
// trial's value for a follow-up), twice at most; every value that failed is kept in
// refit.failed. A held-out test that jams at p does not stop the trial: the model predicts no
// pile for it. Returns false when no attempt could be simulated.
bool run_trial(const LoopContext& ctx, PileStore& store, const RefitPlan& plan, double p,
               double toward, const LoopState& state, Refit& refit) {
  const CandidateEffect& e = *plan.effect;
  const double off = plan.off;
  std::optional<Surface> surf;
  for (int attempt = 0; attempt < 3 && !surf; ++attempt) {
    std::vector<EffectSetting> with = state.effects;
    with.push_back({&e, p});
    try {
      surf = simulate_surface(ctx, store, with);
    } catch (const std::exception& ex) {
      refit.notes +=
          "at " + std::to_string(p) + ": " + std::string(ex.what()).substr(0, 300) + "; ";
      ctx.say("refit at " + std::to_string(p) + " failed; stepping back halfway");
      refit.failed.push_back(p);
      p = toward + 0.5 * (p - toward);
    }
  }
  if (!surf) return false;
  Trial tr;
  tr.p = p;
  tr.surf = &store.keep(std::move(*surf));
  for (std::size_t i = 0; i < ctx.tests().size(); ++i)
    if (!tr.surf->curve[i].no_pile.empty()) tr.no_pile.push_back(ctx.tests()[i].id);
  tr.fraction = response_fraction(ctx, plan, *tr.surf, state);
  // t may extrapolate beyond the simulated value, but never past the effect's range.
  const double t_max_setting = ctx.s().t_max;
  const double bound = (p < off ? e.lo : e.hi) - off;
  const double t_max =
      p != off ? std::min(t_max_setting, std::max(1.0, bound / (p - off))) : t_max_setting;
  tr.joint = fit_mu(ctx, state.model, tr.surf, t_max, ctx.roles.fitted, plan.channels);
  for (const auto& [w, sf] : state.model.terms)
    tr.model.terms.push_back({(1.0 - tr.joint.t) * w, sf});
  tr.model.terms.push_back({tr.joint.t, tr.surf});
  tr.rmse = calibration_rmse(ctx, tr.model, tr.joint.mu);
  refit.trials.push_back(tr);
  return true;
}

// Whether p is off, a value a trial has simulated already or one that failed to simulate.
bool tried_already(const Refit& refit, double off, double p) {
  const auto same = [p](double q) { return same_value(q, p); };
  if (same(off)) return true;
  for (const Trial& tr : refit.trials)
    if (same(tr.p)) return true;
  return std::any_of(refit.failed.begin(), refit.failed.end(), same);
}

}  // namespace

const Trial& best_trial(const Refit& refit) {
  std::size_t pick = 0;
  for (std::size_t q = 1; q < refit.trials.size(); ++q)
    if (refit.trials[q].rmse < refit.trials[pick].rmse) pick = q;
  return refit.trials[pick];
}

std::optional<double> follow_up_value(const Refit& refit, double off, double lo, double hi,
                                      double tolerance) {
  if (refit.trials.empty()) return std::nullopt;
  const Trial& best = best_trial(refit);
  if (std::abs(best.joint.t - 1.0) <= tolerance) return std::nullopt;
  const double next = std::clamp(off + best.joint.t * (best.p - off), lo, hi);
  if (tried_already(refit, off, next)) return std::nullopt;
  return next;
}

// Secant refinement (on the refit's channels: the angle, or every traced observable for a
// candidate admitted on the joint evidence). The linear estimate p1 assumes the response grows linearly from off to the
// probe; a threshold effect (a plate that starts to slide below some friction) breaks that. When
// the simulated response fraction misses the traced strength `coef` by more than half, the next
// value interpolates coef between the known responses (off: 0, probe: 1, and the trials), at
// most twice more.
Refit refit_by_simulation(const LoopContext& ctx, PileStore& store, const RefitPlan& plan,
                          const LoopState& state) {
  const CandidateEffect& e = *plan.effect;
  const double off = plan.off, coef = plan.coef;
  Refit refit;
  const int kMaxRefinements = 2;
  if (!run_trial(ctx, store, plan, plan.p1, off, state, refit)) return refit;
  for (int k = 0; k < kMaxRefinements; ++k) {
    const Trial& last = refit.trials.back();
    if (std::abs(last.fraction - coef) <= 0.5 * std::abs(coef)) break;
    std::vector<std::pair<double, double>> pts = {{off, 0.0}, {plan.fingerprint->probe, 1.0}};
    for (const Trial& tr : refit.trials) pts.push_back({tr.p, tr.fraction});
    std::sort(pts.begin(), pts.end());
    double next = secant_value(pts, coef, last.p);
    if (!std::isfinite(next)) break;
    next = std::clamp(next, e.lo, e.hi);
    const bool known = std::any_of(pts.begin(), pts.end(),
                                   [next](const auto& pf) { return same_value(pf.first, next); });
    if (known) break;
    ctx.say(e.name + ": simulated response " + std::to_string(last.fraction) +
            " of the probe's at " + std::to_string(last.p) + " (traced " + std::to_string(coef) +
            "); refining at " + std::to_string(next));
    if (!run_trial(ctx, store, plan, next, off, state, refit)) break;
  }
  // The value is read off the chord from off to the best trial, value = off + t (p - off). A
  // response that bends (a cohesion that saturates, an exponent whose effect grows faster than
  // linearly) puts a value read far along that chord off the truth: on the validation's rods a
  // trial at L/I 1.59 fitted t 1.76 and read L/I 2.04 for a hidden 2.6. So the refit simulates
  // where the fit lands, until the best trial's t is within kFollowTolerance of 1 (the value is
  // then a simulated one, not an extrapolation), refit_follow_ups times at most.
  const double kFollowTolerance = 0.1;
  for (int k = 0; k < ctx.s().refit_follow_ups; ++k) {
    const std::optional<double> next = follow_up_value(refit, off, e.lo, e.hi, kFollowTolerance);
    if (!next) break;
    const double best_p = best_trial(refit).p;  // the next trial may move refit.trials
    ctx.say(e.name + ": the fit lands at t " + std::to_string(best_trial(refit).joint.t) +
            " of the trial at " + std::to_string(best_p) + "; simulating where it lands, " +
            std::to_string(*next));
    if (!run_trial(ctx, store, plan, *next, best_p, state, refit)) break;
  }
  return refit;
}

// The simulated refit is the test of the linear tracing: when the joint fit puts the effect back
// at its off value (t = 0), or the simulated model does not lower the calibration error by more
// than the seed noise of a prediction, the simulations do not confirm it and it is not chosen.
// Returns the reason, or an empty string when confirmed.
std::string unconfirmed_reason(const LoopContext& ctx, const Trial& best, const LoopState& state) {
  const double rmse_now = calibration_rmse(ctx, state.model, state.fit.mu);
  const double margin = ctx.s().rule.loo_margin_factor * ctx.noise.se;
  if (best.joint.t <= 0.0)
    return "the joint refit of mu_r and the effect on simulated piles puts the effect at its "
           "off value (t = 0)";
  if (best.rmse > rmse_now - margin)
    return "the simulated refit lowers the calibration RMSE from " + std::to_string(rmse_now) +
           " to " + std::to_string(best.rmse) + " deg, not by more than the seed noise " +
           std::to_string(margin) + " deg";
  return "";
}

}  // namespace reposetwin::experiments::loop_detail
