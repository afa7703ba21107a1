#include "tablefree/ferraris.hpp"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>

#include "core/error.hpp"
#include "core/rotation.hpp"
#include "core/site.hpp"

namespace calstand::solver {

namespace {

constexpr const char* kFerrarisWhere = "ferraris";
constexpr double kFerrarisMg = 1e-3 * core::kStandardGravity;

struct FerrarisLabel {
  const char* name;
  int axis;
  int sign;  // statics: +1 up, -1 down; turns: 0
};
const FerrarisLabel kLabels[] = {{"x_p", 0, 1},   {"x_a", 0, -1},  {"y_p", 1, 1},
                                 {"y_a", 1, -1},  {"z_p", 2, 1},   {"z_a", 2, -1},
                                 {"x_rot", 0, 0}, {"y_rot", 1, 0}, {"z_rot", 2, 0}};

// The along-axis part of a tilt varies as sigma_p^4, and sigma_p^2 comes from 6 degrees of
// freedom: plugging the estimate in understates it badly (E[s^4] is 1.5 times the plug-in's
// square, and the estimate is low often). Averaged over the estimate's own uncertainty (sigma^2
// ~ 6 s^2 / chi2_6): E[sigma^4] = 36 / (4 * 2) s^4 = 4.5 s^4.
constexpr double kQuarticFactor = 4.5;

struct AccelGls {
  Eigen::Matrix<double, 12, 1> theta;
  Eigen::Matrix<double, 12, 12> cov;
  double chi2 = 0.0;
  std::array<Eigen::Vector3d, 6> residual;
};

// Accel in N: theta = [b, T e_x, T e_y, T e_z]; holds in kLabels order.
AccelGls ferraris_accel_gls(const std::array<Eigen::Vector3d, 6>& mean,
                            const std::array<Eigen::Vector3d, 6>& sigma, double g,
                            double placement_sigma) {
  Eigen::Matrix<double, 12, 12> N = Eigen::Matrix<double, 12, 12>::Zero();
  Eigen::Matrix<double, 12, 1> rhs = Eigen::Matrix<double, 12, 1>::Zero();
  std::array<Eigen::Matrix3d, 6> W;
  std::array<Eigen::Matrix<double, 3, 12>, 6> A;
  for (std::size_t p = 0; p < 6; ++p) {
    const int axis = kLabels[p].axis;
    const double s = kLabels[p].sign;
    // A tilt theta (two horizontal components of variance sp2 each) moves the reading across
    // the axis by g theta (variance g^2 sp2 per direction) and along it by g (cos theta - 1):
    // mean -g sp2, variance g^2 sp2^2 (theta^2 / 2 is sp2 times a chi-square of 2 dof / 2),
    // the latter averaged over the uncertainty of sp2 (kQuarticFactor).
    const double sp2 = placement_sigma * placement_sigma;
    Eigen::Matrix3d cov = sigma[p].cwiseAbs2().asDiagonal();
    const Eigen::Vector3d e = Eigen::Vector3d::Unit(axis);
    const Eigen::Matrix3d along = e * e.transpose();
    cov += g * g * sp2 * (Eigen::Matrix3d::Identity() - along) +
           kQuarticFactor * g * g * sp2 * sp2 * along;
    W[p] = cov.inverse();
    A[p].setZero();
    A[p].block<3, 3>(0, 0).setIdentity();
    A[p].block<3, 3>(0, 3 + 3 * axis) = s * g * (1.0 - sp2) * Eigen::Matrix3d::Identity();
    N += A[p].transpose() * W[p] * A[p];
    rhs += A[p].transpose() * W[p] * mean[p];
  }
  AccelGls out;
  out.cov = N.inverse();
  out.theta = out.cov * rhs;
  for (std::size_t p = 0; p < 6; ++p) {
    out.residual[p] = mean[p] - A[p] * out.theta;
    out.chi2 += out.residual[p].dot(W[p] * out.residual[p]);
  }
  return out;
}

Eigen::Matrix3d ferraris_columns(const Eigen::Matrix<double, 12, 1>& theta) {
  Eigen::Matrix3d T;
  for (int i = 0; i < 3; ++i) T.col(i) = theta.segment<3>(3 + 3 * i);
  return T;
}

// The A-frame outputs from the N-frame unknowns x = [b_a, T_a cols, b_g, T_g cols] (24):
// accel 12 contract (bias, scale ppm, misalignment xy xz yx yz zx zy), gyro 12, rotation 3 [deg].
Eigen::Matrix<double, 27, 1> ferraris_outputs(const Eigen::Matrix<double, 24, 1>& x) {
  const Eigen::Matrix3d Ta = ferraris_columns(x.head<12>());
  const Eigen::Matrix3d Tg = ferraris_columns(x.tail<12>());
  const LowerTriangularFrame f = lower_triangular_frame(Ta);
  const TriadModel a = TriadModel::from_matrix(f.L, x.head<3>());
  const TriadModel gy = TriadModel::from_matrix(Tg * f.Q.transpose(), x.segment<3>(12));
  Eigen::Matrix<double, 27, 1> out;
  static const int rows[] = {0, 0, 1, 1, 2, 2};
  static const int cols[] = {1, 2, 0, 2, 0, 1};
  out.segment<3>(0) = a.bias;
  out.segment<3>(3) = a.scale_ppm;
  for (int k = 0; k < 6; ++k) out[6 + k] = a.misalignment(rows[k], cols[k]);
  out.segment<3>(12) = gy.bias;
  out.segment<3>(15) = gy.scale_ppm;
  for (int k = 0; k < 6; ++k) out[18 + k] = gy.misalignment(rows[k], cols[k]);
  const Eigen::AngleAxisd rot(f.Q);
  out.segment<3>(24) = rot.angle() * rot.axis() * core::kRadToDeg;
  return out;
}

}  // namespace

std::vector<FerrarisSection> ferraris_sections_from_steps(
    std::span<const int> steps, const std::vector<std::pair<int, std::string>>& labels) {
  std::vector<FerrarisSection> out;
  for (const auto& [step, label] : labels) {
    FerrarisSection s;
    s.label = label;
    bool found = false;
    for (std::size_t k = 0; k < steps.size(); ++k) {
      if (steps[k] != step) continue;
      if (!found) s.begin = k;
      s.end = k + 1;
      found = true;
    }
    if (!found) {
      throw core::InputError(kFerrarisWhere,
                             fmt::format("section {} (step {}) has no samples", label, step));
    }
    out.push_back(s);
  }
  return out;
}

FerrarisResult calibrate_ferraris(std::span<const core::ImuSample> samples,
                                  std::span<const FerrarisSection> sections,
                                  const FerrarisOptions& o) {
  const double g = o.gravity_mps2;
  if (!(g > 0.0) || !std::isfinite(g)) {
    throw core::InputError(kFerrarisWhere,
                           "local gravity (gravity_mps2) must be given and positive");
  }
  std::array<const FerrarisSection*, 9> by_label{};
  for (const FerrarisSection& s : sections) {
    bool known = false;
    for (std::size_t k = 0; k < 9; ++k) {
      if (s.label != kLabels[k].name) continue;
      if (by_label[k] != nullptr) {
        throw core::InputError(kFerrarisWhere, fmt::format("section {} is given twice", s.label));
      }
      if (s.begin + 3 > s.end || s.end > samples.size()) {
        throw core::InputError(kFerrarisWhere,
                               fmt::format("section {} is empty or outside the samples "
                                           "(needs at least 3 samples)",
                                           s.label));
      }
      by_label[k] = &s;
      known = true;
    }
    if (!known) {
      throw core::InputError(kFerrarisWhere,
                             fmt::format("unknown section label \"{}\" (x_p x_a y_p y_a "
                                         "z_p z_a x_rot y_rot z_rot)",
                                         s.label));
    }
  }
  std::string missing;
  for (std::size_t k = 0; k < 9; ++k) {
    if (by_label[k] == nullptr)
      missing += (missing.empty() ? "" : ", ") + std::string(kLabels[k].name);
  }
  if (!missing.empty()) {
    throw core::InputError(kFerrarisWhere, "the session lacks the sections " + missing +
                                               " (six holds and three turns are needed)");
  }

  FerrarisResult out;
  // Holds.
  std::array<Eigen::Vector3d, 6> accel_mean, accel_sigma;
  Eigen::Vector3d gyro_sum = Eigen::Vector3d::Zero();
  std::array<Eigen::Vector3d, 6> gyro_means;
  double white_sq = 0.0;
  Eigen::Vector3d block_scatter = Eigen::Vector3d::Zero();
  Eigen::Vector3d block_expected = Eigen::Vector3d::Zero();
  for (std::size_t p = 0; p < 6; ++p) {
    const FerrarisSection& s = *by_label[p];
    const StaticMean a = static_mean(samples, s.begin, s.end, TriadSensor::kAccel);
    const StaticMean w = static_mean(samples, s.begin, s.end, TriadSensor::kGyro);
    accel_mean[p] = a.mean;
    accel_sigma[p] = a.sigma_of_mean;
    // Block means (4 per hold): their scatter against what the sample noise predicts for them.
    {
      const std::size_t n = s.end - s.begin;
      const std::size_t len = n / 4;
      if (len >= 3) {
        std::array<Eigen::Vector3d, 4> bm;
        Eigen::Vector3d mean_of = Eigen::Vector3d::Zero();
        for (std::size_t b = 0; b < 4; ++b) {
          const StaticMean m =
              static_mean(samples, s.begin + b * len, s.begin + (b + 1) * len, TriadSensor::kAccel);
          bm[b] = m.mean;
          mean_of += m.mean / 4.0;
          block_expected += m.sigma_of_mean.cwiseAbs2() / 4.0;
        }
        for (const Eigen::Vector3d& m : bm) block_scatter += (m - mean_of).cwiseAbs2() / 3.0 / 4.0;
      }
    }
    gyro_means[p] = w.mean;
    gyro_sum += w.mean;
    white_sq += w.sample_sigma.cwiseAbs2().mean();
    FerrarisHold h;
    h.label = s.label;
    h.start_s = samples[s.begin].receive_time_s;
    h.end_s = samples[s.end - 1].receive_time_s;
    h.mean_accel_mps2 = a.mean;
    h.mean_gyro_dps = w.mean;
    out.holds.push_back(h);
  }
  const Eigen::Vector3d b_g = gyro_sum / 6.0;
  Eigen::Vector3d b_g_sigma;
  {
    Eigen::Vector3d scatter = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d& m : gyro_means) scatter += (m - b_g).cwiseAbs2();
    b_g_sigma = (scatter / 5.0).cwiseSqrt() / std::sqrt(6.0);
  }
  const double white_dps = std::sqrt(white_sq / 6.0);
  // A bias that wanders between holds is not in a hold's own noise: where the block means of
  // the holds (pooled, 18 degrees of freedom per axis) scatter more than their sample noise
  // says, every hold mean's sigma is inflated by that ratio (the wander at the seconds scale
  // standing for the wander between holds).
  Eigen::Vector3d wander = Eigen::Vector3d::Ones();
  for (int i = 0; i < 3; ++i) {
    if (block_expected[i] > 0.0)
      wander[i] = std::sqrt(std::max(1.0, block_scatter[i] / block_expected[i]));
  }
  for (Eigen::Vector3d& sg : accel_sigma) sg = sg.cwiseProduct(wander);
  out.hold_noise_inflation = wander;

