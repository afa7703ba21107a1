#include "tablefree/triad_model.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>

#include "core/error.hpp"

namespace calstand::solver {

Eigen::Matrix3d TriadModel::matrix() const {
  Eigen::Matrix3d T = Eigen::Matrix3d::Identity() + misalignment;
  for (int i = 0; i < 3; ++i) T(i, i) = 1.0 + 1e-6 * scale_ppm[i];
  return T;
}

Eigen::Vector3d TriadModel::correct(const Eigen::Vector3d& measured) const {
  return matrix().lu().solve(measured - bias);
}

TriadModel TriadModel::from_matrix(const Eigen::Matrix3d& T, const Eigen::Vector3d& bias) {
  TriadModel m;
  m.bias = bias;
  for (int i = 0; i < 3; ++i) {
    m.scale_ppm[i] = (T(i, i) - 1.0) * 1e6;
    for (int j = 0; j < 3; ++j) {
      if (i != j) m.misalignment(i, j) = T(i, j);
    }
  }
  return m;
}

LowerTriangularFrame lower_triangular_frame(const Eigen::Matrix3d& T) {
  if (!(std::abs(T.determinant()) > 1e-12) || !T.allFinite()) {
    throw core::InputError("lower_triangular_frame", "the triad matrix is singular");
  }
  // T^T = Qr Rr with Rr upper triangular, so T = Rr^T Qr^T.
  const Eigen::HouseholderQR<Eigen::Matrix3d> qr(T.transpose());
  Eigen::Matrix3d Qr = qr.householderQ();
  Eigen::Matrix3d Rr = qr.matrixQR().triangularView<Eigen::Upper>();
  for (int i = 0; i < 3; ++i) {
    if (Rr(i, i) < 0.0) {
      Rr.row(i) *= -1.0;
      Qr.col(i) *= -1.0;
    }
  }
  LowerTriangularFrame f;
  f.L = Rr.transpose();
  f.Q = Qr.transpose();
  if (f.Q.determinant() < 0.0) {
    throw core::InputError("lower_triangular_frame",
                           "the triad is left-handed (determinant < 0): an axis sign is wrong");
  }
  return f;
}

const char* estimate_status_name(EstimateStatus s) {
  switch (s) {
    case EstimateStatus::kEstimated:
      return "estimated";
    case EstimateStatus::kFixedByConvention:
      return "fixed by convention";
    case EstimateStatus::kUndetermined:
      return "undetermined";
  }
  return "estimated";
}

std::vector<std::string> triad_parameter_names(const std::string& prefix) {
  return {prefix + "_bias.x",          prefix + "_bias.y",          prefix + "_bias.z",
          prefix + "_scale.x",         prefix + "_scale.y",         prefix + "_scale.z",
          prefix + "_misalignment.xy", prefix + "_misalignment.xz", prefix + "_misalignment.yx",
          prefix + "_misalignment.yz", prefix + "_misalignment.zx", prefix + "_misalignment.zy"};
}

std::vector<TriadEstimate> triad_estimates(const std::string& prefix, const TriadModel& m) {
  const std::vector<std::string> names = triad_parameter_names(prefix);
  const std::string bias_unit = prefix == "gyro" ? "deg/s" : "m/s^2";
  std::vector<TriadEstimate> out(12);
  for (int i = 0; i < 3; ++i) {
    out[static_cast<std::size_t>(i)] = {names[static_cast<std::size_t>(i)], m.bias[i], 0.0,
                                        bias_unit, EstimateStatus::kEstimated};
    out[static_cast<std::size_t>(3 + i)] = {names[static_cast<std::size_t>(3 + i)], m.scale_ppm[i],
                                            0.0, "ppm", EstimateStatus::kEstimated};
  }
  static const int rows[] = {0, 0, 1, 1, 2, 2};
  static const int cols[] = {1, 2, 0, 2, 0, 1};
  for (std::size_t k = 0; k < 6; ++k) {
    out[6 + k] = {names[6 + k], m.misalignment(rows[k], cols[k]), 0.0, "rad",
                  EstimateStatus::kEstimated};
  }
  return out;
}

std::vector<int> undetermined_columns(const Eigen::MatrixXd& J, const Eigen::VectorXd& natural_unit,
                                      double tolerance) {
  const Eigen::MatrixXd Jn = J * natural_unit.asDiagonal();
  const Eigen::MatrixXd H = Jn.transpose() * Jn;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(H);
  const Eigen::VectorXd& lambda = eig.eigenvalues();
  const double top = lambda.maxCoeff();
  std::vector<int> out;
  if (!(top > 0.0)) {
    for (int j = 0; j < static_cast<int>(J.cols()); ++j) out.push_back(j);
    return out;
  }
  Eigen::VectorXd share = Eigen::VectorXd::Zero(J.cols());
  for (int k = 0; k < static_cast<int>(lambda.size()); ++k) {
    if (lambda[k] < tolerance * top) share += eig.eigenvectors().col(k).cwiseAbs2();
  }
  for (int j = 0; j < static_cast<int>(J.cols()); ++j) {
    if (share[j] >= 0.25) out.push_back(j);
  }
  return out;
}

StaticMean static_mean(std::span<const core::ImuSample> samples, std::size_t begin, std::size_t end,
                       TriadSensor sensor) {
  if (begin >= end || end > samples.size()) {
    throw core::InputError("static_mean", "empty or out-of-range sample interval");
  }
  const auto value = [&](std::size_t k) -> const Eigen::Vector3d& {
    return sensor == TriadSensor::kGyro ? samples[k].gyro_dps : samples[k].accel_mps2;
  };
  StaticMean m;
  m.count = end - begin;
  const double n = static_cast<double>(m.count);
  for (std::size_t k = begin; k < end; ++k) m.mean += value(k);
  m.mean /= n;
  if (m.count < 3) return m;
  Eigen::Vector3d var = Eigen::Vector3d::Zero();
  Eigen::Vector3d lag1 = Eigen::Vector3d::Zero();
  for (std::size_t k = begin; k < end; ++k) {
    const Eigen::Vector3d d = value(k) - m.mean;
    var += d.cwiseAbs2();
    if (k + 1 < end) lag1 += d.cwiseProduct(value(k + 1) - m.mean);
  }
  for (int i = 0; i < 3; ++i) {
    const double v = var[i] / (n - 1.0);
    const double r1 = var[i] > 0.0 ? std::clamp(lag1[i] / var[i], 0.0, 0.95) : 0.0;
    const double n_eff = n * (1.0 - r1) / (1.0 + r1);
    m.sample_sigma[i] = std::sqrt(v);
    m.sigma_of_mean[i] = std::sqrt(v / std::max(1.0, n_eff));
  }
  return m;
}

nlohmann::json triad_estimates_to_json(const std::vector<TriadEstimate>& estimates) {
  nlohmann::json out = nlohmann::json::array();
  for (const TriadEstimate& e : estimates) {
    out.push_back({{"name", e.name},
                   {"value", e.value},
                   {"sigma", e.sigma},
                   {"unit", e.unit},
                   {"status", estimate_status_name(e.status)}});
  }
  return out;
}

}  // namespace calstand::solver
