#pragma once

#include <Eigen/Core>
#include <optional>

namespace calstand::core {

constexpr double kEarthRateRadPerS = 7.292115e-5;  ///< W of error-model.md [rad/s]
constexpr double kStandardGravity = 9.80665;       ///< g0 [m/s^2]

/// WGS-84 normal gravity on the ellipsoid (Somigliana closed form) [m/s^2].
double normal_gravity_ellipsoid(double latitude_deg);

/// WGS-84 normal gravity at ellipsoidal height `height_m` with the second-order free-air
/// correction (NIMA TR8350.2 eq. 4-3) [m/s^2].
double normal_gravity(double latitude_deg, double height_m);

/// Where the station stands.
struct Site {
  double latitude_deg = 0.0;
  double longitude_deg = 0.0;
  double height_m = 0.0;               ///< ellipsoidal height [m]
  std::optional<double> gravity_mps2;  ///< measured local gravity, overrides the formula

  /// Local gravity magnitude [m/s^2]: configured value, else normal_gravity().
  double gravity() const;

  /// Specific force of a body at rest in L (ENU) [m/s^2]: (0, 0, +g).
  Eigen::Vector3d specific_force_level() const;

  /// Earth rate in L [rad/s]: W (0, cos(lat), sin(lat)).
  Eigen::Vector3d earth_rate_level_radps() const;
};

}  // namespace calstand::core