  // Accelerometer: naive, then with the placement variance (chi2 = dof).
  const int dof = 6;
  const AccelGls naive = ferraris_accel_gls(accel_mean, accel_sigma, g, 0.0);
  out.accel_chi2_naive = naive.chi2;
  out.accel_chi2_per_dof_naive = naive.chi2 / dof;
  out.accel_dof = dof;
  double sigma_p = 0.0;
  if (o.estimate_placement && naive.chi2 > dof) {
    double lo = 0.0, hi = 1e-3;
    while (ferraris_accel_gls(accel_mean, accel_sigma, g, hi).chi2 > dof && hi < 1.0) hi *= 2.0;
    for (int it = 0; it < 100; ++it) {
      const double mid = 0.5 * (lo + hi);
      if (ferraris_accel_gls(accel_mean, accel_sigma, g, mid).chi2 > dof) {
        lo = mid;
      } else {
        hi = mid;
      }
    }
    sigma_p = 0.5 * (lo + hi);
    out.placement_estimated = true;
  }
  const AccelGls fit = ferraris_accel_gls(accel_mean, accel_sigma, g, sigma_p);
  out.accel_chi2 = fit.chi2;
  out.accel_chi2_per_dof = fit.chi2 / dof;
  out.placement_sigma_deg = sigma_p * core::kRadToDeg;
  out.placement_rms_tilt_deg = std::sqrt(2.0) * out.placement_sigma_deg;
  const Eigen::Matrix3d Ta = ferraris_columns(fit.theta);
  out.accel_nominal_frame = TriadModel::from_matrix(Ta, fit.theta.head<3>());

