#include "core/site.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/rotation.hpp"

namespace calstand::core {
namespace {

// Published WGS-84 normal gravity values (NIMA TR8350.2, 3rd ed., table 3.4 and eq. 4-1):
// equator 9.7803253359, pole 9.8321849378 m/s^2.
TEST(NormalGravity, MatchesPublishedWgs84Values) {
  EXPECT_NEAR(normal_gravity_ellipsoid(0.0), 9.7803253359, 1e-9);
  EXPECT_NEAR(normal_gravity_ellipsoid(90.0), 9.8321849378, 1e-9);
  EXPECT_NEAR(normal_gravity_ellipsoid(-90.0), 9.8321849378, 1e-9);
  // GRS80 tabulates 9.806199203 m/s^2 at 45 deg; WGS-84's equatorial gravity is 1.4356e-6 m/s^2
  // lower than GRS80's (9.7803267715), and at 45 deg the two differ by that much again scaled by
  // the latitude factor (~1.0000), so WGS-84 gives 9.8061977.
  EXPECT_NEAR(normal_gravity_ellipsoid(45.0), 9.8061977, 1e-7);
}

TEST(NormalGravity, FreeAirGradientIsAbout3086MicroGalPerMetre) {
  // The normal free-air gradient is -0.3086 mGal/m = -3.086e-6 s^-2 at mid latitudes.
  const double gradient = (normal_gravity(45.0, 1000.0) - normal_gravity(45.0, 0.0)) / 1000.0;
  EXPECT_NEAR(gradient, -3.086e-6, 0.01e-6);
  EXPECT_DOUBLE_EQ(normal_gravity(30.0, 0.0), normal_gravity_ellipsoid(30.0));
}

TEST(Site, ConfiguredGravityOverridesTheFormula) {
  Site site{30.53, 114.35, 20.0, std::nullopt};
  EXPECT_NEAR(site.gravity(), normal_gravity(30.53, 20.0), 1e-12);
  site.gravity_mps2 = 9.7936;
  EXPECT_DOUBLE_EQ(site.gravity(), 9.7936);
  EXPECT_EQ(site.specific_force_level(), Eigen::Vector3d(0.0, 0.0, 9.7936));
}

TEST(Site, EarthRateProjectsOntoNorthAndUp) {
  Site site;
  site.latitude_deg = 30.0;
  const Eigen::Vector3d w = site.earth_rate_level_radps();
  EXPECT_DOUBLE_EQ(w.x(), 0.0);
  EXPECT_NEAR(w.y(), 7.292115e-5 * std::sqrt(3.0) / 2.0, 1e-18);
  EXPECT_NEAR(w.z(), 7.292115e-5 * 0.5, 1e-18);
  EXPECT_NEAR(w.norm(), kEarthRateRadPerS, 1e-18);
  // 15.041 deg/h in total, the familiar figure.
  EXPECT_NEAR(w.norm() * kRadToDeg * 3600.0, 15.041, 1e-3);
  site.latitude_deg = -30.0;
  EXPECT_LT(site.earth_rate_level_radps().z(), 0.0);  // southern hemisphere: pointing down
}

}  // namespace
}  // namespace calstand::core
