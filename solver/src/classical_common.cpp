#include "classical_common.hpp"

#include <fmt/format.h>

#include <Eigen/SVD>
#include <cmath>
#include <limits>

#include "core/error.hpp"

namespace calstand::solver::detail {

void require_finite(const Eigen::MatrixXd& m, const std::string& where, const std::string& what) {
  if (!m.allFinite()) throw core::InputError(where, what + " is not finite");
}

void require_finite(double v, const std::string& where, const std::string& what) {
  if (!std::isfinite(v))
    throw core::InputError(where, fmt::format("{} is not finite ({})", what, v));
}

void require_sigma(double sigma, const std::string& where, const std::string& what) {
  require_finite(sigma, where, what);
  if (sigma < 0.0)
    throw core::InputError(where, fmt::format("{} {} must not be negative", what, sigma));
}

const std::vector<std::string>& matrix_unknown_names() {
  static const std::vector<std::string> names{"ref_x", "ref_y", "ref_z", "bias"};
  return names;
}

double scaled_condition_number(const Eigen::MatrixXd& A, Eigen::VectorXd* null_direction) {
  // Scaling the columns of A^T to unit norm removes the units (g = 9.8 against the bias column
  // of ones, or the Earth rate of 0.004 deg/s) so the number speaks about geometry only.
  Eigen::MatrixXd design = A.transpose();
  for (Eigen::Index c = 0; c < design.cols(); ++c) {
    const double norm = design.col(c).norm();
    if (norm > 0.0) design.col(c) /= norm;
  }
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(design, Eigen::ComputeThinV);
  const Eigen::VectorXd& s = svd.singularValues();
  if (null_direction != nullptr) *null_direction = svd.matrixV().col(s.size() - 1);
  const double smallest = s(s.size() - 1);
  return smallest > 0.0 ? s(0) / smallest : std::numeric_limits<double>::infinity();
}

namespace {

// "0.71 ref_x - 0.71 bias": the undetermined combination, so the user sees which unknowns the
// positions cannot tell apart.
std::string describe_direction(const Eigen::VectorXd& v, const std::vector<std::string>& names) {
  std::string out;
  for (Eigen::Index k = 0; k < v.size(); ++k) {
    if (std::abs(v(k)) < 0.05) continue;
    const bool first = out.empty();
    const char* sign = v(k) < 0.0 ? (first ? "-" : " - ") : (first ? "" : " + ");
    out += fmt::format("{}{:.2f} {}", sign, std::abs(v(k)),
                       k < static_cast<Eigen::Index>(names.size()) ? names[k] : "?");
  }
  return out;
}

}  // namespace

RowLeastSquares solve_rows(const Eigen::MatrixXd& U, const Eigen::MatrixXd& A,
                           const std::vector<std::string>& unknown_names, double max_condition,
                           const std::string& where) {
  const Eigen::Index p = A.rows();
  const Eigen::Index n = A.cols();
  if (U.cols() != n) {
    throw core::InputError(
        where, fmt::format("{} measured positions but {} reference positions", U.cols(), n));
  }
  if (n < p) {
    throw core::InputError(
        where, fmt::format("{} positions given, need at least {} ({} unknowns per axis)", n, p, p));
  }
  require_finite(U, where, "a measured mean");
  require_finite(A, where, "a reference");

  Eigen::VectorXd scale(p);
  Eigen::MatrixXd design = A.transpose();  // N x p
  for (Eigen::Index c = 0; c < p; ++c) {
    scale(c) = design.col(c).norm();
    if (scale(c) == 0.0) {
      throw core::InputError(
          where, fmt::format("positions do not determine M: {} is zero in "
                             "every position",
                             c < static_cast<Eigen::Index>(unknown_names.size()) ? unknown_names[c]
                                                                                 : "a regressor"));
    }
    design.col(c) /= scale(c);
  }
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(design, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const Eigen::VectorXd& s = svd.singularValues();
  const double cond = s(p - 1) > 0.0 ? s(0) / s(p - 1) : std::numeric_limits<double>::infinity();
  if (!(cond <= max_condition)) {
    throw core::InputError(
        where, fmt::format("positions do not determine M: design condition number {:.3g} "
                           "(limit {:.3g}); undetermined combination: {}",
                           cond, max_condition,
                           describe_direction(svd.matrixV().col(p - 1), unknown_names)));
  }
  // x_scaled = V S^-1 U^T y per row; x = D^-1 x_scaled with D = diag(scale).
  const Eigen::MatrixXd V_over_s = svd.matrixV() * s.cwiseInverse().asDiagonal();  // p x p
  const Eigen::VectorXd inv_scale = scale.cwiseInverse();
  RowLeastSquares out;
  out.X = (U * svd.matrixU() * V_over_s.transpose()) * inv_scale.asDiagonal();
  out.cov_base =
      inv_scale.asDiagonal() * (V_over_s * V_over_s.transpose()) * inv_scale.asDiagonal();
  out.condition_number = cond;
  return out;
}

MatrixCalibration pack_matrix_calibration(const Eigen::MatrixXd& X, const Eigen::MatrixXd& cov_base,
                                          const Eigen::MatrixXd& U, const Eigen::MatrixXd& A,
                                          double condition_number,
                                          const MatrixFitOptions& options) {
  MatrixCalibration r;
  r.M = X.leftCols(4);
  r.bias = r.M.col(3);
  for (int i = 0; i < 3; ++i) {
    r.scale_ppm(i) = 1e6 * (r.M(i, i) - 1.0);
    for (int j = 0; j < 3; ++j) r.misalignment_rad(i, j) = i == j ? 0.0 : r.M(i, j);
  }
  r.residuals = U - X * A;
  r.positions = static_cast<int>(U.cols());
  r.dof = static_cast<int>(U.cols() - A.rows());
  r.condition_number = condition_number;
  for (int i = 0; i < 3; ++i) {
    r.residual_rms(i) = std::sqrt(r.residuals.row(i).squaredNorm() / static_cast<double>(U.cols()));
  }

  if (options.measurement_sigma) {
    r.measurement_sigma = *options.measurement_sigma;
    r.sigma_source = SigmaSource::kGiven;
  } else if (r.dof > 0) {
    // Unbiased scatter estimate: sum r^2 / (N - p) per axis (each axis is its own LS).
    for (int i = 0; i < 3; ++i) {
      r.measurement_sigma(i) =
          std::sqrt(r.residuals.row(i).squaredNorm() / static_cast<double>(r.dof));
    }
    r.sigma_source = SigmaSource::kResidualScatter;
  } else {
    r.sigma_source = SigmaSource::kNone;
  }

  // The covariance of row i is sigma_i^2 (A A^T)^-1; M's block is the marginal of the first
  // four unknowns (any further regressors, e.g. g-sensitivity, stay in the full fit).
  const Eigen::Matrix4d base = cov_base.topLeftCorner(4, 4);
  for (int i = 0; i < 3; ++i) {
    const double var = r.measurement_sigma(i) * r.measurement_sigma(i);
    r.row_covariance[static_cast<std::size_t>(i)] = var * base;
    r.bias_sigma(i) = std::sqrt(var * base(3, 3));
    r.scale_sigma_ppm(i) = 1e6 * std::sqrt(var * base(i, i));
    for (int j = 0; j < 3; ++j) {
      r.misalignment_sigma_rad(i, j) = i == j ? 0.0 : std::sqrt(var * base(j, j));
    }
  }
  return r;
}

}  // namespace calstand::solver::detail
