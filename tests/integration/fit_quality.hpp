#pragma once
// The comparison the real-driver tests make: a fit through the protocols against the same
// procedure's fit on the in-process simulator, both against the known IMU's truth.

#include <gtest/gtest.h>

#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/normal.hpp>
#include <cmath>
#include <nlohmann/json.hpp>
#include <string>

#include "known_imu_station.hpp"

namespace calstand::testing {

/// How rarely chance alone may fail a bar of the comparison.
inline constexpr double kChanceP = 1e-4;

/// Both fits within `k` sigma of the truth, parameter by parameter; and the real drivers' fit
/// as good as the in-process one: chi2/dof, and the RMS of the normalised errors (about 1 for an
/// honest fit; each run has its own noise, so they are compared loosely).
inline void expect_same_quality(const nlohmann::json& in_process, const nlohmann::json& real,
                                double k) {
  ASSERT_EQ(in_process["parameters"].size(), real["parameters"].size());
  // Each of a fit's n parameters is within k sigma, or within what chance alone passes at
  // p = kChanceP over n normal errors (4.5 sigma for 12): a fixed 4 sigma failed one honest
  // fit in 100 of 12 parameters, and the suite makes a dozen such fits.
  const double n = static_cast<double>(real["parameters"].size());
  const double z_bar =
      std::max(k, boost::math::quantile(boost::math::complement(
                      boost::math::normal_distribution<>(), kChanceP / (2.0 * n))));
  auto rms_z = [&](const nlohmann::json& fit, const char* which) {
    double sum = 0.0;
    for (const auto& p : fit["parameters"]) {
      const std::string name = p["name"];
      const double z =
          (p["value"].get<double>() - known_imu_truth(name)) / p["sigma"].get<double>();
      EXPECT_LT(std::abs(z), z_bar) << name << " (" << which << ")";
      sum += z * z;
    }
    return std::sqrt(sum / static_cast<double>(fit["parameters"].size()));
  };
  const double in_process_rms = rms_z(in_process, "in process");
  const double real_rms = rms_z(real, "real drivers");
  // The bar: twice the in-process figure (the real path may add a little), and never below
  // what chance alone reaches at p = 1e-4 with the fit's own degrees of freedom. A fixed floor
  // of 2 suited a thermal fit's ~24 degrees of freedom; a six-position's 6 pass 3 at p = 0.005,
  // which across the suite's eight real-driver six-positions failed one CI in 25.
  const double dof = real["dof"].get<double>();
  const double chance_bar =
      dof > 0 ? boost::math::quantile(boost::math::complement(
                    boost::math::chi_squared_distribution<double>(dof), kChanceP)) /
                    dof
              : 2.0;
  EXPECT_LT(real["chi2_dof"].get<double>(),
            std::max(2.0 * in_process["chi2_dof"].get<double>() + 0.5, chance_bar))
      << "in process " << in_process["chi2_dof"] << ", real drivers " << real["chi2_dof"]
      << " over " << dof << " degrees of freedom";
  EXPECT_LT(real_rms, std::max(2.0 * in_process_rms, 2.0))
      << "in process " << in_process_rms << ", real drivers " << real_rms;
}

}  // namespace calstand::testing
