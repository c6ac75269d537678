// The loop's model of the twin: curves on the mu_r grid, their mixture, the joint fit of mu_r
// (and of a refit's weight t) and the residuals it leaves (loop_stages.hpp, loop.hpp's note).
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "experiments/loop/loop_stages.hpp"

namespace reposetwin::experiments::loop_detail {

double Curve::lin(const std::vector<double>& y, double m) const {
  m = clamp(m);
  std::size_t k = 0;
  while (k + 2 < mu.size() && m > mu[k + 1]) ++k;
  const double s = (m - mu[k]) / (mu[k + 1] - mu[k]);
  return y[k] + s * (y[k + 1] - y[k]);
}

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The scan of the joint fit: mu_r on 2001 points of the grid's span, the weight t of `extra` in
// closed form at each (clamped to [0, t_max]); the lowest weighted SSE wins. Each point's sums
// go into `profile`.
MuFit scan_mu(const LoopContext& ctx, const Model& model, const Surface* extra, double t_max,
              const std::vector<std::size_t>& tests, const std::vector<Channel>& channels,
              std::vector<ProfileRow>& profile) {
  const double lo = ctx.grid.front(), hi = ctx.grid.back();
  const int steps = 2000;
  const Model alone{{{1.0, extra}}};
  MuFit best;
  double best_sse = 1e300;
  for (int q = 0; q <= steps; ++q) {
    const double m = lo + (hi - lo) * q / steps;
    double swdy = 0.0, swdd = 0.0, swyy = 0.0;
    std::vector<double> y, dd, w;  // residual, extra surface's change, weight 1 / sigma^2
    for (std::size_t i : tests)
      for (Channel c : channels) {
        const double base = model.value(i, m, c);
        const double di = extra ? alone.value(i, m, c) - base : 0.0;
        y.push_back(ctx.observed(i, c) - base);
        dd.push_back(di);
        w.push_back(1.0 / (ctx.sigma(i, c) * ctx.sigma(i, c)));
        swdy += w.back() * di * y.back();
        swdd += w.back() * di * di;
        swyy += w.back() * y.back() * y.back();
      }
    profile.push_back({m, swyy, swdy, swdd});
    const double t = (extra && swdd > 0.0) ? std::clamp(swdy / swdd, 0.0, t_max) : 0.0;
    double sse = 0.0;
    for (std::size_t k = 0; k < y.size(); ++k) sse += w[k] * std::pow(y[k] - t * dd[k], 2);
    if (sse < best_sse) {
      best_sse = sse;
      best.mu = m;
      best.t = t;
    }
  }
  return best;
}

// Standard errors from the Jacobian of the prediction in (mu, t) at the fit, each row over its
// noise; with `extra`, the information matrix in total and per test (for the next tests).
void add_standard_errors(const LoopContext& ctx, const Model& model, const Surface* extra,
                         const std::vector<std::size_t>& tests,
                         const std::vector<Channel>& channels, MuFit& best) {
  const double lo = ctx.grid.front(), hi = ctx.grid.back();
  const Model alone{{{1.0, extra}}};
  const double h = (hi - lo) / 100.0;
  Eigen::MatrixXd jac(tests.size() * channels.size(), extra ? 2 : 1);
  Eigen::Index k = 0;
  for (std::size_t i : tests)
    for (Channel c : channels) {
      auto pred = [&](double m) {
        const double base = model.value(i, m, c);
        return extra ? base + best.t * (alone.value(i, m, c) - base) : base;
      };
      const double a = std::max(lo, best.mu - h), b = std::min(hi, best.mu + h);
      jac(k, 0) = (pred(b) - pred(a)) / (b - a) / ctx.sigma(i, c);
      if (extra)
        jac(k, 1) = (alone.value(i, best.mu, c) - model.value(i, best.mu, c)) / ctx.sigma(i, c);
      ++k;
    }
  const Eigen::MatrixXd info = jac.transpose() * jac;
  if (extra) {
    best.info = info;
    Eigen::Index row = 0;
    for (std::size_t i : tests) {
      const Eigen::MatrixXd part = jac.middleRows(row, static_cast<Eigen::Index>(channels.size()));
      best.test_info.push_back({i, part.transpose() * part});
      row += static_cast<Eigen::Index>(channels.size());
    }
  }
  Eigen::FullPivLU<Eigen::MatrixXd> lu(info);
  if (lu.isInvertible()) {
    const Eigen::MatrixXd cov = lu.inverse();
    best.mu_se = std::sqrt(std::max(0.0, cov(0, 0)));
    if (extra) best.t_se = std::sqrt(std::max(0.0, cov(1, 1)));
  } else {
    best.mu_se = std::numeric_limits<double>::infinity();
    best.t_se = std::numeric_limits<double>::infinity();
  }
}

}  // namespace

