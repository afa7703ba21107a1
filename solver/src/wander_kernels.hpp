#pragma once
// The wander processes a run's step means are tried against, and one channel's regression on
// them: shared by the noise model the fits are weighted with (noise_estimate.cpp) and by the
// choice between a deterministic term and a wander (effect_or_wander.cpp), so that both weigh
// the same processes on the same rows.

#include <Eigen/Core>
#include <vector>

#include "solver/step_noise.hpp"
#include "solver/step_summary.hpp"

namespace calstand::solver::detail {

/// A wander process of unit amplitude (its variance parameter 1: sigma^2, B^2 or K^2) and the
/// eigen-decomposition of its step-mean covariance scaled by the step counts,
/// G = N^1/2 K N^1/2 = U diag(lambda) U^T, which turns every trial of amplitude into diagonal
/// arithmetic and serves all channels at once (their white parts differ only by a factor).
struct Kernel {
  WanderModel unit;
  Eigen::VectorXd lambda;
  Eigen::MatrixXd U;
  double mean_variance = 1.0;  ///< mean of K's diagonal: one step mean's wander variance
  int parameters = 1;          ///< of the wander: amplitude, and tau for Gauss-Markov
};

/// Every wander tried on a set of step means: first-order Gauss-Markov on a grid of correlation
/// times from a step's length to beyond the run, flicker, random walk; and the alternative that
/// is no wander, an extra variance of each step mean on its own.
struct WanderKernels {
  std::vector<Kernel> wanders;
  Kernel independent;
  double typical_count = 1.0;  ///< median samples per step mean
};
WanderKernels make_wander_kernels(const std::vector<StepSummary>& steps);

/// One channel's regression: N^1/2 X and N^1/2 y (X: the design's columns that act on the
/// channel, normalised and reduced to full rank), and its white variance per sample.
struct ChannelProblem {
  Eigen::MatrixXd Xs;
  Eigen::VectorXd ys;
  double white = 1.0;
  int parameters = 0;
};

/// The problem of `channel` over `steps` with the regressor columns `columns` of the steps'
/// summaries and, when given, `extra` (steps x k: further columns on this channel).
ChannelProblem channel_problem(const std::vector<StepSummary>& steps,
                               const std::vector<Eigen::Index>& columns, int channel, double white,
                               const Eigen::MatrixXd* extra = nullptr);

/// Which likelihood an amplitude maximises. The restricted one (REML) estimates the noise of
/// one design without the bias of the parameters it fits; the profile one (the full likelihood
/// with the parameters at their GLS values) compares two designs, which REML cannot: the
/// restricted likelihoods of two designs are likelihoods of different data (the contrasts each
/// design leaves).
enum class Likelihood { kRestricted, kProfile };

struct Trial {
  double log_likelihood = 0.0;
  double amplitude = 0.0;  ///< the wander's variance parameter
};

/// The best amplitude of `kernel` for one channel: a grid over the ratio of its variance to a
/// typical step mean's white variance, then Brent's method between the best point's neighbours.
Trial best_amplitude(const Kernel& kernel, const ChannelProblem& p, double typical_count,
                     Likelihood likelihood);

/// The log likelihood of the channel with white noise alone.
double white_log_likelihood(const ChannelProblem& p, Likelihood likelihood);

/// The kernel of a wander known in full (its amplitude given: `wander` as it is), for the
/// likelihood of a channel under it (known_log_likelihood()).
Kernel known_kernel(const WanderModel& wander, const std::vector<StepSummary>& steps);

/// The log likelihood of the channel with white noise and `kernel`'s process at its own
/// amplitude (a known_kernel()).
double known_log_likelihood(const Kernel& kernel, const ChannelProblem& p, Likelihood likelihood);

/// `kernel`'s process with the fitted amplitude.
WanderModel with_amplitude(const Kernel& kernel, double amplitude);

}  // namespace calstand::solver::detail