  // Gyro: integrate each turn.
  Eigen::Matrix<double, 12, 1> gyro_theta;
  gyro_theta.head<3>() = b_g;
  Eigen::Matrix<double, 12, 12> gyro_cov = Eigen::Matrix<double, 12, 12>::Zero();
  gyro_cov.topLeftCorner<3, 3>() = b_g_sigma.cwiseAbs2().asDiagonal();
  std::array<double, 3> turn_T{}, turn_phi{};
  for (std::size_t k = 0; k < 3; ++k) {
    const FerrarisSection& s = *by_label[6 + k];
    const int axis = kLabels[6 + k].axis;
    Eigen::Vector3d theta = Eigen::Vector3d::Zero();
    for (std::size_t i = s.begin; i + 1 < s.end; ++i) {
      const double dt = samples[i + 1].receive_time_s - samples[i].receive_time_s;
      theta += 0.5 * (samples[i].gyro_dps + samples[i + 1].gyro_dps - 2.0 * b_g) * dt;
    }
    const double duration = samples[s.end - 1].receive_time_s - samples[s.begin].receive_time_s;
    const double given = s.angle_deg != 0.0 ? s.angle_deg : o.turn_angle_deg;
    double used = given;
    const double measured = theta[axis];
    if (o.turn_sign == TurnSign::kDetect) {
      used = std::copysign(std::abs(given), measured);
      out.notes.push_back(fmt::format(
          "{}: the gyro integrates {:+.1f} deg about +{} ({}clockwise seen from the axis tip); "
          "used {:+.0f} deg{}",
          s.label, measured, "xyz"[axis], measured >= 0.0 ? "counter-" : "", used,
          used == given ? "" : fmt::format(" (the label says {:+.0f})", given)));
    } else if (measured * given < 0.0) {
      out.notes.push_back(fmt::format(
          "{}: the label says {:+.0f} deg but the gyro integrates {:+.1f} deg about +{}: the "
          "gyro scale will come out near -1 on that axis (TurnSign::kDetect takes the sign "
          "from the data)",
          s.label, given, measured, "xyz"[axis]));
    }
    FerrarisTurn t;
    t.label = s.label;
    t.start_s = samples[s.begin].receive_time_s;
    t.end_s = samples[s.end - 1].receive_time_s;
    t.integrated_deg = theta;
    t.measured_angle_deg = measured;
    t.used_angle_deg = used;
    // Turn axis seen by the calibrated accelerometer (centripetal acceleration included).
    Eigen::Vector3d a = Eigen::Vector3d::Zero();
    for (std::size_t i = s.begin; i < s.end; ++i) a += samples[i].accel_mps2;
    a /= static_cast<double>(s.end - s.begin);
    const Eigen::Vector3d f = Ta.lu().solve(a - fit.theta.head<3>());
    t.axis_tilt_deg = std::acos(std::clamp(f.normalized()[axis], -1.0, 1.0)) * core::kRadToDeg;
    out.turns.push_back(t);
    // The turn axis is placed like a hold: on average cos(tilt) = 1 - sigma_p^2 of it lies
    // along the nominal axis.
    gyro_theta.segment<3>(3 + 3 * axis) = theta / (used * (1.0 - sigma_p * sigma_p));
    turn_T[k] = duration;
    turn_phi[k] = used;
  }
  // Gyro covariance: white noise over each turn, the common bias, the placement of the axis.
  for (std::size_t k = 0; k < 3; ++k) {
    const int ai = kLabels[6 + k].axis;
    const FerrarisSection& s = *by_label[6 + k];
    const double dt =
        turn_T[k] / static_cast<double>(std::max<std::size_t>(1, s.end - s.begin - 1));
    Eigen::Matrix3d c = (white_dps * white_dps * dt * turn_T[k] / (turn_phi[k] * turn_phi[k])) *
                        Eigen::Matrix3d::Identity();
    const Eigen::Vector3d e = Eigen::Vector3d::Unit(ai);
    const double sp2 = sigma_p * sigma_p;
    c += sp2 * (Eigen::Matrix3d::Identity() - e * e.transpose()) +
         kQuarticFactor * sp2 * sp2 * e * e.transpose();
    gyro_cov.block<3, 3>(3 + 3 * ai, 3 + 3 * ai) += c;
    for (std::size_t l = 0; l < 3; ++l) {
      const int aj = kLabels[6 + l].axis;
      const double f = (turn_T[k] / turn_phi[k]) * (turn_T[l] / turn_phi[l]);
      gyro_cov.block<3, 3>(3 + 3 * ai, 3 + 3 * aj) += f * gyro_cov.topLeftCorner<3, 3>();
    }
    gyro_cov.block<3, 3>(3 + 3 * ai, 0) =
        -(turn_T[k] / turn_phi[k]) * gyro_cov.topLeftCorner<3, 3>();
    gyro_cov.block<3, 3>(0, 3 + 3 * ai) = gyro_cov.block<3, 3>(3 + 3 * ai, 0).transpose();
  }
  const Eigen::Matrix3d Tg = ferraris_columns(gyro_theta);
  out.gyro_nominal_frame = TriadModel::from_matrix(Tg, b_g);

