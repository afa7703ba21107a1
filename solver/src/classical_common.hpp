#pragma once

// Shared machinery of the matrix-form classical methods (six-, twelve-, multi-position): the
// row-wise least squares U = M A, its conditioning check, and packing into MatrixCalibration.
// Private to the solver library.

#include <Eigen/Core>
#include <string>

#include "solver/classical.hpp"

namespace calstand::solver::detail {

/// Throws core::InputError(where, "<what> is not finite") unless every entry is finite.
void require_finite(const Eigen::MatrixXd& m, const std::string& where, const std::string& what);
void require_finite(double v, const std::string& where, const std::string& what);
/// Throws core::InputError(where, ...) unless the standard deviation `sigma` named `what` is
/// finite and not negative.
void require_sigma(double sigma, const std::string& where, const std::string& what);

/// Least-squares solution of U (3xN) = X (3xp) A (pxN), one independent LS per row of U.
struct RowLeastSquares {
  Eigen::MatrixXd X;         ///< 3 x p
  Eigen::MatrixXd cov_base;  ///< (A A^T)^-1, p x p: the covariance of a row of X per unit sigma^2
  double condition_number = 0.0;  ///< of A^T with unit-norm columns
};

/// Solves by an SVD of the column-scaled design A^T (numerically safer than forming A A^T).
/// `unknown_names` (size p) label the singular direction in the error. Throws core::InputError
/// when N < p or the scaled condition number exceeds `max_condition`.
RowLeastSquares solve_rows(const Eigen::MatrixXd& U, const Eigen::MatrixXd& A,
                           const std::vector<std::string>& unknown_names, double max_condition,
                           const std::string& where);

/// Condition number of A^T with its columns scaled to unit norm; `null_direction` (optional)
/// receives the right singular vector of the smallest singular value (in scaled unknowns).
double scaled_condition_number(const Eigen::MatrixXd& A, Eigen::VectorXd* null_direction);

/// Builds the result from a solved X (3xp; its first four columns are [I+S+Mis | b]) and
/// cov_base (pxp): residuals U - X A, sigmas from options or residual scatter (dof = N - p).
MatrixCalibration pack_matrix_calibration(const Eigen::MatrixXd& X, const Eigen::MatrixXd& cov_base,
                                          const Eigen::MatrixXd& U, const Eigen::MatrixXd& A,
                                          double condition_number, const MatrixFitOptions& options);

/// Unknown names of the standard 4-row design: ref_x, ref_y, ref_z, bias.
const std::vector<std::string>& matrix_unknown_names();

}  // namespace calstand::solver::detail
