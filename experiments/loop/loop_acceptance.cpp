#include "experiments/loop/loop_acceptance.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "experiments/io/format.hpp"
#include "experiments/io/json_fields.hpp"
#include "experiments/io/json_read.hpp"

namespace reposetwin::experiments {
namespace {

void check_sizes(const Eigen::MatrixXd& x, const Eigen::VectorXd& y, const Eigen::VectorXd& sigma) {
  if (x.rows() != y.size() || sigma.size() != y.size())
    throw std::invalid_argument("weighted least squares: X has " + std::to_string(x.rows()) +
                                " rows, y " + std::to_string(y.size()) + ", sigma " +
                                std::to_string(sigma.size()));
  if (x.rows() < x.cols())
    throw std::invalid_argument("weighted least squares: " + std::to_string(x.rows()) +
                                " rows for " + std::to_string(x.cols()) + " coefficients");
  for (Eigen::Index i = 0; i < sigma.size(); ++i)
    if (!(sigma[i] > 0.0) || !std::isfinite(sigma[i]))
      throw std::invalid_argument("weighted least squares: sigma[" + std::to_string(i) +
                                  "] = " + std::to_string(sigma[i]) + " must be positive");
}

Eigen::MatrixXd columns(const Eigen::VectorXd& a, const Eigen::VectorXd* b) {
  Eigen::MatrixXd x(a.size(), b ? 2 : 1);
  x.col(0) = a;
  if (b) x.col(1) = *b;
  return x;
}

}  // namespace

double chi2_95(double dof) {
  if (!(dof > 0.0)) throw std::invalid_argument("chi2_95: dof must be > 0");
  const double a = 2.0 / (9.0 * dof);
  return dof * std::pow(1.0 - a + 1.645 * std::sqrt(a), 3);
}

BoundedFit bounded_fit(const Eigen::VectorXd& s, const Eigen::VectorXd* f, const Eigen::VectorXd& y,
                       const Eigen::VectorXd& sigma, double lo, double hi) {
  BoundedFit out;
  const WlsFit free = weighted_least_squares(columns(s, f), y, sigma);
  out.b = free.beta[0];
  if (f) {
    out.c = free.beta[1];
    out.c_se = free.se[1];
  }
  out.rmse = free.rmse;
  out.chi2 = free.chi2;
  if (out.b >= lo && out.b <= hi) return out;
  out.at_bound = true;
  out.b = out.b < lo ? lo : hi;
  const Eigen::VectorXd rest = y - out.b * s;
  if (f) {
    const WlsFit g = weighted_least_squares(*f, rest, sigma);
    out.c = g.beta[0];
    out.c_se = g.se[0];
    out.rmse = g.rmse;
    out.chi2 = g.chi2;
  } else {
    out.rmse = std::sqrt(rest.squaredNorm() / static_cast<double>(rest.size()));
    out.chi2 = rest.cwiseQuotient(sigma).squaredNorm();
  }
  return out;
}

namespace {

// Leave-one-out RMSE of the bounded fit.
double bounded_loo_rmse(const Eigen::VectorXd& s, const Eigen::VectorXd* f,
                        const Eigen::VectorXd& y, const Eigen::VectorXd& sigma, double lo,
                        double hi) {
  const Eigen::Index n = y.size();
  const Eigen::Index k = f ? 2 : 1;
  if (n < k + 2)
    throw std::invalid_argument("leave-one-out: " + std::to_string(n) + " tests for " +
                                std::to_string(k) + " coefficients (need at least " +
                                std::to_string(k + 2) + ")");
  double sum = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) {
    Eigen::VectorXd si(n - 1), fi(n - 1), yi(n - 1), wi(n - 1);
    for (Eigen::Index r = 0, q = 0; r < n; ++r) {
      if (r == i) continue;
      si[q] = s[r];
      if (f) fi[q] = (*f)[r];
      yi[q] = y[r];
      wi[q] = sigma[r];
      ++q;
    }
    double err = 0.0;
    try {
      const BoundedFit b = bounded_fit(si, f ? &fi : nullptr, yi, wi, lo, hi);
      err = y[i] - b.b * s[i] - (f ? b.c * (*f)[i] : 0.0);
    } catch (const std::invalid_argument&) {
      err = y[i];  // as loo_rmse: without row i the columns are degenerate
    }
    sum += err * err;
  }
  return std::sqrt(sum / static_cast<double>(n));
}

}  // namespace