// A surface of weight 0 (a refit whose t came out 0) does not enter the prediction, so its jam
// does not take the prediction away.
std::string Model::no_pile(std::size_t i) const {
  for (const auto& [w, surf] : terms)
    if (w != 0.0 && !surf->curve[i].no_pile.empty()) return surf->curve[i].no_pile;
  return "";
}

// The weighted sum of `of(curve)` over the surfaces that enter the prediction, or NaN when one
// of them formed no pile for test i.
template <class Of>
double Model::mix(std::size_t i, Of of) const {
  if (!no_pile(i).empty()) return kNaN;
  double s = 0.0;
  for (const auto& [w, surf] : terms)
    if (w != 0.0) s += w * of(surf->curve[i]);
  return s;
}

double Model::value(std::size_t i, double m, Channel channel) const {
  if (channel == Channel::kAngle) return mix(i, [m](const Curve& c) { return c.at(m); });
  return mix(i, [m, channel](const Curve& c) { return c.lin(c.mean[channel], m); });
}

// The loop's joint fit, not calibration::calibrate_batch's: calibrate matches ONE test's angle
// by inverting a monotone (isotonic) fit it samples adaptively, with a bootstrap interval; the
// loop fits one mu_r to MANY tests at once on a fixed grid (weighted least squares over the
// calibration tests, sigma_i from seeds and the lab), jointly with the weight t of a candidate's
// simulated surface, with standard errors from the Jacobian. With one test, no surface and a
// monotone curve both give the crossing of the interpolated curve, but neither generalises to the
// other's problem, so they stay two estimators.
MuFit fit_mu(const LoopContext& ctx, const Model& model, const Surface* extra, double t_max,
             const std::vector<std::size_t>& tests, const std::vector<Channel>& channels) {
  const double lo = ctx.grid.front(), hi = ctx.grid.back();
  std::vector<ProfileRow> profile;  // the likelihood surface, for the joint region
  MuFit best = scan_mu(ctx, model, extra, t_max, tests, channels, profile);
  best.at_edge = best.mu <= lo + 1e-12 || best.mu >= hi - 1e-12;
  const int n_obs = static_cast<int>(tests.size() * channels.size());
  if (extra && n_obs >= 3) best.region = joint_region(profile, 0.0, t_max, n_obs);
  best.t_max = t_max;
  best.profile = std::move(profile);
  add_standard_errors(ctx, model, extra, tests, channels, best);
  return best;
}

std::vector<ResidualRow> residuals(const LoopContext& ctx, const Model& model, double m) {
  std::vector<ResidualRow> rows;
  for (std::size_t i = 0; i < ctx.tests().size(); ++i) {
    const LabTest& t = ctx.tests()[i];
    ResidualRow r;
    r.id = t.id;
    r.role = t.role;
    r.measured_deg = t.angle_deg;
    r.predicted_deg = model.angle(i, m);
    r.residual_deg = t.angle_deg - r.predicted_deg;
    r.sigma_deg = ctx.sigma(i, Channel::kAngle);
    r.predicted_se_deg = ctx.noise.se;
    r.no_pile = model.no_pile(i);
    if (!r.no_pile.empty()) {  // NaN predictions; the lab's H, D and crest have no residual
      r.predicted_h_mm = r.predicted_d_mm = kNaN;
      rows.push_back(r);
      continue;
    }
    r.predicted_h_mm = model.value(i, m, Channel::kH);
    r.predicted_d_mm = model.value(i, m, Channel::kD);
    if (t.height_mm) r.residual_h_mm = *t.height_mm - r.predicted_h_mm;
    if (t.diameter_mm) r.residual_d_mm = *t.diameter_mm - r.predicted_d_mm;
    if (t.crest_mm) {
      r.predicted_crest_mm = model.value(i, m, Channel::kCrest);
      r.residual_crest_mm = *t.crest_mm - *r.predicted_crest_mm;
    }
    rows.push_back(r);
  }
  return rows;
}

double calibration_rmse(const LoopContext& ctx, const Model& model, double mu) {
  std::vector<double> r;
  for (std::size_t i : ctx.roles.fitted) r.push_back(ctx.tests()[i].angle_deg - model.angle(i, mu));
  return rmse(r);
}

}  // namespace reposetwin::experiments::loop_detail
