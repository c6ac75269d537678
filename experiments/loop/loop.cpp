#include "experiments/loop/loop.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <set>

#include "experiments/calibration/calibration.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/io/input_error.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// One test's simulated response on the mu_r grid (one model setting).
struct Curve {
  std::vector<double> mu;                        // grid [-]
  MonotoneFit fit;                               // angle against mu_r
  std::vector<double> h, d, angle;               // seed means per grid point [mm, mm, deg]
  std::vector<std::vector<double>> angle_seeds;  // per grid point, per seed [deg]
  std::vector<std::vector<double>> h_seeds, d_seeds;
  std::vector<int> clogged;                      // per grid point: pours that formed no pile

  double clamp(double m) const { return std::clamp(m, mu.front(), mu.back()); }
  double at(double m) const { return evaluate(fit, clamp(m)); }
  double lin(const std::vector<double>& y, double m) const {
    m = clamp(m);
    std::size_t k = 0;
    while (k + 2 < mu.size() && m > mu[k + 1]) ++k;
    const double s = (m - mu[k]) / (mu[k + 1] - mu[k]);
    return y[k] + s * (y[k + 1] - y[k]);
  }
};

// The twin for every test at one setting of the effects: curves on the mu_r grid.
struct Surface {
  std::vector<EffectSetting> effects;
  std::vector<Curve> curve;                               // per test
  std::vector<std::vector<std::vector<SimOutcome>>> raw;  // [test][grid][seed]
};

// The current model: a mixture of simulated surfaces (see the design note).
struct Model {
  std::vector<std::pair<double, const Surface*>> terms;
  double angle(std::size_t i, double m) const {
    double s = 0.0;
    for (const auto& [w, surf] : terms) s += w * surf->curve[i].at(m);
    return s;
  }
  double h(std::size_t i, double m) const {
    double s = 0.0;
    for (const auto& [w, surf] : terms) s += w * surf->curve[i].lin(surf->curve[i].h, m);
    return s;
  }
  double d(std::size_t i, double m) const {
    double s = 0.0;
    for (const auto& [w, surf] : terms) s += w * surf->curve[i].lin(surf->curve[i].d, m);
    return s;
  }
};

double mean(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return v.empty() ? 0.0 : s / static_cast<double>(v.size());
}

double rmse(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x * x;
  return v.empty() ? 0.0 : std::sqrt(s / static_cast<double>(v.size()));
}

class Loop {
 public:
  Loop(const LabData& data, const std::string& out, const LoopSettings& s)
      : data_(data),
        out_(out),
        s_(s),
        cache_(s.cache_dir.empty() ? (fs::path(out) / "cache").string() : s.cache_dir,
               {s.workers, s.progress}) {}

  json run();

 private:
  void say(const std::string& m) const {
    if (s_.progress) std::cerr << "[loop] " << m << std::endl;
  }
  // The cache's runs, a pour that formed no pile repeated with a new seed (s_.max_pours).
  std::vector<SimOutcome> pour(const std::vector<SimRequest>& req) {
    return run_repouring(req, s_.max_pours,
                         [this](const std::vector<SimRequest>& r) { return cache_.run(r); });
  }
  Surface simulate_surface(const std::vector<EffectSetting>& effects);
  struct MuFit {
    double mu = 0.0, mu_se = 0.0, t = 0.0, t_se = 0.0;
    bool at_edge = false;
  };
  MuFit fit_mu(const Model& model, const Surface* extra) const;
  std::vector<double> sigmas() const;
  json residual_table(const Model& model, double mu) const;

  const LabData& data_;
  std::string out_;
  LoopSettings s_;
  SimCache cache_;
  std::vector<std::size_t> cal_, val_;  // test indices by role
  double noise_sd_ = 0.0;               // pooled seed spread of one pile's angle [deg]
  std::vector<std::unique_ptr<Surface>> surfaces_;
};

