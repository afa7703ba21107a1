#pragma once

#include <cstddef>

#include "noise/allan.hpp"

namespace calstand::solver {

/// Order d of the phase differences of `kind`: 2 for the Allan and modified Allan variances, 3
/// for the Hadamard ones; also the most differences the lag-1 noise identification takes for it
/// (identify_noise_lag1(), dmax).
int difference_order(AllanKind kind);

/// Range of noise exponents alpha for which the estimator `kind` converges (alpha + 2d > 1,
/// d = 2 for Allan and modified, 3 for Hadamard): [-2, 2] or [-4, 2].
int min_alpha(AllanKind kind);
constexpr int kMaxAlpha = 2;

/// Equivalent degrees of freedom of the overlapping estimator `kind` at averaging factor m on
/// `samples` rate samples, for power-law noise S_y(f) ~ f^alpha.
///
/// Greenhall and Riley's method ("Uncertainty of stability variances based on finite
/// differences", PTTI 2003; the algorithm behind NIST SP 1065's EDF tables): the variance of
/// the estimator is a double sum over the autocovariance of the difference sequence, which for
/// power-law noise follows from the generalised structure function. With J = min(terms,
/// (d + 1) m) lags it is summed exactly up to a few hundred lags; beyond that the sum is a
/// Riemann sum of a smooth function and is replaced by its integral (adaptive quadrature),
/// which is what the paper's tables tabulate. Returns at least 1.
///
/// Throws core::InputError when alpha is outside [min_alpha(kind), 2], m is 0 or the data are
/// too short for m (no difference term).
double equivalent_dof(AllanKind kind, int alpha, std::size_t m, std::size_t samples);

/// A confidence interval of a deviation.
struct DeviationInterval {
  double lo = 0.0;  ///< [unit of the deviation]
  double hi = 0.0;
};

/// The two-sided interval of probability `confidence` for a deviation estimate with `edf`
/// degrees of freedom: edf * s^2 / chi2 quantiles, (1 + c)/2 and (1 - c)/2, rooted (Boost.Math
/// chi-square, non-integer degrees of freedom allowed). Throws core::InputError for
/// confidence outside (0, 1), edf <= 0 or a negative deviation.
DeviationInterval deviation_interval(double deviation, double edf, double confidence);

}  // namespace calstand::solver
