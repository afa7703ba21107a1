#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "solver/classical.hpp"

/// Thermal calibration (issue 4, "per-plateau fits and a polynomial of the chosen order in
/// temperature"): a parameter estimated on each temperature plateau (e.g. a bias by a static
/// fit at that plateau) is fitted by a weighted polynomial in dT = T - T_ref. The coefficients
/// map onto the contract's temperature terms: for a bias, c_0 is `<sensor>_bias.<axis>` at
/// T_ref and c_k (k >= 1) is `<sensor>_temp_bias.<axis>k` [unit/degC^k]; for a scale factor,
/// c_0 is `<sensor>_scale.<axis>` [ppm] and c_1 is `<sensor>_temp_scale.<axis>` [ppm/degC]
/// (the contract has only a linear temperature scale term).
/// Pure functions, thread safe. Errors throw core::InputError naming the function and the fault.
namespace calstand::solver {

/// One plateau's estimate of one parameter.
struct ThermalPoint {
  double temperature_c = 0.0;  ///< plateau temperature [degC]
  double value = 0.0;          ///< the parameter on this plateau [its unit]
  double sigma = 0.0;          ///< 1-sigma of value (> 0) [its unit]
};

/// Weighted polynomial fit value(T) = sum_{k=0..order} c_k dT^k.
struct ThermalPolynomial {
  double temperature_ref_c = 25.0;
  int order = 1;
  Eigen::VectorXd coefficients;  ///< c_0..c_order [unit/degC^k]
  Eigen::VectorXd sigmas;        ///< 1-sigma of each c_k [unit/degC^k]
  Eigen::MatrixXd covariance;    ///< of c_0..c_order
  Eigen::VectorXd residuals;     ///< value - fit per point, in input order [unit]
  int dof = 0;                   ///< points - (order + 1)
  double chi2_dof = 0.0;         ///< sum (residual/sigma)^2 / dof; 0 when dof == 0
  /// True when the covariance was multiplied by chi2_dof (ThermalOptions::scale_by_chi2).
  bool scaled_by_chi2 = false;

  /// The polynomial at temperature_c [unit].
  double evaluate(double temperature_c) const;
};

/// Options of thermal_polynomial().
struct ThermalOptions {
  double temperature_ref_c = 25.0;  ///< T_ref of dT [degC] (the contract's default)
  /// Multiply the covariance by chi2_dof when dof > 0 and chi2_dof > 1, for plateau sigmas that
  /// are known to be optimistic. Off by default: the plateau sigmas are taken as honest.
  bool scale_by_chi2 = false;
};

/// Weighted least squares of the points' values on 1, dT, .., dT^order (weights 1/sigma^2).
/// Throws core::InputError when order < 0, when order >= the number of plateaus (message names
/// both, e.g. "order 3 needs at least 4 temperature plateaus, 3 given"), when fewer than
/// order + 1 distinct temperatures are given, or for a non-finite value or sigma <= 0.
ThermalPolynomial thermal_polynomial(const std::vector<ThermalPoint>& points, int order,
                                     const ThermalOptions& options = {});

/// One plateau: every parameter estimated there, by contract name (e.g. "gyro_bias.x",
/// "accel_scale.z") with its value and sigma in contract units.
struct ThermalPlateau {
  double temperature_c = 0.0;
  std::vector<ClassicalEstimate> parameters;
};

/// Fits each parameter present in the plateaus with thermal_polynomial() and names the result
/// in the contract's terms: for `<s>_bias.<a>` the estimates `<s>_bias.<a>` (c_0) and
/// `<s>_temp_bias.<a>1..<a>N`; for `<s>_scale.<a>` (order must be 1) `<s>_scale.<a>` and
/// `<s>_temp_scale.<a>`. Units follow the contract, e.g. "deg/s/degC^2".
/// Throws core::InputError for a parameter without a temperature term in the contract, a
/// parameter missing on some plateau, or any thermal_polynomial() error (prefixed with the
/// parameter's name).
std::vector<ClassicalEstimate> thermal_calibration(const std::vector<ThermalPlateau>& plateaus,
                                                   int order, const ThermalOptions& options = {});

}  // namespace calstand::solver