Surface Loop::simulate_surface(const std::vector<EffectSetting>& effects) {
  const std::size_t n = data_.tests.size(), g = s_.mu_grid.size(), k = s_.seeds.size();
  std::vector<SimRequest> req;
  for (std::size_t i = 0; i < n; ++i)
    for (double m : s_.mu_grid)
      for (std::uint64_t seed : s_.seeds)
        req.push_back(make_request(data_.tests[i], s_.mu_key, m, seed, effects, s_.image));
  const std::vector<SimOutcome> out = pour(req);
  Surface surf;
  surf.effects = effects;
  surf.curve.resize(n);
  surf.raw.assign(n, std::vector<std::vector<SimOutcome>>(g));
  std::size_t q = 0;
  for (std::size_t i = 0; i < n; ++i) {
    Curve& c = surf.curve[i];
    c.mu = s_.mu_grid;
    std::vector<Observation> obs;
    for (std::size_t j = 0; j < g; ++j) {
      std::vector<double> a, h, d;
      int clogged = 0;
      for (std::size_t r = 0; r < k; ++r, ++q) {
        const SimOutcome& o = out[q];
        // A run that formed no pile (clogged) has no angle; averaging its 0 into the curve would
        // be silent garbage. A jammed pour is repeated with a new seed (pour()); one still
        // without a pile after max_pours pours is left to the caller (the baseline stops, a
        // refit trial steps back).
        if (!o.pile)
          throw std::runtime_error("test " + data_.tests[i].id + " formed no pile at mu_r " +
                                   std::to_string(s_.mu_grid[j]) + ", seed " +
                                   std::to_string(s_.seeds[r]) + ", in " +
                                   std::to_string(s_.max_pours) + " pour(s) (last: " +
                                   o.sim_dir +
                                   (o.no_pile.empty() ? "" : "; its photographs: " + o.no_pile) +
                                   "): the loop needs a pile at every grid point");
        clogged += o.clogged_pours;
        surf.raw[i][j].push_back(o);
        const double angle = twin_angle(o, s_.angle);
        a.push_back(angle);
        h.push_back(o.height_mm);
        d.push_back(o.diameter_mm);
        obs.push_back({s_.mu_grid[j], o.seed, std::clamp(angle, 0.0, 90.0)});
      }
      c.angle.push_back(mean(a));
      c.h.push_back(mean(h));
      c.d.push_back(mean(d));
      c.angle_seeds.push_back(a);
      c.h_seeds.push_back(h);
      c.d_seeds.push_back(d);
      c.clogged.push_back(clogged);
    }
    c.fit = fit_monotone(obs);
  }
  return surf;
}

std::vector<double> Loop::sigmas() const {
  std::vector<double> sig;
  const double se_pred2 = noise_sd_ * noise_sd_ / static_cast<double>(s_.seeds.size());
  for (const LabTest& t : data_.tests)
    sig.push_back(std::sqrt(noise_sd_ * noise_sd_ / t.repeats + se_pred2));
  return sig;
}

Loop::MuFit Loop::fit_mu(const Model& model, const Surface* extra) const {
  const std::vector<double> sig = sigmas();
  const double lo = s_.mu_grid.front(), hi = s_.mu_grid.back();
  const int steps = 2000;
  MuFit best;
  double best_sse = 1e300;
  for (int q = 0; q <= steps; ++q) {
    const double m = lo + (hi - lo) * q / steps;
    double swdy = 0.0, swdd = 0.0;
    std::vector<double> y, dd, w;
    for (std::size_t i : cal_) {
      const double base = model.angle(i, m);
      const double di = extra ? extra->curve[i].at(m) - base : 0.0;
      y.push_back(data_.tests[i].angle_deg - base);
      dd.push_back(di);
      w.push_back(1.0 / (sig[i] * sig[i]));
      swdy += w.back() * di * y.back();
      swdd += w.back() * di * di;
    }
    const double t = (extra && swdd > 0.0) ? std::clamp(swdy / swdd, 0.0, s_.t_max) : 0.0;
    double sse = 0.0;
    for (std::size_t k = 0; k < y.size(); ++k) sse += w[k] * std::pow(y[k] - t * dd[k], 2);
    if (sse < best_sse) {
      best_sse = sse;
      best.mu = m;
      best.t = t;
    }
  }
  best.at_edge = best.mu <= lo + 1e-12 || best.mu >= hi - 1e-12;
  // Standard errors from the Jacobian of the prediction in (mu, t).
  const double h = (hi - lo) / 100.0;
  Eigen::MatrixXd jac(cal_.size(), extra ? 2 : 1);
  for (std::size_t k = 0; k < cal_.size(); ++k) {
    const std::size_t i = cal_[k];
    auto pred = [&](double m) {
      const double base = model.angle(i, m);
      return extra ? base + best.t * (extra->curve[i].at(m) - base) : base;
    };
    const double a = std::max(lo, best.mu - h), b = std::min(hi, best.mu + h);
    jac(k, 0) = (pred(b) - pred(a)) / (b - a) / sig[i];
    if (extra) jac(k, 1) = (extra->curve[i].at(best.mu) - model.angle(i, best.mu)) / sig[i];
  }
  const Eigen::MatrixXd info = jac.transpose() * jac;
  Eigen::FullPivLU<Eigen::MatrixXd> lu(info);
  if (lu.isInvertible()) {
    const Eigen::MatrixXd cov = lu.inverse();
    best.mu_se = std::sqrt(std::max(0.0, cov(0, 0)));
    if (extra) best.t_se = std::sqrt(std::max(0.0, cov(1, 1)));
  } else {
    best.mu_se = std::numeric_limits<double>::infinity();
    best.t_se = std::numeric_limits<double>::infinity();
  }
  return best;
}

