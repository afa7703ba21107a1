// Twelve-position calibration: each body axis up and down at two headings 180 deg apart
// (seed notes, "12-position method"). Gravity calibrates the accelerometers as in the
// six-position test, with redundancy; the Earth rate, whose horizontal component reverses
// between the two headings, calibrates the gyros (weakly: W is 0.004 deg/s).

#include <fmt/format.h>

#include "classical_common.hpp"
#include "core/error.hpp"
#include "core/rotation.hpp"
#include "core/site.hpp"
#include "core/table_geometry.hpp"
#include "solver/classical.hpp"

namespace calstand::solver {

std::array<TableAngles, 12> twelve_position_table_angles() {
  // Outer axis North (horizontal), inner axis Up at outer 0: C_LB = R_N(outer) R_U(inner).
  // Pairs differ by a half turn about the vertical (heading 0 and 180).
  return {{
      {0.0, 0.0},
      {0.0, 180.0},  // z up
      {180.0, 0.0},
      {180.0, 180.0},  // z down
      {-90.0, 0.0},
      {90.0, 180.0},  // x up
      {90.0, 0.0},
      {-90.0, 180.0},  // x down
      {-90.0, -90.0},
      {90.0, 90.0},  // y up
      {90.0, -90.0},
      {-90.0, 90.0},  // y down
  }};
}

std::array<Eigen::Matrix3d, 12> twelve_position_attitudes(double second_heading_deg) {
  const core::TableGeometry table;  // the typical table: outer North, inner Up at zero
  const std::array<TableAngles, 12> angles = twelve_position_table_angles();
  const Eigen::Matrix3d turn =
      core::axis_angle(Eigen::Vector3d::UnitZ(), second_heading_deg * core::kDegToRad);
  std::array<Eigen::Matrix3d, 12> out;
  for (std::size_t k = 0; k < 12; k += 2) {
    out[k] = table.body_to_level(angles[k].outer_deg, angles[k].inner_deg);
    out[k + 1] = turn * out[k];  // a turn about Up keeps gravity in B, moves the Earth rate
  }
  return out;
}

TwelvePositionResult twelve_position(const std::vector<StaticPosition>& positions,
                                     double gravity_mps2,
                                     const Eigen::Vector3d& earth_rate_level_dps,
                                     const TwelvePositionOptions& options) {
  constexpr const char* kWhere = "twelve_position";
  if (positions.size() != 12) {
    throw core::InputError(kWhere, fmt::format("{} positions given, need exactly 12 (use "
                                               "multi_position for another count)",
                                               positions.size()));
  }
  detail::require_finite(gravity_mps2, kWhere, "gravity");
  detail::require_finite(earth_rate_level_dps, kWhere, "earth_rate_level");
  if (gravity_mps2 <= 0.0) {
    throw core::InputError(kWhere, fmt::format("gravity {} m/s^2 must be positive", gravity_mps2));
  }
  constexpr int kN = 12;
  Eigen::Matrix3Xd u_accel(3, kN);
  Eigen::Matrix3Xd u_gyro(3, kN);
  Eigen::Matrix4Xd a_accel(4, kN);
  Eigen::Matrix4Xd a_gyro(4, kN);
  const Eigen::Vector3d f_level(0.0, 0.0, gravity_mps2);  // specific force at rest, ENU
  for (int k = 0; k < kN; ++k) {
    const StaticPosition& p = positions[static_cast<std::size_t>(k)];
    detail::require_finite(p.C_LB, kWhere, fmt::format("position {} attitude", k));
    const Eigen::Matrix3d C_BL = p.C_LB.transpose();
    u_accel.col(k) = p.accel_mps2;
    u_gyro.col(k) = p.gyro_dps;
    a_accel.col(k) << C_BL * f_level, 1.0;
    a_gyro.col(k) << C_BL * earth_rate_level_dps, 1.0;
  }

  TwelvePositionResult r;
  r.accel = multi_position(u_accel, a_accel, options.accel);
  if (!options.fit_gyro_g_sensitivity) {
    r.gyro = multi_position(u_gyro, a_gyro, options.gyro);
    return r;
  }
  // gyro = (I+S+Mis) w + b + G f/g0: append f/g0 to the design (contract: G per g0, not per g).
  Eigen::MatrixXd a_full(7, kN);
  a_full.topRows(4) = a_gyro;
  a_full.bottomRows(3) = a_accel.topRows(3) / core::kStandardGravity;
  static const std::vector<std::string> kNames{"w_x", "w_y", "w_z", "bias", "f_x", "f_y", "f_z"};
  const detail::RowLeastSquares ls =
      detail::solve_rows(u_gyro, a_full, kNames, options.gyro.max_condition_number, kWhere);
  r.gyro = detail::pack_matrix_calibration(ls.X, ls.cov_base, u_gyro, a_full, ls.condition_number,
                                           options.gyro);
  Eigen::Matrix3d g_sens = ls.X.rightCols(3);
  Eigen::Matrix3d g_sigma;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      g_sigma(i, j) = r.gyro.measurement_sigma(i) * std::sqrt(ls.cov_base(4 + j, 4 + j));
    }
  }
  r.gyro_g_sensitivity = g_sens;
  r.gyro_g_sensitivity_sigma = g_sigma;
  return r;
}

}  // namespace calstand::solver
