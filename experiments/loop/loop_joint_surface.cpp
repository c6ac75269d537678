#include "experiments/loop/loop_joint_surface.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace reposetwin::experiments {
namespace {

void check(const SurfaceProblem& p, const SurfaceFingerprint& f, const std::string& name) {
  if (p.channels.empty()) throw std::invalid_argument("surface trace: no channel");
  const Eigen::Index k = static_cast<Eigen::Index>(p.mu.size());
  if (k < 2) throw std::invalid_argument("surface trace: at least 2 mu_r samples");
  for (std::size_t q = 1; q < p.mu.size(); ++q)
    if (!(p.mu[q] > p.mu[q - 1]))
      throw std::invalid_argument("surface trace: mu_r samples not ascending");
  const Eigen::Index n = p.channels.front().observed.size();
  if (n < 3)
    throw std::invalid_argument("surface trace: at least 3 tests, got " + std::to_string(n));
  for (const SurfaceChannel& ch : p.channels)
    if (ch.observed.size() != n || ch.sigma.size() != n || ch.predicted.rows() != k ||
        ch.predicted.cols() != n)
      throw std::invalid_argument("surface trace: channel " + ch.name + " has a different size");
  if (!f.empty() && f.size() != p.channels.size())
    throw std::invalid_argument("surface trace: " + name + " has " + std::to_string(f.size()) +
                                " fingerprint surfaces for " + std::to_string(p.channels.size()) +
                                " channels");
  for (const Eigen::MatrixXd& m : f)
    if (m.rows() != k || m.cols() != n)
      throw std::invalid_argument("surface trace: " + name + "'s surface size");
}

// The standardised rows at sample k, channel-major (row ch n + i): y = (obs - P) / sigma and
// the fingerprint over sigma.
struct Rows {
  Eigen::VectorXd y, f;
};

Rows rows_at(const SurfaceProblem& p, const SurfaceFingerprint& fp, Eigen::Index k) {
  const Eigen::Index n = p.channels.front().observed.size();
  const Eigen::Index m = n * static_cast<Eigen::Index>(p.channels.size());
  Rows r{Eigen::VectorXd(m), Eigen::VectorXd::Zero(m)};
  for (std::size_t c = 0; c < p.channels.size(); ++c) {
    const SurfaceChannel& ch = p.channels[c];
    for (Eigen::Index i = 0; i < n; ++i) {
      const Eigen::Index row = static_cast<Eigen::Index>(c) * n + i;
      r.y[row] = (ch.observed[i] - ch.predicted(k, i)) / ch.sigma[i];
      if (!fp.empty()) r.f[row] = fp[c](k, i) / ch.sigma[i];
    }
  }
  return r;
}

// The best sample and strength over the rows `keep` marks (all rows when empty).
struct SampleFit {
  Eigen::Index k = 0;
  double c = 0.0;
  double chi2 = std::numeric_limits<double>::infinity();
};

SampleFit best_sample(const std::vector<Rows>& at, bool with_f, const std::vector<bool>& keep) {
  SampleFit best;
  for (std::size_t k = 0; k < at.size(); ++k) {
    const Rows& r = at[k];
    double ff = 0.0, fy = 0.0, yy = 0.0;
    for (Eigen::Index row = 0; row < r.y.size(); ++row) {
      if (!keep.empty() && !keep[static_cast<std::size_t>(row)]) continue;
      ff += r.f[row] * r.f[row];
      fy += r.f[row] * r.y[row];
      yy += r.y[row] * r.y[row];
    }
    const double c = with_f && ff > 0.0 ? fy / ff : 0.0;
    const double chi2 = yy - 2.0 * c * fy + c * c * ff;
    if (chi2 < best.chi2) best = {static_cast<Eigen::Index>(k), c, chi2};
  }
  return best;
}

// The standard error of c at the minimum: of the pair (mu, c) from the Gauss-Newton matrix with
// the slope against mu by central differences of the samples, or of c alone on the grid's end.
// NaN when mu and c cannot be told apart (a singular matrix).
double coef_se(const std::vector<Rows>& at, const std::vector<double>& mu, const SampleFit& s) {
  const Rows& r = at[static_cast<std::size_t>(s.k)];
  const double ff = r.f.squaredNorm();
  const Eigen::Index last = static_cast<Eigen::Index>(at.size()) - 1;
  if (s.k == 0 || s.k == last) return 1.0 / std::sqrt(ff);
  const Rows& a = at[static_cast<std::size_t>(s.k - 1)];
  const Rows& b = at[static_cast<std::size_t>(s.k + 1)];
  const double dm = mu[static_cast<std::size_t>(s.k + 1)] - mu[static_cast<std::size_t>(s.k - 1)];
  // d residual / d mu of y - c f.
  const Eigen::VectorXd g = ((b.y - s.c * b.f) - (a.y - s.c * a.f)) / dm;
  Eigen::Matrix2d jtj;
  jtj << g.squaredNorm(), -g.dot(r.f), -g.dot(r.f), ff;
  const double det = jtj.determinant();
  if (!(det > 1e-12 * jtj(0, 0) * ff)) return std::numeric_limits<double>::quiet_NaN();
  return std::sqrt(jtj(0, 0) / det);
}

}  // namespace

