// The loop's stages from the calibrated baseline to the tracing (loop.hpp's design note): the
// mu_r grid settled so that mu_r does not sit on its bound, the candidates' fingerprints with
// their probes scaled until they stand out of the seed noise, and the residual of every test
// traced on the angle and jointly on every measured observable (loop_decision.hpp).
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "experiments/io/format.hpp"
#include "experiments/loop/loop_stages.hpp"

namespace reposetwin::experiments::loop_detail {
std::size_t Loop::nearest_grid_point(double mu) const {
  std::size_t node = 0;
  for (std::size_t j = 1; j < grid_.size(); ++j)
    if (std::abs(grid_[j] - mu) < std::abs(grid_[node] - mu)) node = j;
  return node;
}

// Whether the settings trace `e`: named in them, or, when they name none, not opt-in.
bool Loop::selected(const CandidateEffect& e) const {
  if (s_.candidates.empty()) return !e.opt_in;
  return std::find(s_.candidates.begin(), s_.candidates.end(), e.name) != s_.candidates.end();
}

// The registry's candidates (those named in the settings) that every test's scene can express.
std::vector<const CandidateEffect*> Loop::available_candidates(
    std::vector<UnavailableCandidate>& unavailable) {
  std::vector<const CandidateEffect*> cands;
  for (const CandidateEffect& e : candidate_effects()) {
    if (!selected(e)) continue;
    std::string why;
    for (const LabTest& t : data_.tests)
      if (why.empty()) {
        why = effect_unavailable(t, e);
        if (!why.empty()) why = "test " + t.id + ": " + why;
      }
    if (why.empty()) why = effect_unidentifiable(data_.tests, e);
    if (!why.empty()) {
      unavailable.push_back({e.name, why});
      say("candidate " + e.name + " unavailable: " + why);
      continue;
    }
    cands.push_back(&e);
  }
  return cands;
}

// mu_r on an end of its grid cannot take up what it should, and the tracing would hand the rest
// to the effects (an unbounded mu_r correction is no answer: beyond the grid a constant offset is
// not a mu_r change). So the grid grows by one point beyond that end, the spacing of its last
// step, at most grid_extensions times (never below 0 nor above mu_max); the baseline is
// simulated there (the other points come from the cache) and mu_r calibrated again.
GridRecord Loop::settle_grid(const Surface*& base, BaselineRecord& baseline) {
  GridRecord g;
  g.initial = grid_;
  g.policy = grid_bound_name(s_.at_bound);
  const int allowed = s_.at_bound == GridBound::kExtend ? s_.grid_extensions : 0;
  const MuPrior& prior = s_.mu_prior;
  const double floor = prior.declared() ? prior.lo : 0.0;
  const double ceiling = prior.declared() ? std::min(prior.hi, s_.mu_max) : s_.mu_max;
  const auto at_prior = [&](bool low) {
    return prior.declared() && (low ? grid_.front() <= prior.lo + 1e-12
                                    : grid_.back() >= prior.hi - 1e-12);
  };
  std::string limit;
  while (baseline.fit.at_edge && static_cast<int>(g.added.size()) < allowed) {
    const bool low = baseline.fit.mu <= grid_.front() + 1e-12;
    double next = low ? grid_.front() - (grid_[1] - grid_[0])
                      : grid_.back() + (grid_.back() - grid_[grid_.size() - 2]);
    next = low ? std::max(floor, next) : std::min(ceiling, next);
    if ((low && grid_.front() <= floor) || (!low && grid_.back() >= ceiling)) {
      limit = at_prior(low) ? "the declared range's end"
              : low         ? "mu_r cannot go below 0"
                            : "mu_max " + significant(s_.mu_max, 3) + " reached";
      break;
    }
    say("mu_r " + std::to_string(baseline.fit.mu) + " on the grid's " + (low ? "low" : "high") +
        " end: adding mu_r = " + std::to_string(next));
    grid_.insert(low ? grid_.begin() : grid_.end(), next);
    g.added.push_back(next);
    surfaces_.push_back(std::make_unique<Surface>(simulate_surface({})));
    base = surfaces_.back().get();
    set_seed_noise(*base);
    baseline = calibrate_baseline(*base);
  }
  g.final_grid = grid_;
  g.at_bound = baseline.fit.at_edge;
  if (prior.declared()) {
    g.prior = std::make_pair(prior.lo, prior.hi);
    g.prior_reason = prior.reason;
    g.beyond_prior = g.at_bound && at_prior(baseline.fit.mu <= grid_.front() + 1e-12);
  }
  std::string added;
  for (double a : g.added) added += (added.empty() ? "" : ", ") + significant(a, 3);
  const std::string mu = significant(baseline.fit.mu, 3);
  if (!g.at_bound)
    g.statement = g.added.empty() ? "mu_r " + mu + " lies inside the grid"
                                  : "mu_r " + mu + " lies inside the grid extended by " + added;
  else if (g.beyond_prior)
    g.statement = "mu_r alone needs a value beyond its declared range " +
                  significant(prior.lo, 3) + "-" + significant(prior.hi, 3) + " (" +
                  prior.reason + ") to fit the data: it sits at " + mu +
                  (g.added.empty() ? std::string() : " after adding " + added) +
                  ". That is evidence for an effect mu_r lacks, so the candidates are traced "
                  "and refitted jointly with mu_r held inside that range";
  else
    g.statement = "mu_r " + mu + " sits on the grid's bound" +
                  (g.added.empty() ? std::string() : " after adding " + added) +
                  (limit.empty() ? "" : " (" + limit + ")") +
                  (s_.at_bound == GridBound::kTrace
                       ? "; traced with the mu_r correction held inside the grid (--at-bound "
                         "trace): what mu_r cannot take up is left to the candidates"
                       : "; nothing is traced: what mu_r cannot take up would be handed to the "
                         "effects (a wider --mu-grid, more --grid-extensions, or --at-bound "
                         "trace to trace anyway)");
  return g;
}

// Fingerprints at the grid point nearest the calibrated mu_r, with the baseline's seeds.
std::vector<FingerprintRecord> Loop::fingerprint_candidates(
    const Surface& base, std::size_t node, std::vector<UnavailableCandidate>& unavailable) {
  const std::vector<const CandidateEffect*> cands = available_candidates(unavailable);
  say("fingerprints: " + std::to_string(cands.size()) +
      " candidates at mu_r = " + std::to_string(grid_[node]));
  std::vector<FingerprintRecord> fps;
  for (const CandidateEffect* e : cands)
    if (auto f = probe_candidate(*e, base, node, unavailable)) fps.push_back(std::move(*f));
  return fps;
}

// One candidate's fingerprint, its probe doubled (away from the off value, inside the range)
// while the fingerprint does not stand out of the seed noise, probe_scalings times at most.
// One batch per probe, so that a candidate whose runs or photographs fail (a lens model that
// folds, a pile vision cannot find from that camera) is reported, not fatal.
std::optional<FingerprintRecord> Loop::probe_candidate(
    const CandidateEffect& e, const Surface& base, std::size_t node,
    std::vector<UnavailableCandidate>& unavailable) {
  const double off = effect_off(e);
  std::vector<double> tried;
  std::string why;
  double probe = e.probe;
  for (int k = 0; k <= s_.probe_scalings; ++k) {
    if (k > 0) {
      const double next = std::clamp(off + 2.0 * (probe - off), e.lo, e.hi);
      if (std::abs(next - probe) <= 1e-9 * std::max(1.0, std::abs(probe))) break;
      say("candidate " + e.name + ": " + why + "; probing at " + std::to_string(next));
      probe = next;
    }
    // Each pair starts from the seed of the baseline pile it is compared with (a repeated
    // pour's seed if the first one jammed), so a measurement effect re-photographs that pile.
    std::vector<SimRequest> req;
    for (std::size_t i = 0; i < data_.tests.size(); ++i)
      if (base.curve[i].no_pile.empty())  // a held-out test the twin predicts no pile for
        for (const SimOutcome& o : base.raw[i][node])
          req.push_back(make_request(data_.tests[i], s_.mu_key, grid_[node], o.seed,
                                     {{&e, probe}}, s_.image));
    std::vector<SimOutcome> got;
    try {
      got = pour(req);
      for (const SimOutcome& o : got)
        if (!o.pile) throw std::runtime_error("a run formed no pile with the effect at " +
                                              std::to_string(probe));
    } catch (const std::exception& ex) {
      const std::string failed = std::string("failed at probe ") + std::to_string(probe) + ": " +
                                 ex.what();
      unavailable.push_back({e.name, why.empty() ? failed : why + "; " + failed});
      say("candidate " + e.name + " " + failed);
      return std::nullopt;
    }
    tried.push_back(probe);
    FingerprintRecord f = fingerprint(e, probe, base, node, got);
    f.probes_tried = tried;
    why = untraceable(f);
    if (why.empty()) return f;
  }
  char largest[160];
  std::snprintf(largest, sizeof largest, " (largest probe tried %.4g %s, %d probe(s))",
                tried.back(), e.units.c_str(), static_cast<int>(tried.size()));
  unavailable.push_back({e.name, why + largest});
  say("candidate " + e.name + " not traceable: " + why + largest);
  return std::nullopt;
}

// The mean paired change of every test's angle, H and D, from `on` (test-major, seeds in the
// baseline's order) against the baseline's piles at the grid point; NaN for a test the baseline
// predicts no pile for (not poured, not traced).
FingerprintRecord Loop::fingerprint(const CandidateEffect& e, double probe, const Surface& base,
                                    std::size_t node, const std::vector<SimOutcome>& on) const {
  FingerprintRecord f;
  f.name = e.name;
  f.probe = probe;
  f.mu_r = grid_[node];
  // The crest is recorded only where the lab measured one, so a dataset without one keeps its
  // record.
  std::vector<Channel> recorded = {Channel::kAngle, Channel::kH, Channel::kD};
  if (crest_measured_) recorded.push_back(Channel::kCrest);
  std::size_t q = 0;
  for (std::size_t i = 0; i < data_.tests.size(); ++i) {
    if (!base.curve[i].no_pile.empty()) {
      const double nan = std::numeric_limits<double>::quiet_NaN();
      for (Channel c : recorded) f.change[c].push_back(nan);
      f.angle_se_deg.push_back(nan);
      continue;
    }
    PerChannel<std::vector<double>> delta;  // per seed
    for (std::size_t r = 0; r < s_.seeds.size(); ++r, ++q) {
      const SimOutcome& off = base.raw[i][node][r];
      for (Channel c : kAllChannels) delta[c].push_back(twin_value(on[q], c) - twin_value(off, c));
    }
    for (Channel c : recorded) f.change[c].push_back(sample_stats(delta[c]).mean);
    const std::vector<double>& da = delta[Channel::kAngle];
    const double mean_da = f.change[Channel::kAngle].back();
    double v = 0.0;
    for (double x : da) v += (x - mean_da) * (x - mean_da);
    f.angle_se_deg.push_back(std::sqrt(v / (da.size() - 1) / da.size()));
  }
  return f;
}

// Why a fingerprint cannot be traced (empty: it can), over the traced tests that have one.
std::string Loop::untraceable(const FingerprintRecord& f) const {
  std::vector<std::size_t> tests;
  for (std::size_t i : trace_)
    if (std::isfinite(f.change[Channel::kAngle][i])) tests.push_back(i);
  // An effect that moves the angle by less than the seed noise of a predicted angle at its
  // probe cannot be traced: any residual would need an absurd strength (a lens whose
  // distortion shifts the angle by 0.01 deg "explains" 5 deg with k1 = 100).
  double ms = 0.0;
  const std::vector<double>& angle = f.change[Channel::kAngle];
  for (std::size_t i : tests) ms += angle[i] * angle[i];
  const double rms = std::sqrt(ms / static_cast<double>(tests.size()));
  char why[240];
  if (rms < seed_se_) {
    std::snprintf(why, sizeof why,
                  "its fingerprint at the probe (RMS %.3g deg over the traced tests) "
                  "is below the seed noise of a predicted angle (%.3g deg)",
                  rms, seed_se_);
    return why;
  }
  // Nor can an effect whose fingerprint does not stand out of its own seed noise. A
  // fingerprint is a mean of paired differences whose noise (about sd sqrt(2 / seeds) for a
  // physical effect, which re-draws the piles) is larger than the seed noise above, so a pure
  // noise column passes the first test. Under "no effect", n RMS^2 / se^2 (se^2 the mean
  // squared standard error of the per-test means, n traced tests) is about chi^2(n); the
  // fingerprint must exceed its 95% point (Wilson-Hilferty).
  double se2 = 0.0;
  for (std::size_t i : tests) se2 += f.angle_se_deg[i] * f.angle_se_deg[i];
  const double n = static_cast<double>(tests.size());
  se2 /= n;
  const double a = 2.0 / (9.0 * n);
  const double chi2_95_per_n = std::pow(1.0 - a + 1.645 * std::sqrt(a), 3);
  if (rms * rms < chi2_95_per_n * se2) {
    std::snprintf(why, sizeof why,
                  "its fingerprint at the probe (RMS %.3g deg over the traced tests) "
                  "does not stand out of its own seed noise (standard error %.3g deg per "
                  "test; 95%% point %.3g deg)",
                  rms, std::sqrt(se2), std::sqrt(chi2_95_per_n * se2));
    return why;
  }
  return "";
}

// The slope of the current model's value of a channel against mu_r at the fit, over a tenth of
// the grid span (the monotone fit is piecewise linear).
double Loop::mu_slope(const LoopState& state, std::size_t i, Channel channel) const {
  const double span = grid_.back() - grid_.front();
  const double a = std::max(grid_.front(), state.fit.mu - 0.05 * span);
  const double b = std::min(grid_.back(), state.fit.mu + 0.05 * span);
  return (state.model.value(i, b, channel) - state.model.value(i, a, channel)) / (b - a);
}

// The traced tests the model predicts a pile for. A held-out test whose twin pours jammed has
// no residual to trace (its "no pile" is reported with the residuals); it is named in left_out.
std::vector<std::size_t> Loop::traced(const Model& model, std::vector<std::string>& left_out) const {
  std::vector<std::size_t> tests;
  for (std::size_t i : trace_) {
    const std::string why = model.no_pile(i);
    if (why.empty())
      tests.push_back(i);
    else
      left_out.push_back(data_.tests[i].id + ": " + why);
  }
  return tests;
}

// The observables traced jointly over `tests`: the angle always; H and D when every traced test
// has them measured; the crest width when the lab data give it on every traced test (absent
// from every test: the problem is the one without it).
JointProblem Loop::joint_problem(const LoopState& state, const std::vector<std::size_t>& tests,
                                 std::vector<std::string>& left_out) const {
  JointProblem p;
  p.mu_shift_lo = grid_.front() - state.fit.mu;
  p.mu_shift_hi = grid_.back() - state.fit.mu;
  const Eigen::Index n = static_cast<Eigen::Index>(tests.size());
  bool hd = true;
  for (std::size_t i : tests)
    hd = hd && data_.tests[i].height_mm.has_value() && data_.tests[i].diameter_mm.has_value();
  if (!hd) left_out.push_back("H and D: not measured on every test");
  std::vector<Channel> always = {Channel::kAngle};
  if (hd) always.insert(always.end(), {Channel::kH, Channel::kD});
  const double mu = state.fit.mu;
  for (Channel c : always) {
    TraceChannel ch{channel_name(c), channel_unit(c), Eigen::VectorXd(n), Eigen::VectorXd(n),
                    Eigen::VectorXd(n)};
    for (Eigen::Index k = 0; k < n; ++k) {
      const std::size_t i = tests[k];
      ch.residual[k] = observed(i, c) - state.model.value(i, mu, c);
      ch.sigma[k] = noise(i, c);
      ch.mu_sensitivity[k] = mu_slope(state, i, c);
    }
    // A flat mu_r response (all slopes ~0) still leaves mu_r free as a constant shift.
    if (c == Channel::kAngle && ch.mu_sensitivity.cwiseAbs().maxCoeff() < 1e-6)
      ch.mu_sensitivity.setOnes();
    p.channels.push_back(std::move(ch));
  }
  if (!crest_measured_) return p;
  const Channel cr = Channel::kCrest;
  OptionalChannel crest{{channel_name(cr), channel_unit(cr), Eigen::VectorXd(n),
                         Eigen::VectorXd(n), Eigen::VectorXd(n)},
                        std::vector<bool>(static_cast<std::size_t>(n))};
  for (Eigen::Index k = 0; k < n; ++k) {
    const std::size_t i = tests[k];
    const bool measured = data_.tests[i].crest_mm.has_value();
    crest.measured[static_cast<std::size_t>(k)] = measured;
    crest.channel.residual[k] = measured ? observed(i, cr) - state.model.value(i, mu, cr) : 0.0;
    crest.channel.sigma[k] = noise(i, cr);
    crest.channel.mu_sensitivity[k] = mu_slope(state, i, cr);
  }
  add_optional_channel(p, crest, left_out);
  return p;
}

// The residual of the current model regressed on every unused fingerprint: on the angle (the
// acceptance rule) and jointly on every measured observable (the decision), over every test.
IterationRecord Loop::trace(int it, const LoopState& state,
                            const std::vector<FingerprintRecord>& fps) const {
  IterationRecord rec;
  rec.iteration = it;
  rec.mu_r = state.fit.mu;
  std::vector<std::size_t> tests;
  // A test the baseline formed no pile for has no fingerprint either (a refit of weight 1 can
  // give it a prediction while the baseline gives none).
  for (std::size_t i : traced(state.model, rec.tests_left_out)) {
    bool fingerprinted = true;
    for (const FingerprintRecord& f : fps)
      fingerprinted = fingerprinted &&
                      (state.used.count(f.name) || std::isfinite(f.change[Channel::kAngle][i]));
    if (fingerprinted)
      tests.push_back(i);
    else
      rec.tests_left_out.push_back(data_.tests[i].id +
                                   ": no fingerprint (the baseline formed no pile for it)");
  }
  // The design's own bound (describe_design): fewer tests than that leave nothing to judge a
  // candidate by; the iteration then says so and traces nothing.
  if (tests.size() < 4) {
    rec.decision.statement = "nothing traced: " + std::to_string(tests.size()) +
                             " test(s) have a prediction (the twin forms no pile for the "
                             "others); a leave-one-out check of a mu_r correction and one effect "
                             "needs at least 4";
    return rec;
  }
  JointProblem joint = joint_problem(state, tests, rec.channels_left_out);
  // A crest fingerprint from photographs cached before the crest was recorded has no value: the
  // channel then leaves this trace rather than carry NaN into every score.
  if (joint.channels.back().name == channel_name(Channel::kCrest))
    for (const FingerprintRecord& f : fps) {
      if (state.used.count(f.name)) continue;
      const std::vector<double>& crest = f.change[Channel::kCrest];
      bool finite = crest.size() == data_.tests.size();
      for (std::size_t i : tests) finite = finite && std::isfinite(crest[i]);
      if (finite) continue;
      joint.channels.pop_back();
      rec.channels_left_out.push_back("crest: the photographs of " + f.name +
                                      "'s fingerprint do not record it");
      break;
    }
  for (const TraceChannel& ch : joint.channels) rec.channels.push_back(ch.name);
  TraceProblem p;
  p.residual = joint.channels[0].residual;
  p.sigma = joint.channels[0].sigma;
  p.mu_sensitivity = joint.channels[0].mu_sensitivity;
  p.seed_noise_deg = seed_se_;
  p.mu_shift_lo = joint.mu_shift_lo;
  p.mu_shift_hi = joint.mu_shift_hi;
  rec.null = score_null(p);
  const Eigen::Index n = p.residual.size();
  for (const FingerprintRecord& f : fps) {
    if (state.used.count(f.name)) continue;
    std::vector<Eigen::VectorXd> cols;
    for (const TraceChannel& ch : joint.channels) {
      const std::vector<double>& v = f.change[channel_from_name(ch.name)];
      Eigen::VectorXd col(n);
      for (Eigen::Index k = 0; k < n; ++k) col[k] = v[tests[k]];
      cols.push_back(col);
    }
    rec.candidates.push_back(score_candidate(p, f.name, cols[0], rec.null, s_.rule));
    rec.joint.push_back(score_joint(joint, f.name, cols));
    // The strength each fit asks for, against what the effect can do.
    const CandidateEffect& e = find_effect(f.name);
    const double off = effect_off(e);
    CandidateScore& a = rec.candidates.back();
    JointScore& j = rec.joint.back();
    a.out_of_range = outside_range(a.coef, a.coef_se, off, f.probe, e.lo, e.hi, e.units);
    if (j.identifiable)
      j.out_of_range = outside_range(j.coef, j.coef_se, off, f.probe, e.lo, e.hi, e.units);
  }
  rec.offset = score_offset(joint);
  rec.mu_only = score_joint(joint, "mu_r only", {});
  return rec;
}

}  // namespace reposetwin::experiments::loop_detail
