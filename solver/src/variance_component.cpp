#include "solver/variance_component.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <boost/math/tools/minima.hpp>
#include <cmath>

namespace calstand::solver::detail {
namespace {

// The ratio's range and grid (see best_log10_ratio()).
constexpr double kLog10RatioLo = -3.0;
constexpr double kLog10RatioHi = 4.0;
constexpr int kRatioGrid = 15;
// Brent's method: bits of precision in log r (a ratio known to 0.1 % changes no weight) and
// the most evaluations it may take.
constexpr int kBrentBits = 12;
constexpr int kBrentIterations = 40;

}  // namespace

KernelBasis kernel_basis(const Eigen::MatrixXd& G) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(G);
  KernelBasis out;
  out.lambda = eig.eigenvalues().cwiseMax(0.0);  // a covariance: rounding can leave -1e-17
  out.U = eig.eigenvectors();
  return out;
}

namespace {

/// -0.5 (log det C + [log det M] + quadratic) for restricted or profile.
double gls_log_likelihood(const Eigen::VectorXd& lambda, const Eigen::MatrixXd& Xh,
                          const Eigen::VectorXd& yh, double white, double rho, bool restricted) {
  const Eigen::ArrayXd one_plus = 1.0 + rho * lambda.array();
  const Eigen::VectorXd w = one_plus.inverse().matrix();
  const double log_det_c = one_plus.log().sum();
  const Eigen::MatrixXd M = Xh.transpose() * w.asDiagonal() * Xh;
  const Eigen::VectorXd b = Xh.transpose() * w.cwiseProduct(yh);
  double log_det_m = 0.0, fitted = 0.0;
  if (M.rows() > 0) {
    const Eigen::LLT<Eigen::MatrixXd> llt(M);
    if (llt.info() != Eigen::Success) return -std::numeric_limits<double>::infinity();
    if (restricted) log_det_m = 2.0 * llt.matrixL().toDenseMatrix().diagonal().array().log().sum();
    fitted = b.dot(llt.solve(b));
  }
  const double quadratic = (yh.dot(w.cwiseProduct(yh)) - fitted) / white;
  return -0.5 * (log_det_c + log_det_m + quadratic);
}

}  // namespace

double restricted_log_likelihood(const Eigen::VectorXd& lambda, const Eigen::MatrixXd& Xh,
                                 const Eigen::VectorXd& yh, double white, double rho) {
  return gls_log_likelihood(lambda, Xh, yh, white, rho, true);
}

double profile_log_likelihood(const Eigen::VectorXd& lambda, const Eigen::MatrixXd& Xh,
                              const Eigen::VectorXd& yh, double white, double rho) {
  return gls_log_likelihood(lambda, Xh, yh, white, rho, false);
}

RatioFit best_log10_ratio(const std::function<double(double)>& log_likelihood) {
  RatioFit best{kLog10RatioLo, -std::numeric_limits<double>::infinity()};
  const auto evaluate = [&](double r) {
    const double v = log_likelihood(r);
    if (v > best.log_likelihood) best = {r, v};
    return v;
  };
  const double step = (kLog10RatioHi - kLog10RatioLo) / (kRatioGrid - 1);
  for (int i = 0; i < kRatioGrid; ++i) evaluate(kLog10RatioLo + step * i);
  // `evaluate` keeps the best point seen, grid included.
  const double lo = std::max(kLog10RatioLo, best.log10_ratio - step);
  const double hi = std::min(kLog10RatioHi, best.log10_ratio + step);
  boost::uintmax_t iterations = kBrentIterations;
  boost::math::tools::brent_find_minima([&](double r) { return -evaluate(r); }, lo, hi, kBrentBits,
                                        iterations);
  return best;
}

}  // namespace calstand::solver::detail