json Loop::residual_table(const Model& model, double m) const {
  const std::vector<double> sig = sigmas();
  json rows = json::array();
  for (std::size_t i = 0; i < data_.tests.size(); ++i) {
    const LabTest& t = data_.tests[i];
    const double pred = model.angle(i, m);
    json r = {{"id", t.id},
              {"role", t.role},
              {"measured_deg", t.angle_deg},
              {"predicted_deg", pred},
              {"residual_deg", t.angle_deg - pred},
              {"sigma_deg", sig[i]},
              {"predicted_se_deg", noise_sd_ / std::sqrt(double(s_.seeds.size()))},
              {"predicted_H_mm", model.h(i, m)},
              {"predicted_D_mm", model.d(i, m)}};
    if (t.height_mm) r["residual_H_mm"] = *t.height_mm - model.h(i, m);
    if (t.diameter_mm) r["residual_D_mm"] = *t.diameter_mm - model.d(i, m);
    rows.push_back(r);
  }
  return rows;
}

json rmse_by_role(const json& rows) {
  std::vector<double> c, v;
  for (const json& r : rows)
    (r["role"] == "calibrate" ? c : v).push_back(r["residual_deg"].get<double>());
  json j = {{"calibrate_deg", rmse(c)}, {"n_calibrate", c.size()}, {"n_validate", v.size()}};
  j["validate_deg"] = v.empty() ? json() : json(rmse(v));
  return j;
}