JointScore score_joint_on_surfaces(const SurfaceProblem& p, const std::string& name,
                                   const SurfaceFingerprint& f) {
  check(p, f, name);
  const Eigen::Index n = p.channels.front().observed.size();
  const Eigen::Index samples = static_cast<Eigen::Index>(p.mu.size());
  std::vector<Rows> at;
  for (Eigen::Index k = 0; k < samples; ++k) at.push_back(rows_at(p, f, k));
  JointScore out;
  out.name = name;
  out.rows = static_cast<int>(at.front().y.size());
  bool with_f = !f.empty();
  if (with_f) {
    double most = 0.0;
    for (const Rows& r : at) most = std::max(most, r.f.squaredNorm());
    with_f = most > 0.0 && std::isfinite(most);
    out.identifiable = with_f;
  }
  const SampleFit fit = best_sample(at, with_f, {});
  out.mu_shift = p.mu[static_cast<std::size_t>(fit.k)] - p.mu_fit;
  out.mu_shift_at_bound = fit.k == 0 || fit.k == samples - 1;
  out.chi2 = fit.chi2;
  if (with_f) {
    const double se = coef_se(at, p.mu, fit);
    if (std::isfinite(se)) {
      out.coef = fit.c;
      out.coef_se = se;
      out.t = se > 0.0 ? std::abs(fit.c) / se : 0.0;
    } else {
      out.identifiable = false;  // mu_r and the effect move the piles alike at the minimum
    }
  }
  const Rows& r = at[static_cast<std::size_t>(fit.k)];
  for (std::size_t c = 0; c < p.channels.size(); ++c) {
    double x = 0.0;
    for (Eigen::Index i = 0; i < n; ++i) {
      const Eigen::Index row = static_cast<Eigen::Index>(c) * n + i;
      const double e = r.y[row] - fit.c * r.f[row];
      x += e * e;
    }
    out.chi2_by_channel.push_back(x);
  }
  // Leave-one-test-out: (mu, c) fitted without test i predict its rows.
  const std::size_t rows = static_cast<std::size_t>(out.rows);
  for (Eigen::Index i = 0; i < n; ++i) {
    std::vector<bool> keep(rows, true);
    for (std::size_t c = 0; c < p.channels.size(); ++c)
      keep[c * static_cast<std::size_t>(n) + static_cast<std::size_t>(i)] = false;
    const SampleFit without = best_sample(at, with_f, keep);
    const Rows& w = at[static_cast<std::size_t>(without.k)];
    for (std::size_t c = 0; c < p.channels.size(); ++c) {
      const Eigen::Index row = static_cast<Eigen::Index>(c) * n + i;
      const double e = w.y[row] - without.c * w.f[row];
      out.loo_chi2 += e * e;
    }
  }
  return out;
}

JointScore score_offset_on_surfaces(const SurfaceProblem& p) {
  if (p.channels.empty()) throw std::invalid_argument("surface trace: no channel");
  const Eigen::Index k = static_cast<Eigen::Index>(p.mu.size());
  const Eigen::Index n = p.channels.front().observed.size();
  SurfaceFingerprint f(p.channels.size(), Eigen::MatrixXd::Zero(k, n));
  f[0].setOnes();
  return score_joint_on_surfaces(p, "offset", f);
}

double interpolate_on_nodes(const std::vector<double>& nodes, const std::vector<double>& values,
                            double m) {
  if (nodes.size() != values.size())
    throw std::invalid_argument("interpolate_on_nodes: " + std::to_string(nodes.size()) +
                                " nodes, " + std::to_string(values.size()) + " values");
  int lo = -1, hi = -1;  // the known nodes nearest below and above m
  for (std::size_t q = 0; q < nodes.size(); ++q) {
    if (!std::isfinite(values[q])) continue;
    if (nodes[q] <= m) lo = static_cast<int>(q);
    if (nodes[q] >= m && hi < 0) hi = static_cast<int>(q);
  }
  if (lo < 0 && hi < 0) return std::numeric_limits<double>::quiet_NaN();
  if (lo < 0) return values[static_cast<std::size_t>(hi)];
  if (hi < 0 || hi == lo) return values[static_cast<std::size_t>(lo)];
  const double a = nodes[static_cast<std::size_t>(lo)], b = nodes[static_cast<std::size_t>(hi)];
  const double w = (m - a) / (b - a);
  return (1.0 - w) * values[static_cast<std::size_t>(lo)] +
         w * values[static_cast<std::size_t>(hi)];
}

}  // namespace reposetwin::experiments
