// Six-position least squares in the seed's matrix form (seed notes, "six-position method,
// least squares form"): U = M A with M = [I+S+Mis | b] and A's columns [reference; 1], solved
// as M = U A^T (A A^T)^-1. Kept literally so tests can compare it with multi_position(), which
// solves the same problem by an SVD.

#include <fmt/format.h>

#include <Eigen/LU>

#include "classical_common.hpp"
#include "core/error.hpp"
#include "solver/classical.hpp"

namespace calstand::solver {

Eigen::Matrix<double, 4, 6> six_position_design(double reference) {
  Eigen::Matrix<double, 4, 6> A = Eigen::Matrix<double, 4, 6>::Zero();
  for (int axis = 0; axis < 3; ++axis) {
    A(axis, 2 * axis) = reference;       // +axis up
    A(axis, 2 * axis + 1) = -reference;  // -axis up
  }
  A.row(3).setOnes();
  return A;
}

MatrixCalibration six_position(const Eigen::Matrix<double, 3, 6>& U,
                               const Eigen::Matrix<double, 4, 6>& A,
                               const MatrixFitOptions& options) {
  constexpr const char* kWhere = "six_position";
  detail::require_finite(U, kWhere, "a measured mean");
  detail::require_finite(A, kWhere, "a reference");
  if (options.measurement_sigma) {
    detail::require_finite(*options.measurement_sigma, kWhere, "measurement_sigma");
  }
  Eigen::VectorXd null_direction;
  const double cond = detail::scaled_condition_number(A, &null_direction);
  if (!(cond <= options.max_condition_number)) {
    // Same wording as multi_position so both report a bad geometry alike.
    throw core::InputError(kWhere,
                           fmt::format("positions do not determine M: design condition number "
                                       "{:.3g} (limit {:.3g})",
                                       cond, options.max_condition_number));
  }
  const Eigen::Matrix4d normal_inverse = (A * A.transpose()).inverse();
  const Eigen::Matrix<double, 3, 4> M = U * A.transpose() * normal_inverse;
  return detail::pack_matrix_calibration(M, normal_inverse, U, A, cond, options);
}

}  // namespace calstand::solver
