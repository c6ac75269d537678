// A candidate fitted jointly with mu_r on simulated surfaces, not linearised at one grid point.
// Plain numbers in, a JointScore out (loop_decision.hpp), so the decision reads it as it reads
// the linear trace's scores.
//
// Design note. The linear trace (loop_decision.hpp) writes the residual at the calibrated mu_r
// as b s + c f: the model's slope against mu_r and the candidate's fingerprint, both taken at
// one grid point. That holds while the effect and mu_r act the same at every mu_r. They do not
// when an effect that mu_r can partly mimic is strong: with rods hidden at mu_r 0.25, mu_r alone
// climbs to the declared range's end (0.4), and there the rods' fingerprint fits the residual
// worst of five; at 0.25 they move H and D differently. So each candidate is fitted on
// surfaces: the model's prediction P(mu) and the fingerprint F(mu) are known at every mu_r
// sample across the grid (F simulated at every grid point, interpolated between them), and
//     chi^2(mu, c) = sum over channels and tests of ((obs - P(mu) - c F(mu)) / sigma)^2
// is minimised over mu on the samples with c in closed form at each (c = F.y / F.F, rows over
// sigma). Every sample is tried, so a second minimum cannot hide behind a first. The standard
// error of c is the Gauss-Newton one of the pair (mu, c) at the minimum, where mu and c trade
// against each other, or of c alone when mu sits on the grid's end (as the linear bounded fit
// does). Leave-one-test-out refits (mu, c) without the test and predicts its rows.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "experiments/loop/loop_decision.hpp"

namespace reposetwin::experiments {

/// One observable over the traced tests, the current model's prediction at every mu_r sample.
struct SurfaceChannel {
  std::string name;           // "angle", "H", "D", "crest"
  Eigen::VectorXd observed;   // (n) the lab's value [units]
  Eigen::VectorXd sigma;      // (n) 1-sigma noise of the residual [units]
  Eigen::MatrixXd predicted;  // (K x n) the model at mu sample k [units]
};

/// The channels traced together on K samples of mu_r.
struct SurfaceProblem {
  std::vector<double> mu;  // (K >= 2) ascending samples across the grid [-]
  double mu_fit = 0.0;     // the current calibration; JointScore::mu_shift is relative to it [-]
  std::vector<SurfaceChannel> channels;
};

/// A candidate's fingerprint on the samples: per channel, (K x n) the change it makes [units].
using SurfaceFingerprint = std::vector<Eigen::MatrixXd>;

/// The candidate fitted jointly with mu_r (design note); `f` empty: mu_r alone. Throws
/// std::invalid_argument for mismatched sizes, fewer than 3 tests or 2 samples.
JointScore score_joint_on_surfaces(const SurfaceProblem& p, const std::string& name,
                                   const SurfaceFingerprint& f);

/// The offset hypothesis on the surfaces: ones on the first channel (the angle), zeros on the
/// others, at every mu_r.
JointScore score_offset_on_surfaces(const SurfaceProblem& p);

/// `nodes` (ascending grid points) and `values` (one per node, NaN where unknown) interpolated
/// linearly at m, held constant beyond the outermost known nodes; NaN when none is known.
double interpolate_on_nodes(const std::vector<double>& nodes, const std::vector<double>& values,
                            double m);

}  // namespace reposetwin::experiments