WlsFit weighted_least_squares(const Eigen::MatrixXd& x, const Eigen::VectorXd& y,
                              const Eigen::VectorXd& sigma) {
  check_sizes(x, y, sigma);
  const Eigen::VectorXd w = sigma.array().inverse();
  const Eigen::MatrixXd xw = w.asDiagonal() * x;
  const Eigen::VectorXd yw = w.cwiseProduct(y);
  const Eigen::MatrixXd normal = xw.transpose() * xw;
  Eigen::LDLT<Eigen::MatrixXd> ldlt(normal);
  // Singular when a pivot is tiny next to the matrix scale (zero or proportional columns).
  const double scale = normal.diagonal().cwiseAbs().maxCoeff();
  if (!(scale > 0.0) || ldlt.info() != Eigen::Success ||
      ldlt.vectorD().cwiseAbs().minCoeff() <= 1e-12 * scale)
    throw std::invalid_argument(
        "weighted least squares: the columns are zero or proportional (singular normal matrix)");
  WlsFit f;
  f.beta = ldlt.solve(xw.transpose() * yw);
  const Eigen::MatrixXd cov = ldlt.solve(Eigen::MatrixXd::Identity(x.cols(), x.cols()));
  f.se = cov.diagonal().cwiseMax(0.0).cwiseSqrt();
  const Eigen::VectorXd res = y - x * f.beta;
  f.chi2 = res.cwiseProduct(w).squaredNorm();
  f.rmse = std::sqrt(res.squaredNorm() / static_cast<double>(res.size()));
  return f;
}

double loo_rmse(const Eigen::MatrixXd& x, const Eigen::VectorXd& y, const Eigen::VectorXd& sigma) {
  check_sizes(x, y, sigma);
  const Eigen::Index n = x.rows();
  if (n < x.cols() + 2)
    throw std::invalid_argument("leave-one-out: " + std::to_string(n) + " tests for " +
                                std::to_string(x.cols()) + " coefficients (need at least " +
                                std::to_string(x.cols() + 2) + ")");
  double sum = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) {
    Eigen::MatrixXd xi(n - 1, x.cols());
    Eigen::VectorXd yi(n - 1), si(n - 1);
    for (Eigen::Index r = 0, k = 0; r < n; ++r) {
      if (r == i) continue;
      xi.row(k) = x.row(r);
      yi[k] = y[r];
      si[k] = sigma[r];
      ++k;
    }
    double err = 0.0;
    try {
      const WlsFit f = weighted_least_squares(xi, yi, si);
      err = y[i] - x.row(i).dot(f.beta);
    } catch (const std::invalid_argument&) {
      // Without row i the columns are degenerate: this row alone carried them, so the model
      // cannot predict it; count the whole residual.
      err = y[i];
    }
    sum += err * err;
  }
  return std::sqrt(sum / static_cast<double>(n));
}

NullScore score_null(const TraceProblem& p) {
  const Eigen::Index n = p.residual.size();
  if (p.sigma.size() != n || p.mu_sensitivity.size() != n)
    throw std::invalid_argument("trace: residual, sigma and mu_sensitivity differ in size");
  if (n < 3)
    throw std::invalid_argument("trace: at least 3 tests are needed, got " + std::to_string(n));
  if (!(p.mu_shift_lo <= 0.0 && p.mu_shift_hi >= 0.0))
    throw std::invalid_argument("trace: the mu_r shift bounds must include 0");
  NullScore s;
  s.rmse_before = std::sqrt(p.residual.squaredNorm() / static_cast<double>(n));
  const BoundedFit f =
      bounded_fit(p.mu_sensitivity, nullptr, p.residual, p.sigma, p.mu_shift_lo, p.mu_shift_hi);
  s.mu_shift = f.b;
  s.rmse_fit = f.rmse;
  s.loo_rmse = bounded_loo_rmse(p.mu_sensitivity, nullptr, p.residual, p.sigma, p.mu_shift_lo,
                                p.mu_shift_hi);
  return s;
}