  // Frame A and the propagated covariance.
  Eigen::Matrix<double, 24, 1> x;
  x.head<12>() = fit.theta;
  x.tail<12>() = gyro_theta;
  Eigen::Matrix<double, 24, 24> cx = Eigen::Matrix<double, 24, 24>::Zero();
  cx.topLeftCorner<12, 12>() = fit.cov;
  cx.bottomRightCorner<12, 12>() = gyro_cov;
  const Eigen::Matrix<double, 27, 1> y = ferraris_outputs(x);
  Eigen::Matrix<double, 27, 24> Jy;
  for (int j = 0; j < 24; ++j) {
    const double h = 1e-7 * std::max(1.0, std::abs(x[j]));
    Eigen::Matrix<double, 24, 1> xp = x, xm = x;
    xp[j] += h;
    xm[j] -= h;
    Jy.col(j) = (ferraris_outputs(xp) - ferraris_outputs(xm)) / (2.0 * h);
  }
  const Eigen::Matrix<double, 27, 27> cy = Jy * cx * Jy.transpose();
  {
    const LowerTriangularFrame f = lower_triangular_frame(Ta);
    out.accel = TriadModel::from_matrix(f.L, fit.theta.head<3>());
    out.gyro = TriadModel::from_matrix(Tg * f.Q.transpose(), b_g);
  }
  out.parameters = triad_estimates("accel", out.accel);
  const std::vector<TriadEstimate> gyro_est = triad_estimates("gyro", out.gyro);
  out.parameters.insert(out.parameters.end(), gyro_est.begin(), gyro_est.end());
  out.covariance = cy.topLeftCorner<24, 24>();
  for (std::size_t k = 0; k < 24; ++k) {
    TriadEstimate& e = out.parameters[k];
    e.value = y[static_cast<Eigen::Index>(k)];
    if (e.name == "accel_misalignment.xy" || e.name == "accel_misalignment.xz" ||
        e.name == "accel_misalignment.yz") {
      e.status = EstimateStatus::kFixedByConvention;
      e.value = 0.0;
      out.covariance.row(static_cast<Eigen::Index>(k)).setZero();
      out.covariance.col(static_cast<Eigen::Index>(k)).setZero();
      continue;
    }
    e.sigma =
        std::sqrt(std::max(0.0, cy(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(k))));
  }
  out.frame_rotation_deg = y.tail<3>();
  for (int i = 0; i < 3; ++i)
    out.frame_rotation_sigma_deg[i] = std::sqrt(std::max(0.0, cy(24 + i, 24 + i)));

