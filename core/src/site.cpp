#include "core/site.hpp"

#include <cmath>

#include "core/rotation.hpp"

namespace calstand::core {
namespace {
// WGS-84 defining and derived constants (NIMA TR8350.2, 3rd ed., tables 3.1-3.3).
constexpr double kSemiMajorAxisM = 6378137.0;
constexpr double kFlattening = 1.0 / 298.257223563;
constexpr double kGravityEquatorMps2 = 9.7803253359;
constexpr double kSomiglianaK = 0.00193185265241;
constexpr double kFirstEccentricitySquared = 6.69437999014e-3;
constexpr double kGravityRatioM = 0.00344978650684;  // omega^2 a^2 b / GM
}  // namespace

double normal_gravity_ellipsoid(double latitude_deg) {
  const double s2 = std::pow(std::sin(latitude_deg * kDegToRad), 2);
  return kGravityEquatorMps2 * (1.0 + kSomiglianaK * s2) /
         std::sqrt(1.0 - kFirstEccentricitySquared * s2);
}

double normal_gravity(double latitude_deg, double height_m) {
  const double s2 = std::pow(std::sin(latitude_deg * kDegToRad), 2);
  const double a = kSemiMajorAxisM;
  const double first_order =
      2.0 / a * (1.0 + kFlattening + kGravityRatioM - 2.0 * kFlattening * s2) * height_m;
  const double second_order = 3.0 * height_m * height_m / (a * a);
  return normal_gravity_ellipsoid(latitude_deg) * (1.0 - first_order + second_order);
}

double Site::gravity() const {
  return gravity_mps2 ? *gravity_mps2 : normal_gravity(latitude_deg, height_m);
}

Eigen::Vector3d Site::specific_force_level() const { return {0.0, 0.0, gravity()}; }

Eigen::Vector3d Site::earth_rate_level_radps() const {
  const double lat = latitude_deg * kDegToRad;
  return kEarthRateRadPerS * Eigen::Vector3d(0.0, std::cos(lat), std::sin(lat));
}

}  // namespace calstand::core