CandidateScore score_candidate(const TraceProblem& p, const std::string& name,
                               const Eigen::VectorXd& fp, const NullScore& null_score,
                               const AcceptanceRule& rule) {
  if (fp.size() != p.residual.size())
    throw std::invalid_argument("trace: fingerprint of " + name + " has " +
                                std::to_string(fp.size()) + " values for " +
                                std::to_string(p.residual.size()) + " tests");
  CandidateScore s;
  s.name = name;
  try {
    const BoundedFit f =
        bounded_fit(p.mu_sensitivity, &fp, p.residual, p.sigma, p.mu_shift_lo, p.mu_shift_hi);
    s.mu_shift = f.b;
    s.mu_shift_at_bound = f.at_bound;
    s.coef = f.c;
    s.coef_se = f.c_se;
    s.t = std::abs(s.coef) / s.coef_se;
    s.rmse_fit = f.rmse;
    s.loo_rmse =
        bounded_loo_rmse(p.mu_sensitivity, &fp, p.residual, p.sigma, p.mu_shift_lo, p.mu_shift_hi);
  } catch (const std::invalid_argument& e) {
    s.why = std::string("not identifiable: ") + e.what();
    s.loo_rmse = null_score.loo_rmse;
    s.rmse_fit = null_score.rmse_fit;
    return s;
  }
  s.loo_gain = null_score.loo_rmse - s.loo_rmse;
  s.explained =
      null_score.rmse_before > 0.0
          ? 1.0 - (s.rmse_fit * s.rmse_fit) / (null_score.rmse_before * null_score.rmse_before)
          : 0.0;
  const double margin = rule.loo_margin_factor * p.seed_noise_deg;
  s.significant = s.t > rule.min_t;
  s.predictive = s.loo_gain > margin;
  s.accepted = s.significant && s.predictive;
  s.why = "|c|/se = " + significant(s.t, 3) + (s.significant ? " > " : " <= ") +
          significant(rule.min_t, 3) + "; LOO gain " + significant(s.loo_gain, 3) + " deg" +
          (s.predictive ? " > " : " <= ") + "seed noise " + significant(margin, 3) + " deg";
  return s;
}

int rank_candidates(std::vector<CandidateScore>& scores) {
  std::stable_sort(
      scores.begin(), scores.end(),
      [](const CandidateScore& a, const CandidateScore& b) { return a.loo_rmse < b.loo_rmse; });
  for (std::size_t i = 0; i < scores.size(); ++i)
    if (scores[i].accepted) return static_cast<int>(i);
  return -1;
}

double rmse(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x * x;
  return v.empty() ? 0.0 : std::sqrt(s / static_cast<double>(v.size()));
}

nlohmann::json to_json(const CandidateScore& s) {
  return {{"name", s.name},
          {"coef", s.coef},
          {"coef_se", s.coef_se},
          {"t", s.t},
          {"mu_shift", s.mu_shift},
          {"mu_shift_at_bound", s.mu_shift_at_bound},
          {"rmse_fit_deg", s.rmse_fit},
          {"loo_rmse_deg", s.loo_rmse},
          {"loo_gain_deg", s.loo_gain},
          {"explained", s.explained},
          {"significant", s.significant},
          {"predictive", s.predictive},
          {"accepted", s.accepted},
          {"why", s.why},
          {"out_of_range", text_or_null(s.out_of_range)}};
}

nlohmann::json to_json(const NullScore& s) {
  return {{"mu_shift", s.mu_shift},
          {"rmse_before_deg", s.rmse_before},
          {"rmse_mu_only_deg", s.rmse_fit},
          {"loo_rmse_mu_only_deg", s.loo_rmse}};
}

CandidateScore candidate_score_from_json(const nlohmann::json& j) {
  CandidateScore s;
  s.name = field<std::string>(j, "name");
  s.coef = number_field(j, "coef");
  s.coef_se = number_field(j, "coef_se");
  s.t = number_field(j, "t");
  s.mu_shift = number_field(j, "mu_shift");
  s.mu_shift_at_bound = field<bool>(j, "mu_shift_at_bound");
  s.rmse_fit = number_field(j, "rmse_fit_deg");
  s.loo_rmse = number_field(j, "loo_rmse_deg");
  s.loo_gain = number_field(j, "loo_gain_deg");
  s.explained = number_field(j, "explained");
  s.significant = field<bool>(j, "significant");
  s.predictive = field<bool>(j, "predictive");
  s.accepted = field<bool>(j, "accepted");
  s.why = field<std::string>(j, "why");
  // Absent or null: within the range (a loop.json written before the range gate has none).
  if (j.contains("out_of_range") && !j["out_of_range"].is_null())
    s.out_of_range = field<std::string>(j, "out_of_range");
  return s;
}

NullScore null_score_from_json(const nlohmann::json& j) {
  return {number_field(j, "mu_shift"), number_field(j, "rmse_before_deg"),
          number_field(j, "rmse_mu_only_deg"), number_field(j, "loo_rmse_mu_only_deg")};
}

}  // namespace reposetwin::experiments