json Loop::run() {
  const fs::path loop_json = fs::path(out_) / "loop.json";
  if (fs::exists(loop_json) && !s_.force)
    throw InputError(loop_json.string() +
                     " already holds a finished loop; use --force to recompute it (the "
                     "simulation cache is kept) or another output folder");
  if (s_.mu_grid.size() < 2 || !std::is_sorted(s_.mu_grid.begin(), s_.mu_grid.end()) ||
      std::adjacent_find(s_.mu_grid.begin(), s_.mu_grid.end()) != s_.mu_grid.end() ||
      s_.mu_grid.front() < 0.0)
    throw InputError("loop: mu_grid must hold at least two increasing values >= 0");
  if (s_.seeds.size() < 2) throw InputError("loop: at least two seeds are needed (seed noise)");
  for (const LabTest& t : data_.tests) check_mu_key(t, s_.mu_key);
  for (std::size_t i = 0; i < data_.tests.size(); ++i)
    (data_.tests[i].role == "calibrate" ? cal_ : val_).push_back(i);
  if (cal_.size() < 3)
    throw InputError(data_.file + ": at least 3 tests with role calibrate are needed, got " +
                     std::to_string(cal_.size()));
  const auto t_start = std::chrono::steady_clock::now();

  // Baseline surface and pooled seed noise.
  say("baseline: " + std::to_string(data_.tests.size()) + " tests x " +
      std::to_string(s_.mu_grid.size()) + " mu_r x " + std::to_string(s_.seeds.size()) + " seeds");
  surfaces_.push_back(std::make_unique<Surface>(simulate_surface({})));
  const Surface& base = *surfaces_.back();
  {
    double ss = 0.0;
    int dof = 0;
    for (const Curve& c : base.curve)
      for (const auto& a : c.angle_seeds) {
        const double m = mean(a);
        for (double x : a) ss += (x - m) * (x - m);
        dof += static_cast<int>(a.size()) - 1;
      }
    noise_sd_ = std::sqrt(ss / std::max(1, dof));
    if (!(noise_sd_ > 0.0)) noise_sd_ = 1e-3;
  }
  const double seed_se = noise_sd_ / std::sqrt(double(s_.seeds.size()));
  Model model;
  model.terms = {{1.0, &base}};
  MuFit fit = fit_mu(model, nullptr);
  const double mu0 = fit.mu;
  const json rows_before = residual_table(model, fit.mu);
  json baseline = {{"mu_r", fit.mu},
                   {"mu_r_se", fit.mu_se},
                   {"mu_r_at_grid_edge", fit.at_edge},
                   {"seed_sd_deg", noise_sd_},
                   {"seed_se_deg", seed_se},
                   {"residuals", rows_before},
                   {"rmse", rmse_by_role(rows_before)}};
  // Each test's simulated angles on the grid, with the seeds of the pours that made the piles
  // and the pours that jammed (repeated; a lab pours its tests without jamming).
  baseline["curves"] = json::array();
  for (std::size_t i = 0; i < data_.tests.size(); ++i) {
    const Curve& c = base.curve[i];
    json seeds = json::array();
    for (const auto& at : base.raw[i]) {
      json s = json::array();
      for (const SimOutcome& o : at) s.push_back(o.seed);
      seeds.push_back(s);
    }
    int jammed = 0;
    for (int x : c.clogged) jammed += x;
    baseline["curves"].push_back({{"id", data_.tests[i].id},
                                  {"mu_r", c.mu},
                                  {"angle_deg", c.angle},
                                  {"angle_seeds_deg", c.angle_seeds},
                                  {"pour_seeds", seeds},
                                  {"clogged_pours", c.clogged}});
    if (jammed > 0)
      say("test " + data_.tests[i].id + ": " + std::to_string(jammed) +
          " baseline pour(s) formed no pile and were repeated with new seeds");
  }
  say("baseline mu_r = " + std::to_string(fit.mu) + ", calibration RMSE " +
      std::to_string(baseline["rmse"]["calibrate_deg"].get<double>()) + " deg, seed sd " +
      std::to_string(noise_sd_) + " deg");

  // Fingerprints at the grid point nearest the calibrated mu_r, with the baseline's seeds.
  std::size_t node = 0;
  for (std::size_t j = 1; j < s_.mu_grid.size(); ++j)
    if (std::abs(s_.mu_grid[j] - mu0) < std::abs(s_.mu_grid[node] - mu0)) node = j;
  struct Fingerprint {
    const CandidateEffect* effect;
    std::vector<double> angle, h, d, angle_se;
  };
  std::vector<Fingerprint> fps;
  json unavailable = json::array();
  std::vector<const CandidateEffect*> cands;
  for (const CandidateEffect& e : candidate_effects()) {
    if (!s_.candidates.empty() &&
        std::find(s_.candidates.begin(), s_.candidates.end(), e.name) == s_.candidates.end())
      continue;
    std::string why;
    for (const LabTest& t : data_.tests)
      if (why.empty()) {
        why = effect_unavailable(t, e);
        if (!why.empty()) why = "test " + t.id + ": " + why;
      }
    if (!why.empty()) {
      unavailable.push_back({{"name", e.name}, {"why", why}});
      say("candidate " + e.name + " unavailable: " + why);
      continue;
    }
    cands.push_back(&e);
  }
  {
    std::vector<SimRequest> req;
    // Each pair starts from the seed of the baseline pile it is compared with (a repeated pour's
    // seed if the first one jammed), so a measurement effect re-photographs that very pile.
    for (const CandidateEffect* e : cands)
      for (std::size_t i = 0; i < data_.tests.size(); ++i)
        for (const SimOutcome& off : base.raw[i][node])
          req.push_back(make_request(data_.tests[i], s_.mu_key, s_.mu_grid[node], off.seed,
                                     {{e, e->probe}}, s_.image));
    say("fingerprints: " + std::to_string(cands.size()) +
        " candidates at mu_r = " + std::to_string(s_.mu_grid[node]));
    // One batch per candidate, so that a candidate whose runs or photographs fail (a lens
    // model that folds, a pile vision cannot find from that camera) is reported, not fatal.
    std::vector<SimOutcome> on;
    std::vector<const CandidateEffect*> ok;
    const std::size_t per = data_.tests.size() * s_.seeds.size();
    for (std::size_t c = 0; c < cands.size(); ++c) {
      try {
        const std::vector<SimRequest> part(req.begin() + c * per, req.begin() + (c + 1) * per);
        const std::vector<SimOutcome> got = pour(part);
        bool all = true;
        for (const SimOutcome& o : got) all = all && o.pile;
        if (!all) throw std::runtime_error("a run formed no pile with the effect at its probe");
        on.insert(on.end(), got.begin(), got.end());
        ok.push_back(cands[c]);
      } catch (const std::exception& ex) {
        unavailable.push_back({{"name", cands[c]->name}, {"why", ex.what()}});
        say("candidate " + cands[c]->name + " failed at its probe: " + ex.what());
      }
    }
    cands = ok;
    std::size_t q = 0;
    for (const CandidateEffect* e : cands) {
      Fingerprint f{e, {}, {}, {}, {}};
      for (std::size_t i = 0; i < data_.tests.size(); ++i) {
        std::vector<double> da, dh, dd;
        for (std::size_t r = 0; r < s_.seeds.size(); ++r, ++q) {
          const SimOutcome& off = base.raw[i][node][r];
          da.push_back(twin_angle(on[q], s_.angle) - twin_angle(off, s_.angle));
          dh.push_back(on[q].height_mm - off.height_mm);
          dd.push_back(on[q].diameter_mm - off.diameter_mm);
        }
        f.angle.push_back(mean(da));
        f.h.push_back(mean(dh));
        f.d.push_back(mean(dd));
        double v = 0.0;
        for (double x : da) v += (x - mean(da)) * (x - mean(da));
        f.angle_se.push_back(std::sqrt(v / (da.size() - 1) / da.size()));
      }
      // An effect that moves the angle by less than the seed noise of a predicted angle at its
      // probe cannot be traced: any residual would need an absurd strength (a lens whose
      // distortion shifts the angle by 0.01 deg "explains" 5 deg with k1 = 100).
      double ms = 0.0;
      for (std::size_t i : cal_) ms += f.angle[i] * f.angle[i];
      const double rms = std::sqrt(ms / static_cast<double>(cal_.size()));
      if (rms < seed_se) {
        char why[200];
        std::snprintf(why, sizeof why,
                      "its fingerprint at the probe (RMS %.3g deg over the calibration tests) "
                      "is below the seed noise of a predicted angle (%.3g deg)",
                      rms, seed_se);
        unavailable.push_back({{"name", e->name}, {"why", why}});
        say("candidate " + e->name + " not traceable: " + why);
        continue;
      }
      // Nor can an effect whose fingerprint does not stand out of its own seed noise. A
      // fingerprint is a mean of paired differences whose noise (about sd sqrt(2 / seeds) for a
      // physical effect, which re-draws the piles) is larger than the seed noise above, so a pure
      // noise column passes the first test. Under "no effect", n RMS^2 / se^2 (se^2 the mean
      // squared standard error of the per-test means, n calibration tests) is about chi^2(n);
      // the fingerprint must exceed its 95% point (Wilson-Hilferty).
      if (s_.seeds.size() >= 2) {
        double se2 = 0.0;
        for (std::size_t i : cal_) se2 += f.angle_se[i] * f.angle_se[i];
        const double n = static_cast<double>(cal_.size());
        se2 /= n;
        const double a = 2.0 / (9.0 * n);
        const double chi2_95_per_n = std::pow(1.0 - a + 1.645 * std::sqrt(a), 3);
        if (rms * rms < chi2_95_per_n * se2) {
          char why[240];
          std::snprintf(why, sizeof why,
                        "its fingerprint at the probe (RMS %.3g deg over the calibration tests) "
                        "does not stand out of its own seed noise (standard error %.3g deg per "
                        "test; 95%% point %.3g deg)",
                        rms, std::sqrt(se2), std::sqrt(chi2_95_per_n * se2));
          unavailable.push_back({{"name", e->name}, {"why", why}});
          say("candidate " + e->name + " not traceable: " + why);
          continue;
        }
      }
      fps.push_back(std::move(f));
    }
  }
  json fingerprints = json::array();
  for (const Fingerprint& f : fps)
    fingerprints.push_back({{"name", f.effect->name},
                            {"probe", f.effect->probe},
                            {"mu_r", s_.mu_grid[node]},
                            {"angle_deg", f.angle},
                            {"angle_se_deg", f.angle_se},
                            {"H_mm", f.h},
                            {"D_mm", f.d}});

  // Iterations: trace, accept, refit by simulation.
  json iterations = json::array();
  json chosen = json::array();
  std::vector<EffectSetting> effects;
  std::set<std::string> used;
  for (int it = 0; it < s_.max_effects + 1; ++it) {
    const std::vector<double> sig = sigmas();
    TraceProblem p;
    const Eigen::Index n = static_cast<Eigen::Index>(cal_.size());
    p.residual.resize(n);
    p.sigma.resize(n);
    p.mu_sensitivity.resize(n);
    p.seed_noise_deg = seed_se;
    p.mu_shift_lo = s_.mu_grid.front() - fit.mu;
    p.mu_shift_hi = s_.mu_grid.back() - fit.mu;
    const double span = s_.mu_grid.back() - s_.mu_grid.front();
    for (Eigen::Index k = 0; k < n; ++k) {
      const std::size_t i = cal_[k];
      p.residual[k] = data_.tests[i].angle_deg - model.angle(i, fit.mu);
      p.sigma[k] = sig[i];
      // Slope over a tenth of the grid span (the monotone fit is piecewise linear).
      const double a = std::max(s_.mu_grid.front(), fit.mu - 0.05 * span);
      const double b = std::min(s_.mu_grid.back(), fit.mu + 0.05 * span);
      p.mu_sensitivity[k] = (model.angle(i, b) - model.angle(i, a)) / (b - a);
    }
    // A flat mu_r response (all slopes ~0) still leaves mu_r free as a constant shift.
    if (p.mu_sensitivity.cwiseAbs().maxCoeff() < 1e-6) p.mu_sensitivity.setOnes();
    const NullScore ns = score_null(p);
    std::vector<CandidateScore> scores;
    std::map<std::string, const Fingerprint*> by_name;
    for (const Fingerprint& f : fps) {
      by_name[f.effect->name] = &f;
      if (used.count(f.effect->name)) continue;
      Eigen::VectorXd col(n);
      for (Eigen::Index k = 0; k < n; ++k) col[k] = f.angle[cal_[k]];
      scores.push_back(score_candidate(p, f.effect->name, col, ns, s_.rule));
    }
    const int best = rank_candidates(scores);
    json iter = {{"iteration", it}, {"mu_r", fit.mu}, {"null", to_json(ns)}};
    iter["candidates"] = json::array();
    for (const auto& sc : scores) iter["candidates"].push_back(to_json(sc));
    if (best < 0 || it == s_.max_effects) {
      iter["chosen"] = nullptr;
      if (best >= 0) {
        // The rule holds for a candidate, but the effect limit stops the loop before its refit
        // (--max-effects 0 traces and ranks only).
        iter["stopped"] = "max_effects (" + std::to_string(s_.max_effects) + ") reached: " +
                          scores[static_cast<std::size_t>(best)].name +
                          " meets the acceptance rule but was not refitted";
        say("iteration " + std::to_string(it) + ": " + iter["stopped"].get<std::string>());
      } else {
        say("iteration " + std::to_string(it) + ": no candidate accepted");
      }
      iterations.push_back(iter);
      break;
    }
    const CandidateScore& sc = scores[static_cast<std::size_t>(best)];
    const CandidateEffect& e = find_effect(sc.name);
    const double off = e.off_from_scene ? scene_value(data_.tests.front(), e.key) : e.off;
    double p1 = std::clamp(off + sc.coef * (e.probe - off), e.lo, e.hi);
    say("iteration " + std::to_string(it) + ": " + e.name + " accepted (" + sc.why +
        "); linear estimate " + std::to_string(p1) + " " + e.units + ", simulating the grid");
    // The fingerprint at the node (calibration tests): the unit of the response fraction.
    const Fingerprint* fp = by_name.at(e.name);
    const double mu_node = s_.mu_grid[node];
    // One refit trial: the effect simulated at p on the whole grid and (mu_r, t) fitted jointly.
    struct Trial {
      double p = 0.0;         // simulated value
      double fraction = 0.0;  // its response at the node, in units of the probe's fingerprint
      const Surface* surf = nullptr;
      MuFit joint;
      double rmse = 0.0;  // calibration RMSE of the refitted model [deg]
      Model model;
    };
    std::vector<Trial> trials;
    std::string refit_note;
    auto cal_rmse = [&](const Model& m, double mu) {
      std::vector<double> r;
      for (std::size_t i : cal_) r.push_back(data_.tests[i].angle_deg - m.angle(i, mu));
      return rmse(r);
    };
    // The value may overshoot into piles the measurement cannot see (a smooth plate spreads a
    // small sample into a monolayer): then step back halfway towards off, twice at most.
    auto run_trial = [&](double p) -> bool {
      std::unique_ptr<Surface> surf;
      for (int attempt = 0; attempt < 3 && !surf; ++attempt) {
        std::vector<EffectSetting> with = effects;
        with.push_back({&e, p});
        try {
          surf = std::make_unique<Surface>(simulate_surface(with));
        } catch (const std::exception& ex) {
          refit_note +=
              "at " + std::to_string(p) + ": " + std::string(ex.what()).substr(0, 300) + "; ";
          say("refit at " + std::to_string(p) + " failed; stepping back halfway");
          p = off + 0.5 * (p - off);
        }
      }
      if (!surf) return false;
      surfaces_.push_back(std::move(surf));
      Trial tr;
      tr.p = p;
      tr.surf = surfaces_.back().get();
      double num = 0.0, den = 0.0;
      for (std::size_t i : cal_) {
        num += (tr.surf->curve[i].at(mu_node) - model.angle(i, mu_node)) * fp->angle[i];
        den += fp->angle[i] * fp->angle[i];
      }
      tr.fraction = den > 0.0 ? num / den : 0.0;
      // t may extrapolate beyond the simulated value, but never past the effect's range.
      const double bound = (p < off ? e.lo : e.hi) - off;
      const double saved_t_max = s_.t_max;
      if (p != off) s_.t_max = std::min(s_.t_max, std::max(1.0, bound / (p - off)));
      tr.joint = fit_mu(model, tr.surf);
      s_.t_max = saved_t_max;
      for (const auto& [w, sf] : model.terms)
        tr.model.terms.push_back({(1.0 - tr.joint.t) * w, sf});
      tr.model.terms.push_back({tr.joint.t, tr.surf});
      tr.rmse = cal_rmse(tr.model, tr.joint.mu);
      trials.push_back(tr);
      return true;
    };
    // Secant refinement. The linear estimate assumes the response grows linearly from off to the
    // probe; a threshold effect (a plate that starts to slide below some friction) breaks that.
    // When the simulated response fraction misses the traced strength c by more than half, the
    // next value interpolates c between the known responses (off: 0, probe: 1, and the trials),
    // at most twice more.
    const int kMaxRefinements = 2;
    if (run_trial(p1)) {
      for (int k = 0; k < kMaxRefinements; ++k) {
        const Trial& last = trials.back();
        if (std::abs(last.fraction - sc.coef) <= 0.5 * std::abs(sc.coef)) break;
        std::vector<std::pair<double, double>> pts = {{off, 0.0}, {e.probe, 1.0}};
        for (const Trial& tr : trials) pts.push_back({tr.p, tr.fraction});
        std::sort(pts.begin(), pts.end());
        double next = std::numeric_limits<double>::quiet_NaN();
        for (std::size_t q = 0; q + 1 < pts.size(); ++q) {
          const auto [pa, fa] = pts[q];
          const auto [pb, fb] = pts[q + 1];
          if (fa == fb || (sc.coef - fa) * (sc.coef - fb) > 0.0) continue;
          next = pa + (sc.coef - fa) / (fb - fa) * (pb - pa);
          // Prefer the bracket next to the last trial.
          if (pa == last.p || pb == last.p) break;
        }
        if (!std::isfinite(next)) break;
        next = std::clamp(next, e.lo, e.hi);
        bool known = false;
        for (const auto& [pp, ff] : pts)
          known = known || std::abs(pp - next) <= 1e-3 * std::max(1.0, std::abs(pp));
        if (known) break;
        say(e.name + ": simulated response " + std::to_string(last.fraction) +
            " of the probe's at " + std::to_string(last.p) + " (traced " + std::to_string(sc.coef) +
            "); refining at " + std::to_string(next));
        if (!run_trial(next)) break;
      }
    }
    if (trials.empty()) {
      iter["chosen"] = {{"name", e.name}, {"refit_failed", refit_note}, {"linear_estimate", p1}};
      iterations.push_back(iter);
      break;
    }
    std::size_t pick = 0;
    for (std::size_t q = 1; q < trials.size(); ++q)
      if (trials[q].rmse < trials[pick].rmse) pick = q;
    json trial_log = json::array();
    for (const Trial& tr : trials)
      trial_log.push_back({{"simulated_at", tr.p},
                           {"response_fraction", tr.fraction},
                           {"t", tr.joint.t},
                           {"mu_r", tr.joint.mu},
                           {"rmse_calibrate_deg", tr.rmse}});
    const Trial& best_trial = trials[pick];
    const double p1_requested = p1;
    p1 = best_trial.p;
    const MuFit joint = best_trial.joint;
    const double value = off + joint.t * (p1 - off);
    const double value_se = joint.t_se * std::abs(p1 - off);
    const Model next = best_trial.model;
    const double rmse_now = cal_rmse(model, fit.mu), rmse_next = best_trial.rmse;
    const double margin = s_.rule.loo_margin_factor * seed_se;
    // The simulated refit is the test of the linear tracing: when the joint fit puts the effect
    // back at its off value (t = 0), or the simulated model does not lower the calibration error
    // by more than the seed noise of a prediction, the simulations do not confirm it and it is
    // not chosen.
    std::string reason;
    if (joint.t <= 0.0)
      reason =
          "the joint refit of mu_r and the effect on simulated piles puts the effect at its "
          "off value (t = 0)";
    else if (rmse_next > rmse_now - margin)
      reason = "the simulated refit lowers the calibration RMSE from " + std::to_string(rmse_now) +
               " to " + std::to_string(rmse_next) + " deg, not by more than the seed noise " +
               std::to_string(margin) + " deg";
    if (!reason.empty()) {
      iter["chosen"] = nullptr;
      iter["not_confirmed"] = {{"name", e.name},      {"linear_estimate", p1_requested},
                               {"simulated_at", p1},  {"t", joint.t},
                               {"mu_r", joint.mu},    {"rmse_calibrate_deg", rmse_next},
                               {"trials", trial_log}, {"refit_notes", refit_note},
                               {"reason", reason}};
      say(e.name + ": not confirmed by the simulated refit (" + reason + "); not chosen");
      iterations.push_back(iter);
      break;
    }
    model = next;
    fit = joint;
    effects.push_back({&e, value});
    used.insert(e.name);
    json c = {{"name", e.name},
              {"kind", e.kind == EffectKind::kPhysics ? "physics" : "measurement"},
              {"key", e.key},
              {"units", e.units},
              {"off", off},
              {"probe", e.probe},
              {"linear_estimate", p1_requested},
              {"simulated_at", p1},
              {"trials", trial_log},
              {"refit_notes", refit_note},
              {"value", value},
              {"value_se", value_se},
              {"t", joint.t},
              {"t_at_limit", joint.t <= 0.0 || joint.t >= s_.t_max},
              {"mu_r", joint.mu},
              {"mu_r_se", joint.mu_se}};
    iter["chosen"] = c;
    chosen.push_back(c);
    iterations.push_back(iter);
  }

  const json rows_after = residual_table(model, fit.mu);
  json provenance = {
      {"code_version", code_version()}, {"data", data_.file},   {"seeds", s_.seeds},
      {"angle_measure", angle_measure_name(s_.angle)},
      {"angle_method", angle_measure_method(s_.angle)},
      {"lab_angle_source", lab_angle_source(s_.angle)},
      {"mu_grid", s_.mu_grid},          {"mu_key", s_.mu_key},  {"image", s_.image.key()},
      {"max_pours", s_.max_pours},
      {"cache", cache_.dir()},          {"finished", utc_now()}};
  if (!base.raw.empty() && !base.raw[0].empty() && !base.raw[0][0].empty())
    provenance["run"] = base.raw[0][0][0].provenance;
  std::set<std::string> scenes;
  for (const LabTest& t : data_.tests) scenes.insert(t.scene_path);
  provenance["scenes"] = scenes;
  json tests = json::array();
  for (const LabTest& t : data_.tests) tests.push_back(to_json(t));
  json registry = json::array();
  for (const CandidateEffect& e : candidate_effects()) registry.push_back(to_json(e));
  json final_block = {{"mu_r", fit.mu},
                      {"mu_r_se", fit.mu_se},
                      {"effects", chosen},
                      {"residuals", rows_after},
                      {"rmse", rmse_by_role(rows_after)}};
  const double before = baseline["rmse"]["calibrate_deg"],
               after = final_block["rmse"]["calibrate_deg"];
  json loop = {
      {"tests", tests},
      {"candidate_registry", registry},
      {"unavailable_candidates", unavailable},
      {"rule",
       {{"min_t", s_.rule.min_t},
        {"loo_margin_deg", s_.rule.loo_margin_factor * seed_se},
        {"text",
         "accept the best-ranked candidate with |c|/se > min_t and a leave-one-"
         "test-out RMSE below the mu_r-only LOO RMSE by more than the seed "
         "standard error of a predicted angle"}}},
      {"baseline", baseline},
      {"fingerprints", fingerprints},
      {"iterations", iterations},
      {"final", final_block},
      {"summary",
       {{"chosen", chosen.empty() ? json() : json(chosen.back()["name"])},
        {"effects",
         [&] {
           json names = json::array();
           for (const auto& c : chosen) names.push_back(c["name"]);
           return names;
         }()},
        {"rmse_calibrate_before_deg", before},
        {"rmse_calibrate_after_deg", after},
        {"rmse_validate_before_deg", baseline["rmse"]["validate_deg"]},
        {"rmse_validate_after_deg", final_block["rmse"]["validate_deg"]},
        {"reduction", before > 0.0 ? 1.0 - after / before : 0.0}}},
      {"simulations",
       {{"pile_runs_started", cache_.simulations_started()},
        {"photos_started", cache_.photos_started()},
        {"wall_s",
         std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count()}}},
      {"provenance", provenance}};
  fs::create_directories(out_);
  if (s_.html) write_loop_html(loop, out_);
  write_json_atomic(loop_json.string(), loop);
  return loop;
}

}  // namespace

