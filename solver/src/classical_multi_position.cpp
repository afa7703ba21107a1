// Multi-position least squares: the six-position matrix model U = M A on any number of
// positions (seed notes: six- and twelve-position are the same LS with more columns). Solved
// row by row through an SVD of the column-scaled design so a poor geometry shows up as a
// condition number and is refused, never fitted to noise.

#include <fmt/format.h>

#include "classical_common.hpp"
#include "core/error.hpp"
#include "solver/classical.hpp"

namespace calstand::solver {

MatrixCalibration multi_position(const Eigen::Matrix3Xd& U, const Eigen::Matrix4Xd& A,
                                 const MatrixFitOptions& options) {
  constexpr const char* kWhere = "multi_position";
  if (options.measurement_sigma) {
    detail::require_finite(*options.measurement_sigma, kWhere, "measurement_sigma");
  }
  const detail::RowLeastSquares ls = detail::solve_rows(U, A, detail::matrix_unknown_names(),
                                                        options.max_condition_number, kWhere);
  return detail::pack_matrix_calibration(ls.X, ls.cov_base, U, A, ls.condition_number, options);
}

}  // namespace calstand::solver
