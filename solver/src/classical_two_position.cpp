// Two-position static calibration of one axis (seed notes, "two-position static calibration"
// and its tilted variant): the up/down pair reverses the reference, so half the sum is the bias
// and half the difference is (1+s) times the reference.

#include <fmt/format.h>

#include <cmath>

#include "classical_common.hpp"
#include "core/error.hpp"
#include "solver/classical.hpp"

namespace calstand::solver {

namespace {

// up = b + (1+s) r, down = b - (1+s) r with the reference r already projected on the axis.
TwoPositionResult solve_pair(double up, double down, double reference, double mean_sigma) {
  TwoPositionResult r;
  r.bias = 0.5 * (up + down);
  r.scale_ppm = 1e6 * ((up - down) / (2.0 * reference) - 1.0);
  // Each estimate is a half sum or half difference of two independent means.
  r.bias_sigma = mean_sigma / std::sqrt(2.0);
  r.scale_sigma_ppm = 1e6 * mean_sigma / (std::sqrt(2.0) * std::abs(reference));
  return r;
}

}  // namespace

TwoPositionResult two_position(double f_up_mps2, double f_down_mps2, double gravity_mps2,
                               double tilt_rad, double mean_sigma) {
  constexpr const char* kWhere = "two_position";
  detail::require_finite(f_up_mps2, kWhere, "f_up");
  detail::require_finite(f_down_mps2, kWhere, "f_down");
  detail::require_finite(gravity_mps2, kWhere, "gravity");
  detail::require_finite(tilt_rad, kWhere, "tilt_rad");
  detail::require_sigma(mean_sigma, kWhere, "mean_sigma");
  if (gravity_mps2 <= 0.0) {
    throw core::InputError(kWhere, fmt::format("gravity {} m/s^2 must be positive", gravity_mps2));
  }
  const double projected = gravity_mps2 * std::cos(tilt_rad);
  // Near 90 deg the axis is horizontal: the pair no longer reverses any reference.
  if (projected < 1e-3 * gravity_mps2) {
    throw core::InputError(
        kWhere, fmt::format("tilt {} rad leaves no gravity along the axis (need |tilt| < 90 deg)",
                            tilt_rad));
  }
  return solve_pair(f_up_mps2, f_down_mps2, projected, mean_sigma);
}

TwoPositionResult two_position_gyro(double w_up_dps, double w_down_dps,
                                    double earth_rate_component_dps, double mean_sigma) {
  constexpr const char* kWhere = "two_position_gyro";
  detail::require_finite(w_up_dps, kWhere, "w_up");
  detail::require_finite(w_down_dps, kWhere, "w_down");
  detail::require_finite(earth_rate_component_dps, kWhere, "earth_rate_component");
  detail::require_sigma(mean_sigma, kWhere, "mean_sigma");
  if (earth_rate_component_dps == 0.0) {
    throw core::InputError(kWhere,
                           "earth_rate_component is 0 deg/s: the up/down pair reverses nothing "
                           "(an East-pointing axis, or the equator for a vertical one)");
  }
  return solve_pair(w_up_dps, w_down_dps, earth_rate_component_dps, mean_sigma);
}

}  // namespace calstand::solver
