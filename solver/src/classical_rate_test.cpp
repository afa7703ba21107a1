// Angular rate tests (seed notes, "angular rate test"): the table turns the sensing axis by a
// precisely known angle or at a known rate, in both directions, so bias and scale separate the
// same way as in the two-position test. The Earth-rate component along the axis is part of the
// reference and is scaled by (1+s) like the table motion, which the seed's closed form drops.

#include <fmt/format.h>

#include <cmath>
#include <set>

#include "classical_common.hpp"
#include "core/error.hpp"
#include "solver/classical.hpp"

namespace calstand::solver {

namespace {}  // namespace

RateTestResult rate_test_cw_ccw(double angle_cw_deg, double angle_ccw_deg,
                                double reference_angle_deg, double duration_s,
                                double earth_rate_component_dps, double angle_sigma_deg) {
  constexpr const char* kWhere = "rate_test_cw_ccw";
  detail::require_finite(angle_cw_deg, kWhere, "angle_cw");
  detail::require_finite(angle_ccw_deg, kWhere, "angle_ccw");
  detail::require_finite(reference_angle_deg, kWhere, "reference_angle");
  detail::require_finite(duration_s, kWhere, "duration");
  detail::require_finite(earth_rate_component_dps, kWhere, "earth_rate_component");
  detail::require_sigma(angle_sigma_deg, kWhere, "angle_sigma");
  if (reference_angle_deg == 0.0) {
    throw core::InputError(kWhere, "reference_angle is 0 deg: the turns must reverse an angle");
  }
  if (duration_s <= 0.0) {
    throw core::InputError(kWhere, fmt::format("duration {} s must be positive", duration_s));
  }
  // Seed: angle_cw = (1+s)(theta + W_z t) + b t, angle_ccw = (1+s)(-theta + W_z t) + b t.
  const double one_plus_s = (angle_cw_deg - angle_ccw_deg) / (2.0 * reference_angle_deg);
  RateTestResult r;
  r.scale_ppm = 1e6 * (one_plus_s - 1.0);
  r.bias_dps =
      (angle_cw_deg + angle_ccw_deg) / (2.0 * duration_s) - one_plus_s * earth_rate_component_dps;
  if (angle_sigma_deg > 0.0) {
    // d(1+s) = (e1 - e2) / (2 theta); db = (e1 + e2) / (2t) - W_z d(1+s). The sum and the
    // difference of two independent errors are uncorrelated, so the variances add.
    const double s_sum = angle_sigma_deg * std::sqrt(2.0);
    const double sd_scale = s_sum / (2.0 * std::abs(reference_angle_deg));
    r.scale_sigma_ppm = 1e6 * sd_scale;
    r.bias_sigma_dps = std::hypot(s_sum / (2.0 * duration_s), earth_rate_component_dps * sd_scale);
    r.sigma_source = SigmaSource::kGiven;
  }
  return r;
}

RateTestResult rate_test_cw_ccw_rates(double rate_pos_dps, double rate_neg_dps,
                                      double table_rate_dps, double earth_rate_component_dps,
                                      double mean_sigma_dps) {
  constexpr const char* kWhere = "rate_test_cw_ccw_rates";
  detail::require_finite(rate_pos_dps, kWhere, "rate_pos");
  detail::require_finite(rate_neg_dps, kWhere, "rate_neg");
  detail::require_finite(table_rate_dps, kWhere, "table_rate");
  if (table_rate_dps == 0.0) {
    throw core::InputError(kWhere, "table_rate is 0 deg/s: the steps must reverse a rate");
  }
  // A mean rate over time t is an integrated angle over t: the same algebra with t = 1 s.
  RateTestResult r = rate_test_cw_ccw(rate_pos_dps, rate_neg_dps, table_rate_dps, 1.0,
                                      earth_rate_component_dps, mean_sigma_dps);
  return r;
}

RateTestResult rate_steps(const std::vector<RateStep>& steps, double earth_rate_component_dps,
                          double mean_sigma_dps) {
  constexpr const char* kWhere = "rate_steps";
  detail::require_finite(earth_rate_component_dps, kWhere, "earth_rate_component");
  detail::require_sigma(mean_sigma_dps, kWhere, "mean_sigma");
  std::set<double> distinct;
  for (const RateStep& s : steps) {
    detail::require_finite(s.table_rate_dps, kWhere, "table_rate");
    detail::require_finite(s.gyro_mean_dps, kWhere, "gyro_mean");
    distinct.insert(s.table_rate_dps);
  }
  if (distinct.size() < 2) {
    throw core::InputError(kWhere, fmt::format("{} distinct table rates in {} steps, need at "
                                               "least 2 to separate bias and scale",
                                               distinct.size(), steps.size()));
  }
  // gyro = b + (1+s) x with x = r + W_z: a straight line, fitted about the mean of x so slope
  // and intercept come out uncorrelated and without cancellation.
  const auto n = static_cast<double>(steps.size());
  double x_mean = 0.0;
  double y_mean = 0.0;
  for (const RateStep& s : steps) {
    x_mean += (s.table_rate_dps + earth_rate_component_dps) / n;
    y_mean += s.gyro_mean_dps / n;
  }
  double sxx = 0.0;
  double sxy = 0.0;
  for (const RateStep& s : steps) {
    const double dx = s.table_rate_dps + earth_rate_component_dps - x_mean;
    sxx += dx * dx;
    sxy += dx * (s.gyro_mean_dps - y_mean);
  }
  const double slope = sxy / sxx;
  const double intercept = y_mean - slope * x_mean;
  RateTestResult r;
  r.scale_ppm = 1e6 * (slope - 1.0);
  r.bias_dps = intercept;

  double sigma = mean_sigma_dps;
  if (sigma > 0.0) {
    r.sigma_source = SigmaSource::kGiven;
  } else if (steps.size() > 2) {
    double ssr = 0.0;
    for (const RateStep& s : steps) {
      const double res =
          s.gyro_mean_dps - intercept - slope * (s.table_rate_dps + earth_rate_component_dps);
      ssr += res * res;
    }
    sigma = std::sqrt(ssr / (n - 2.0));
    r.sigma_source = SigmaSource::kResidualScatter;
  }
  // Textbook line-fit variances: var(slope) = s^2 / Sxx, var(b) = s^2 (1/n + x_mean^2 / Sxx).
  r.scale_sigma_ppm = 1e6 * sigma / std::sqrt(sxx);
  r.bias_sigma_dps = sigma * std::sqrt(1.0 / n + x_mean * x_mean / sxx);
  return r;
}

}  // namespace calstand::solver
