#pragma once
// The comparison the real-driver tests make: a fit through the protocols against the same
// procedure's fit on the in-process simulator, both against the known IMU's truth.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <string>

#include "known_imu_station.hpp"

namespace calstand::testing {

/// Both fits within `k` sigma of the truth, parameter by parameter; and the real drivers' fit
/// as good as the in-process one: chi2/dof, and the RMS of the normalised errors (about 1 for an
/// honest fit; each run has its own noise, so they are compared loosely).
inline void expect_same_quality(const nlohmann::json& in_process, const nlohmann::json& real,
                                double k) {
  ASSERT_EQ(in_process["parameters"].size(), real["parameters"].size());
  auto rms_z = [&](const nlohmann::json& fit, const char* which) {
    double sum = 0.0;
    for (const auto& p : fit["parameters"]) {
      const std::string name = p["name"];
      const double z =
          (p["value"].get<double>() - known_imu_truth(name)) / p["sigma"].get<double>();
      EXPECT_LT(std::abs(z), k) << name << " (" << which << ")";
      sum += z * z;
    }
    return std::sqrt(sum / static_cast<double>(fit["parameters"].size()));
  };
  const double in_process_rms = rms_z(in_process, "in process");
  const double real_rms = rms_z(real, "real drivers");
  // A floor of 2: with some 24 degrees of freedom chi2/dof passes 2 by chance at p ~ 0.002,
  // and an in-process run that came out low by chance (0.35) must not make the bar 1.2.
  EXPECT_LT(real["chi2_dof"].get<double>(),
            std::max(2.0 * in_process["chi2_dof"].get<double>() + 0.5, 2.0))
      << "in process " << in_process["chi2_dof"] << ", real drivers " << real["chi2_dof"];
  EXPECT_LT(real_rms, std::max(2.0 * in_process_rms, 2.0))
      << "in process " << in_process_rms << ", real drivers " << real_rms;
}

}  // namespace calstand::testing