  // Hold residuals in words.
  double norm_sq = 0.0;
  for (std::size_t p = 0; p < 6; ++p) {
    const int axis = kLabels[p].axis;
    Eigen::Vector3d across = fit.residual[p];
    across[axis] = 0.0;
    out.holds[p].across_residual_deg = across.norm() / g * core::kRadToDeg;
    const Eigen::Vector3d f = out.accel.correct(accel_mean[p]);
    out.holds[p].norm_residual_mg = (f.norm() - g) / kFerrarisMg;
    norm_sq += out.holds[p].norm_residual_mg * out.holds[p].norm_residual_mg;
  }
  out.norm_rms_residual_mg = std::sqrt(norm_sq / 6.0);

  const std::string placement =
      out.placement_estimated
          ? fmt::format(
                "the holds were placed with a scatter of {:.2g} deg (RMS tilt; {:.2g} deg "
                "per horizontal axis), estimated from the 6 degrees of freedom so that "
                "chi2/dof = {:.3g}; taken as exact the holds give chi2/dof {:.4g}",
                out.placement_rms_tilt_deg, out.placement_sigma_deg, out.accel_chi2_per_dof,
                out.accel_chi2_per_dof_naive)
          : fmt::format("holds taken as exact: accel chi2/dof {:.4g} against the hold means' noise",
                        out.accel_chi2_per_dof_naive);
  out.summary = fmt::format(
      "Ferraris: {}; misalignment sigmas include that placement; |f| - g at the holds "
      "{:.3g} mg RMS; the triad sits {:.2g} deg from the box frame; the Earth rate (not "
      "modelled) moves a turn integral by at most {:.2g} deg",
      placement, out.norm_rms_residual_mg, out.frame_rotation_deg.norm(),
      core::kEarthRateRadPerS * core::kRadToDeg * std::max({turn_T[0], turn_T[1], turn_T[2]}));
  return out;
}

