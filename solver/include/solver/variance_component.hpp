#pragma once
// One variance component by restricted maximum likelihood (REML), shared by the two noise
// models that need it: the step means of a table fit (noise_estimate.cpp) and the static pose
// means of a calibration without a table (pose_noise.cpp). Both whiten their residuals by the
// white noise, so that the covariance is white * (I + rho G) for a kernel G of unit amplitude;
// G's eigen-decomposition turns every trial of rho into diagonal arithmetic.

#include <Eigen/Core>
#include <functional>
#include <limits>

namespace calstand::solver::detail {

/// G = U diag(lambda) U^T of a symmetric kernel (negative rounding of lambda clipped to 0).
struct KernelBasis {
  Eigen::VectorXd lambda;
  Eigen::MatrixXd U;
};
KernelBasis kernel_basis(const Eigen::MatrixXd& G);

/// Restricted log likelihood (up to a constant shared by every trial) of whitened residuals
/// with covariance white * (I + rho diag(lambda)) in the kernel's eigenbasis, for the design
/// Xh and residuals yh projected on it (U^T X, U^T y). -inf when X^T C^-1 X is singular.
double restricted_log_likelihood(const Eigen::VectorXd& lambda, const Eigen::MatrixXd& Xh,
                                 const Eigen::VectorXd& yh, double white, double rho);

/// Profile log likelihood (the full likelihood with the design's parameters at their GLS
/// values, up to the same constant): restricted_log_likelihood() without log det(X^T C^-1 X),
/// for comparing designs (see wander_kernels.hpp).
double profile_log_likelihood(const Eigen::VectorXd& lambda, const Eigen::MatrixXd& Xh,
                              const Eigen::VectorXd& yh, double white, double rho);

/// The best log10 of the variance ratio r over [-3, 4] (below, the component changes no
/// weight; above, white noise would not matter): a grid of 15, then Brent's method between the
/// best point's neighbours (the likelihood is unimodal in log r there). `log_likelihood` of r.
struct RatioFit {
  double log10_ratio = 0.0;
  double log_likelihood = -std::numeric_limits<double>::infinity();
};
RatioFit best_log10_ratio(const std::function<double(double)>& log_likelihood);

}  // namespace calstand::solver::detail