LabData lab_angles(const LabData& data, AngleMeasure measure) {
  if (measure == AngleMeasure::kSlice)
    throw InputError(data.file + ": the loop cannot compare the 'slice' angle (a protractor on "
                     "particle slices has no counterpart in a lab's photos or sheet); use image, "
                     "image_flank or particles");
  LabData out = data;
  for (LabTest& t : out.tests) {
    if (t.photos.empty()) continue;  // a typed angle (or H and D) is used as given
    if (measure == AngleMeasure::kImageFlank) {
      const json& f = t.photo_measurement.contains("flank_deg") ? t.photo_measurement["flank_deg"]
                                                                : json();
      if (!f.is_object() || !f.contains("mean") || !f["mean"].is_number())
        throw InputError(data.file + " line " + std::to_string(t.line) + " (test " + t.id +
                         "), column photo: the photos' measurement has no flank angle");
      t.angle_deg = f["mean"].get<double>();
    }
    t.photo_measurement["compared_angle"] = {{"measure", angle_measure_name(measure)},
                                             {"angle_deg", t.angle_deg}};
  }
  return out;
}

std::string lab_angle_source(AngleMeasure measure) {
  if (measure == AngleMeasure::kImageFlank)
    return "tests with photos: the flank angle vision measured on them; tests with a typed "
           "angle (or H and D): that value, taken as the flank angle (the lab pile assumed a "
           "full cone)";
  return "tests with photos: atan(2H/D) vision measured on them; others: the typed angle (or "
         "atan(2H/D) of the typed H and D)";
}

double twin_angle(const SimOutcome& o, AngleMeasure measure) {
  switch (measure) {
    case AngleMeasure::kImage:
      return o.angle_deg;
    case AngleMeasure::kImageFlank:
      if (o.pile && !std::isfinite(o.flank_deg))
        throw std::runtime_error(o.image_dir +
                                 ": this photograph's measurement has no flank angle (made by an "
                                 "older version); use a fresh --cache");
      return o.pile ? o.flank_deg : 0.0;
    case AngleMeasure::kParticles:
      return o.positions_angle_deg;
    case AngleMeasure::kSlice:
      break;
  }
  throw std::runtime_error("the loop compares image, image_flank or particles angles, not slice");
}

json run_loop(const LabData& data, const std::string& out_dir, const LoopSettings& settings) {
  const LabData compared = lab_angles(data, settings.angle);
  Loop loop(compared, out_dir, settings);
  return loop.run();
}

}  // namespace reposetwin::experiments