nlohmann::json ferraris_to_json(const FerrarisResult& r) {
  const auto vec = [](const Eigen::Vector3d& v) { return nlohmann::json{v.x(), v.y(), v.z()}; };
  const auto mat = [&](const Eigen::Matrix3d& m) {
    return nlohmann::json{vec(m.row(0)), vec(m.row(1)), vec(m.row(2))};
  };
  nlohmann::json j;
  j["method"] = "ferraris";
  j["frame"] = kAccelTriadFrameText;
  j["parameters"] = triad_estimates_to_json(r.parameters);
  nlohmann::json names = nlohmann::json::array();
  for (const TriadEstimate& e : r.parameters) names.push_back(e.name);
  nlohmann::json rows = nlohmann::json::array();
  for (Eigen::Index i = 0; i < r.covariance.rows(); ++i) {
    nlohmann::json row = nlohmann::json::array();
    for (Eigen::Index k = 0; k < r.covariance.cols(); ++k) row.push_back(r.covariance(i, k));
    rows.push_back(row);
  }
  j["covariance"] = {{"names", names}, {"matrix", rows}};
  j["nominal_frame"] = {
      {"accel",
       {{"bias", vec(r.accel_nominal_frame.bias)},
        {"matrix", mat(r.accel_nominal_frame.matrix())}}},
      {"gyro",
       {{"bias", vec(r.gyro_nominal_frame.bias)}, {"matrix", mat(r.gyro_nominal_frame.matrix())}}}};
  j["frame_rotation_deg"] = vec(r.frame_rotation_deg);
  j["frame_rotation_sigma_deg"] = vec(r.frame_rotation_sigma_deg);
  j["placement"] = {{"estimated", r.placement_estimated},
                    {"sigma_deg", r.placement_sigma_deg},
                    {"rms_tilt_deg", r.placement_rms_tilt_deg}};
  j["quality"] = {{"accel_chi2_per_dof", r.accel_chi2_per_dof},
                  {"accel_chi2_per_dof_naive", r.accel_chi2_per_dof_naive},
                  {"accel_dof", r.accel_dof},
                  {"norm_rms_residual_mg", r.norm_rms_residual_mg},
                  {"summary", r.summary}};
  nlohmann::json holds = nlohmann::json::array();
  for (const FerrarisHold& h : r.holds) {
    holds.push_back({{"label", h.label},
                     {"start_s", h.start_s},
                     {"end_s", h.end_s},
                     {"mean_accel_mps2", vec(h.mean_accel_mps2)},
                     {"mean_gyro_dps", vec(h.mean_gyro_dps)},
                     {"across_residual_deg", h.across_residual_deg},
                     {"norm_residual_mg", h.norm_residual_mg}});
  }
  j["holds"] = holds;
  nlohmann::json turns = nlohmann::json::array();
  for (const FerrarisTurn& t : r.turns) {
    turns.push_back({{"label", t.label},
                     {"start_s", t.start_s},
                     {"end_s", t.end_s},
                     {"integrated_deg", vec(t.integrated_deg)},
                     {"measured_angle_deg", t.measured_angle_deg},
                     {"used_angle_deg", t.used_angle_deg},
                     {"axis_tilt_deg", t.axis_tilt_deg}});
  }
  j["turns"] = turns;
  j["notes"] = r.notes;
  return j;
}

}  // namespace calstand::solver
