// The fingerprints of the candidate effects (loop.hpp's design note): at the grid point nearest
// the calibrated mu_r, each available candidate switched on at its probe with the baseline's
// seeds, its probe scaled until the fingerprint stands out of the seed noise; then that probe at
// every other grid point, so the trace fits the candidate jointly with mu_r across the grid
// (loop_joint_surface.hpp).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "experiments/loop/loop_joint_surface.hpp"
#include "experiments/loop/loop_stages.hpp"

namespace reposetwin::experiments::loop_detail {

namespace {

// The registry's candidates (those named in the settings) that every test's scene can express.
std::vector<const CandidateEffect*> available_candidates(
    const LoopContext& ctx, std::vector<UnavailableCandidate>& unavailable) {
  std::vector<const CandidateEffect*> cands;
  for (const CandidateEffect& e : candidate_effects()) {
    if (!ctx.selected(e)) continue;
    std::string why;
    for (const LabTest& t : ctx.tests())
      if (why.empty()) {
        why = effect_unavailable(t, e);
        if (!why.empty()) why = "test " + t.id + ": " + why;
      }
    if (why.empty()) why = effect_unidentifiable(ctx.tests(), e);
    if (!why.empty()) {
      unavailable.push_back({e.name, why});
      ctx.say("candidate " + e.name + " unavailable: " + why);
      continue;
    }
    cands.push_back(&e);
  }
  return cands;
}

// Why a fingerprint cannot be traced (empty: it can), over the traced tests that have one.
std::string untraceable(const LoopContext& ctx, const FingerprintRecord& f) {
  std::vector<std::size_t> tests;
  for (std::size_t i : ctx.roles.traced)
    if (std::isfinite(f.change[Channel::kAngle][i])) tests.push_back(i);
  // An effect that moves the angle by less than the seed noise of a predicted angle at its
  // probe cannot be traced: any residual would need an absurd strength (a lens whose
  // distortion shifts the angle by 0.01 deg "explains" 5 deg with k1 = 100).
  double ms = 0.0;
  const std::vector<double>& angle = f.change[Channel::kAngle];
  for (std::size_t i : tests) ms += angle[i] * angle[i];
  const double rms = std::sqrt(ms / static_cast<double>(tests.size()));
  char why[240];
  if (rms < ctx.noise.se) {
    std::snprintf(why, sizeof why,
                  "its fingerprint at the probe (RMS %.3g deg over the traced tests) "
                  "is below the seed noise of a predicted angle (%.3g deg)",
                  rms, ctx.noise.se);
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
  const double chi2_95_per_n = chi2_95(n) / n;
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


// The mean paired change of every test's angle, H and D, from `on` (test-major, seeds in the
// baseline's order) against the baseline's piles at the grid point; NaN for a test the baseline
// predicts no pile for (not poured, not traced).
FingerprintRecord fingerprint(const LoopContext& ctx, const CandidateEffect& e, double probe,
                              const Surface& base, std::size_t node,
                              const std::vector<SimOutcome>& on) {
  FingerprintRecord f;
  f.name = e.name;
  f.probe = probe;
  f.mu_r = ctx.grid[node];
  // The crest is recorded only where the lab measured one, so a dataset without one keeps its
  // record.
  std::vector<Channel> recorded = {Channel::kAngle, Channel::kH, Channel::kD};
  if (ctx.noise.crest_measured) recorded.push_back(Channel::kCrest);
  std::size_t q = 0;
  for (std::size_t i = 0; i < ctx.tests().size(); ++i) {
    if (!base.curve[i].no_pile.empty()) {
      const double nan = std::numeric_limits<double>::quiet_NaN();
      for (Channel c : recorded) f.change[c].push_back(nan);
      f.angle_se_deg.push_back(nan);
      continue;
    }
    PerChannel<std::vector<double>> delta;  // per seed
    for (std::size_t r = 0; r < ctx.s().seeds.size(); ++r, ++q) {
      const SimOutcome& off = base.raw[i][node][r];
      for (Channel c : kAllChannels)
        delta[c].push_back(ctx.twin_value(on[q], c) - ctx.twin_value(off, c));
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

// The effect at `probe` poured at grid point k, paired with the baseline's piles there. Each pair
// starts from the seed of the baseline pile it is compared with (a repeated pour's seed if the
// first one jammed), so a measurement effect re-photographs that pile. A held-out test the twin
// predicts no pile for has none. Throws when a run forms no pile.
std::vector<SimOutcome> pour_probe(const LoopContext& ctx, PileStore& store,
                                   const CandidateEffect& e, const Surface& base, std::size_t k,
                                   double probe) {
  std::vector<SimRequest> req;
  for (std::size_t i = 0; i < ctx.tests().size(); ++i)
    if (base.curve[i].no_pile.empty())
      for (const SimOutcome& o : base.raw[i][k])
        req.push_back(make_request(ctx.tests()[i], ctx.s().mu_key, ctx.grid[k], o.seed,
                                   {{&e, probe}}, ctx.s().image));
  std::vector<SimOutcome> got = pour(ctx, store, req);
  for (const SimOutcome& o : got)
    if (!o.pile)
      throw std::runtime_error("a run formed no pile with the effect at " + std::to_string(probe));
  return got;
}

// One candidate's fingerprint, its probe doubled (away from the off value, inside the range)
// while the fingerprint does not stand out of the seed noise, probe_scalings times at most.
// One batch per probe, so that a candidate whose runs or photographs fail (a lens model that
// folds, a pile vision cannot find from that camera) is reported, not fatal.
std::optional<FingerprintRecord> probe_candidate(const LoopContext& ctx, PileStore& store,
                                                 const CandidateEffect& e, const Surface& base,
                                                 std::size_t node,
                                                 std::vector<UnavailableCandidate>& unavailable) {
  const LoopSettings& s = ctx.s();
  const double off = ctx.effect_off(e);
  std::vector<double> tried;
  std::string why;
  double probe = e.probe;
  for (int k = 0; k <= s.probe_scalings; ++k) {
    if (k > 0) {
      const double next = std::clamp(off + 2.0 * (probe - off), e.lo, e.hi);
      if (std::abs(next - probe) <= 1e-9 * std::max(1.0, std::abs(probe))) break;
      ctx.say("candidate " + e.name + ": " + why + "; probing at " + std::to_string(next));
      probe = next;
    }
    std::vector<SimOutcome> got;
    try {
      got = pour_probe(ctx, store, e, base, node, probe);
    } catch (const std::exception& ex) {
      const std::string failed = std::string("failed at probe ") + std::to_string(probe) + ": " +
                                 ex.what();
      unavailable.push_back({e.name, why.empty() ? failed : why + "; " + failed});
      ctx.say("candidate " + e.name + " " + failed);
      return std::nullopt;
    }
    tried.push_back(probe);
    FingerprintRecord f = fingerprint(ctx, e, probe, base, node, got);
    f.probes_tried = tried;
    why = untraceable(ctx, f);
    if (why.empty()) return f;
  }
  char largest[160];
  std::snprintf(largest, sizeof largest, " (largest probe tried %.4g %s, %d probe(s))",
                tried.back(), e.units.c_str(), static_cast<int>(tried.size()));
  unavailable.push_back({e.name, why + largest});
  ctx.say("candidate " + e.name + " not traceable: " + why + largest);
  return std::nullopt;
}

// The candidate's probe at every grid point, each paired with the baseline's piles there; the
// node the probe was chosen at is `f` itself. A grid point whose pours fail keeps the reason and
// no change: the trace interpolates across it (interpolate_on_nodes).
void fingerprint_surface(const LoopContext& ctx, PileStore& store, const CandidateEffect& e,
                         const Surface& base, std::size_t node, FingerprintRecord& f) {
  for (std::size_t k = 0; k < ctx.grid.size(); ++k) {
    FingerprintNode n;
    n.mu_r = ctx.grid[k];
    if (k == node) {
      n.change = f.change;
      f.surface.push_back(std::move(n));
      continue;
    }
    try {
      const std::vector<SimOutcome> got = pour_probe(ctx, store, e, base, k, f.probe);
      n.change = fingerprint(ctx, e, f.probe, base, k, got).change;
    } catch (const std::exception& ex) {
      n.missing = std::string(ex.what()).substr(0, 300);
      ctx.say("candidate " + e.name + ": no fingerprint at mu_r = " + std::to_string(n.mu_r) +
              ": " + n.missing);
    }
    f.surface.push_back(std::move(n));
  }
}

}  // namespace

// Fingerprints at the grid point nearest the calibrated mu_r, with the baseline's seeds, and
// their probes at every grid point.
Fingerprints fingerprint_candidates(const LoopContext& ctx, PileStore& store, const Surface& base,
                                    std::size_t node) {
  Fingerprints fps;
  const std::vector<const CandidateEffect*> cands = available_candidates(ctx, fps.unavailable);
  ctx.say("fingerprints: " + std::to_string(cands.size()) +
          " candidates at mu_r = " + std::to_string(ctx.grid[node]) + ", then across the grid");
  for (const CandidateEffect* e : cands)
    if (auto f = probe_candidate(ctx, store, *e, base, node, fps.unavailable)) {
      fingerprint_surface(ctx, store, *e, base, node, *f);
      fps.records.push_back(std::move(*f));
    }
  return fps;
}

double fingerprint_at(const FingerprintRecord& f, Channel c, std::size_t test, double mu) {
  if (f.surface.empty()) return f.change[c].at(test);
  std::vector<double> nodes, values;
  for (const FingerprintNode& n : f.surface) {
    nodes.push_back(n.mu_r);
    values.push_back(n.missing.empty() && test < n.change[c].size()
                         ? n.change[c][test]
                         : std::numeric_limits<double>::quiet_NaN());
  }
  return interpolate_on_nodes(nodes, values, mu);
}

}  // namespace reposetwin::experiments::loop_detail
