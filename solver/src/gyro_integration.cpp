#include "solver/gyro_integration.hpp"

#include <ceres/ceres.h>
#include <ceres/rotation.h>
#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <memory>

#include "ceres_solve.hpp"
#include "core/error.hpp"
#include "core/rotation.hpp"
#include "core/site.hpp"

namespace calstand::solver {

namespace {

constexpr const char* kGyroWhere = "gyro integration";
// Internal parameters: s x y z [1], m xy xz yx yz zx zy [rad], (bias x y z [deg/s]).
// (g-sensitivity G row-major [(deg/s)/g], after the bias when both are fitted).
constexpr int kGyroMax = 21;

// The gyro matrix inverse from the parameters, for any scalar type.
template <typename T>
void gyro_inverse(const T* p, T inv[9]) {
  const T a[9] = {1.0 + p[0], p[3], p[4], p[5], 1.0 + p[1], p[6], p[7], p[8], 1.0 + p[2]};
  const T c00 = a[4] * a[8] - a[5] * a[7];
  const T c01 = a[5] * a[6] - a[3] * a[8];
  const T c02 = a[3] * a[7] - a[4] * a[6];
  const T det = a[0] * c00 + a[1] * c01 + a[2] * c02;
  inv[0] = c00 / det;
  inv[1] = (a[2] * a[7] - a[1] * a[8]) / det;
  inv[2] = (a[1] * a[5] - a[2] * a[4]) / det;
  inv[3] = c01 / det;
  inv[4] = (a[0] * a[8] - a[2] * a[6]) / det;
  inv[5] = (a[2] * a[3] - a[0] * a[5]) / det;
  inv[6] = c02 / det;
  inv[7] = (a[1] * a[6] - a[0] * a[7]) / det;
  inv[8] = (a[0] * a[4] - a[1] * a[3]) / det;
}

struct TurnData {
  const core::ImuSample* samples = nullptr;
  std::size_t first = 0;  // last sample of the pose left
  std::size_t last = 0;   // first sample of the pose entered
  Eigen::Vector3d bias_dps = Eigen::Vector3d::Zero();
  Eigen::Vector3d u_start = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d e1 = Eigen::Vector3d::UnitX();
  Eigen::Vector3d e2 = Eigen::Vector3d::UnitY();
  double inv_sigma = 1.0;
  bool fit_bias = false;
  int g_offset = -1;  // index of G in the parameters, -1: not fitted
  // Calibrated specific force of each sample of the turn minus the rest's, over g0.
  std::vector<Eigen::Vector3d> force_g;
};

// Integrates the calibrated rate over a turn: q = q_{B_start B_end} (w, x, y, z).
template <typename T>
void integrate_turn(const TurnData& d, const T* p, T q[4]) {
  T inv[9];
  gyro_inverse(p, inv);
  const double deg = core::kDegToRad;
  const auto calibrated = [&](std::size_t i, T w[3]) {
    T m[3];
    for (int a = 0; a < 3; ++a) {
      const T b = d.fit_bias ? p[9 + a] : T(d.bias_dps[a]);
      m[a] = T(d.samples[i].gyro_dps[a]) - b;
      if (d.g_offset >= 0) {
        const Eigen::Vector3d& f = d.force_g[i - d.first];
        for (int c = 0; c < 3; ++c) m[a] -= p[d.g_offset + 3 * a + c] * f[c];
      }
      m[a] *= deg;
    }
    for (int a = 0; a < 3; ++a)
      w[a] = inv[3 * a] * m[0] + inv[3 * a + 1] * m[1] + inv[3 * a + 2] * m[2];
  };
  q[0] = T(1.0);
  q[1] = q[2] = q[3] = T(0.0);
  T prev[3];
  calibrated(d.first, prev);
  for (std::size_t i = d.first; i < d.last; ++i) {
    T next[3];
    calibrated(i + 1, next);
    const double dt = d.samples[i + 1].receive_time_s - d.samples[i].receive_time_s;
    T theta[3];
    for (int a = 0; a < 3; ++a) theta[a] = 0.5 * (prev[a] + next[a]) * dt;
    T dq[4];
    ceres::AngleAxisToQuaternion(theta, dq);
    T out[4];
    ceres::QuaternionProduct(q, dq, out);
    for (int a = 0; a < 4; ++a) q[a] = out[a];
    for (int a = 0; a < 3; ++a) prev[a] = next[a];
  }
  // Keep it unit (rounding over hundreds of products).
  const T n = ceres::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  for (int a = 0; a < 4; ++a) q[a] = q[a] / n;
}

template <typename T>
void turn_residual(const TurnData& d, const T* p, T* r) {
  T q[4];
  integrate_turn(d, p, q);
  // Predicted direction at the end: R^T u_start = rotate by the conjugate.
  const T qc[4] = {q[0], -q[1], -q[2], -q[3]};
  const T u[3] = {T(d.u_start[0]), T(d.u_start[1]), T(d.u_start[2])};
  T pred[3];
  ceres::UnitQuaternionRotatePoint(qc, u, pred);
  r[0] = (d.e1[0] * pred[0] + d.e1[1] * pred[1] + d.e1[2] * pred[2]) * d.inv_sigma;
  r[1] = (d.e2[0] * pred[0] + d.e2[1] * pred[1] + d.e2[2] * pred[2]) * d.inv_sigma;
}

struct TurnResidual {
  TurnData d;
  template <typename T>
  bool operator()(const T* p, T* r) const {
    turn_residual(d, p, r);
    return true;
  }
};

// The accel mean of a hold referred to its first (at_end false) or last sample by the gyro,
// the hold's own mean rate removed.
Eigen::Vector3d referred_mean(std::span<const core::ImuSample> s, std::size_t begin,
                              std::size_t end, bool at_end) {
  Eigen::Vector3d mean_rate = Eigen::Vector3d::Zero();
  for (std::size_t k = begin; k < end; ++k) mean_rate += s[k].gyro_dps;
  mean_rate /= static_cast<double>(end - begin);
  const std::size_t n = end - begin;
  std::vector<Eigen::Vector3d> phi(n, Eigen::Vector3d::Zero());  // from the first sample
  for (std::size_t k = 1; k < n; ++k) {
    const std::size_t i = begin + k;
    const double dt = s[i].receive_time_s - s[i - 1].receive_time_s;
    phi[k] = phi[k - 1] +
             0.5 * (s[i].gyro_dps + s[i - 1].gyro_dps - 2.0 * mean_rate) * dt * core::kDegToRad;
  }
  Eigen::Vector3d m = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k < n; ++k) {
    const Eigen::Vector3d& a = s[begin + k].accel_mps2;
    if (at_end) {
      const Eigen::Vector3d to_end = phi[n - 1] - phi[k];  // integral from t_k to the end
      m += a - to_end.cross(a);
    } else {
      m += a + phi[k].cross(a);
    }
  }
  return m / static_cast<double>(n);
}

// A unit basis across u.
void across(const Eigen::Vector3d& u, Eigen::Vector3d& e1, Eigen::Vector3d& e2) {
  Eigen::Vector3d t = std::abs(u.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  e1 = (t - t.dot(u) * u).normalized();
  e2 = u.cross(e1);
}

TriadModel gyro_model(const double* p, bool fit_bias, const Eigen::Vector3d& rest_bias) {
  // (G, when fitted, is read by the caller.)
  TriadModel m;
  m.bias = fit_bias ? Eigen::Vector3d(p[9], p[10], p[11]) : rest_bias;
  m.scale_ppm = 1e6 * Eigen::Vector3d(p[0], p[1], p[2]);
  m.misalignment(0, 1) = p[3];
  m.misalignment(0, 2) = p[4];
  m.misalignment(1, 0) = p[5];
  m.misalignment(1, 2) = p[6];
  m.misalignment(2, 0) = p[7];
  m.misalignment(2, 1) = p[8];
  return m;
}

struct GyroHold {
  std::size_t interval;
  Eigen::Vector3d m_start;  // raw accel means referred to the first / last sample
  Eigen::Vector3d m_end;
  double sigma_dir;  // rad, per component across gravity
};

}  // namespace

GyroIntegrationResult calibrate_gyro_integration(std::span<const core::ImuSample> samples,
                                                 std::span<const StaticInterval> intervals,
                                                 const GravityNormResult& accel,
                                                 const GyroIntegrationOptions& o) {
  GyroIntegrationResult out;
  const StaticInterval* rest = nullptr;
  for (const StaticInterval& in : intervals) {
    if (in.end > samples.size() || in.begin >= in.end) {
      throw core::InputError(kGyroWhere, "an interval lies outside the samples");
    }
    if (in.initial_rest && rest == nullptr) rest = &in;
  }
  if (rest == nullptr) {
    throw core::InputError(kGyroWhere,
                           "no initial rest among the intervals: the gyro bias comes "
                           "from it (record a rest of some tens of seconds first)");
  }
  const int needed = std::max(o.min_poses, 6);
  if (static_cast<int>(intervals.size()) < needed) {
    throw core::InputError(kGyroWhere, fmt::format("{} static poses are needed (turns between them "
                                                   "determine 9 gyro parameters), found {}",
                                                   needed, intervals.size()));
  }
  const double g = accel.gravity_mps2;
  const StaticMean rest_mean = static_mean(samples, rest->begin, rest->end, TriadSensor::kGyro);
  out.rest_bias_dps = rest_mean.mean;
  out.rest_bias_sigma_dps = rest_mean.sigma_of_mean;
  out.rest_duration_s = rest->duration_s();
  const double white_dps = std::sqrt(rest_mean.sample_sigma.cwiseAbs2().mean());

  // Holds: referred means and direction sigma.
  std::vector<GyroHold> holds;
  for (std::size_t i = 0; i < intervals.size(); ++i) {
    const StaticInterval& in = intervals[i];
    const StaticMean am = static_mean(samples, in.begin, in.end, TriadSensor::kAccel);
    GyroHold h;
    h.interval = i;
    if (o.refer_hold_means) {
      h.m_start = referred_mean(samples, in.begin, in.end, false);
      h.m_end = referred_mean(samples, in.begin, in.end, true);
    } else {
      h.m_start = h.m_end = am.mean;
    }
    h.sigma_dir = std::sqrt(am.sigma_of_mean.cwiseAbs2().mean()) / g;
    holds.push_back(h);
  }

  const double earth_dps = core::kEarthRateRadPerS * core::kRadToDeg;
  const Eigen::Vector3d rest_accel =
      static_mean(samples, rest->begin, rest->end, TriadSensor::kAccel).mean;
  // The accelerometer model corrects every reading the same way the accel fit does (with its
  // quadratic when fitted).
  const auto make_turns = [&](const TriadModel& a_model, const Eigen::Vector3d& a_quadratic,
                              const Eigen::Vector3d& bias) {
    const auto correct = [&](const Eigen::Vector3d& m) {
      return correct_accel(a_model, a_quadratic, m);
    };
    std::vector<TurnData> turns;
    for (std::size_t k = 0; k + 1 < holds.size(); ++k) {
      const StaticInterval& from = intervals[holds[k].interval];
      const StaticInterval& to = intervals[holds[k + 1].interval];
      TurnData d;
      d.samples = samples.data();
      d.first = from.end - 1;
      d.last = to.begin;
      d.bias_dps = bias;
      d.fit_bias = o.fit_bias;
      if (o.fit_g_sensitivity) {
        d.g_offset = o.fit_bias ? 12 : 9;
        const Eigen::Vector3d f_rest = correct(rest_accel);
        for (std::size_t i = d.first; i <= d.last; ++i) {
          d.force_g.push_back((correct(samples[i].accel_mps2) - f_rest) / core::kStandardGravity);
        }
      }
      d.u_start = correct(holds[k].m_end).normalized();
      const Eigen::Vector3d u_end = correct(holds[k + 1].m_start).normalized();
      across(u_end, d.e1, d.e2);
      const double duration = samples[d.last].receive_time_s - samples[d.first].receive_time_s;
      const double dt = duration / static_cast<double>(std::max<std::size_t>(1, d.last - d.first));
      const double arw = white_dps * core::kDegToRad * std::sqrt(dt * duration);
      const double sigma = std::sqrt(holds[k].sigma_dir * holds[k].sigma_dir +
                                     holds[k + 1].sigma_dir * holds[k + 1].sigma_dir + arw * arw);
      d.inv_sigma = 1.0 / std::max(sigma, 1e-9);
      turns.push_back(d);
    }
    return turns;
  };
  std::vector<TurnData> turns =
      make_turns(accel.accel, accel.quadratic_ug_per_g2, out.rest_bias_dps);

  const int np = 9 + (o.fit_bias ? 3 : 0) + (o.fit_g_sensitivity ? 9 : 0);
  const int g_offset = o.fit_g_sensitivity ? (o.fit_bias ? 12 : 9) : -1;
  std::vector<std::unique_ptr<ceres::CostFunction>> costs;
  for (const TurnData& d : turns) {
    switch (np) {
      case 9:
        costs.emplace_back(
            new ceres::AutoDiffCostFunction<TurnResidual, 2, 9>(new TurnResidual{d}));
        break;
      case 12:
        costs.emplace_back(
            new ceres::AutoDiffCostFunction<TurnResidual, 2, 12>(new TurnResidual{d}));
        break;
      case 18:
        costs.emplace_back(
            new ceres::AutoDiffCostFunction<TurnResidual, 2, 18>(new TurnResidual{d}));
        break;
      default:
        costs.emplace_back(
            new ceres::AutoDiffCostFunction<TurnResidual, 2, 21>(new TurnResidual{d}));
        break;
    }
  }
  std::array<double, kGyroMax> p{};
  for (int a = 0; a < 3; ++a) p[static_cast<std::size_t>(9 + a)] = out.rest_bias_dps[a];

  // Solves with `fixed` held at their values in p (max_iterations 0: evaluates only), then the
  // weighted Jacobian and residuals at p.
  const auto solve = [&](const std::vector<int>& fixed, int max_iterations, Eigen::MatrixXd& J,
                         Eigen::VectorXd& r) {
    if (max_iterations > 0) {
      ceres::Problem::Options po;
      po.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
      ceres::Problem problem(po);
      for (const auto& c : costs) problem.AddResidualBlock(c.get(), nullptr, p.data());
      const detail::CeresOutcome solved =
          detail::solve_holding(problem, p.data(), np, fixed, max_iterations);
      out.iterations = solved.iterations;
      out.converged = solved.converged;
    }
    const auto rows = static_cast<Eigen::Index>(2 * costs.size());
    J.resize(rows, np);
    r.resize(rows);
    const double* params[] = {p.data()};
    std::vector<double> jac(static_cast<std::size_t>(2 * np));
    double* jacs[] = {jac.data()};
    for (std::size_t k = 0; k < costs.size(); ++k) {
      double res[2];
      costs[k]->Evaluate(params, res, jacs);
      for (int row = 0; row < 2; ++row) {
        const auto R = static_cast<Eigen::Index>(2 * k + static_cast<std::size_t>(row));
        r[R] = res[row];
        for (int j = 0; j < np; ++j) J(R, j) = jac[static_cast<std::size_t>(row * np + j)];
      }
    }
  };

  // What the turns determine is judged at the nominal gyro (T_g = I), then the fit.
  Eigen::MatrixXd J;
  Eigen::VectorXd r;
  solve({}, 0, J, r);
  // A 100 deg/s bias (or 100 (deg/s)/g) moves a turn like a unit scale error.
  Eigen::VectorXd natural = Eigen::VectorXd::Ones(np);
  natural.tail(np - 9).setConstant(100.0);
  const std::vector<int> fixed = undetermined_columns(J, natural, o.null_tolerance);
  solve(fixed, o.max_iterations, J, r);  // undetermined ones held at nominal (0)
  std::vector<bool> is_fixed(static_cast<std::size_t>(np), false);
  for (int j : fixed) is_fixed[static_cast<std::size_t>(j)] = true;
  out.gyro = gyro_model(p.data(), o.fit_bias, out.rest_bias_dps);

  // Covariance in internal units, free parameters.
  std::vector<int> free;
  for (int j = 0; j < np; ++j) {
    if (!is_fixed[static_cast<std::size_t>(j)]) free.push_back(j);
  }
  const auto nf = static_cast<Eigen::Index>(free.size());
  Eigen::MatrixXd Jf(J.rows(), nf);
  for (Eigen::Index c = 0; c < nf; ++c) Jf.col(c) = J.col(free[static_cast<std::size_t>(c)]);
  const Eigen::MatrixXd H = Jf.transpose() * Jf;
  const Eigen::MatrixXd Hinv = H.ldlt().solve(Eigen::MatrixXd::Identity(nf, nf));
  out.chi2 = r.squaredNorm();
  out.dof = static_cast<int>(r.size()) - static_cast<int>(nf);
  out.chi2_per_dof = out.dof > 0 ? out.chi2 / out.dof : 0.0;
  if (o.scale_sigmas_by_residual && out.dof > 0 && out.chi2_per_dof > 1.0) {
    out.sigma_scale = std::sqrt(out.chi2_per_dof);
    out.sigmas_scaled = true;
  }
  Eigen::MatrixXd cov = Hinv * out.sigma_scale * out.sigma_scale;

  // What the accelerometer calibration and the rest bias carry in: q = (accel 9, or 12 with
  // its quadratic, internal; bias 3 [deg/s] when not fitted).
  const int na = accel.covariance.rows() == 12 ? 12 : 9;
  const int nq = na + (o.fit_bias ? 0 : 3);
  Eigen::MatrixXd Sq = Eigen::MatrixXd::Zero(nq, nq);
  if (o.propagate_accel_covariance && accel.covariance.rows() == na) {
    // accel covariance: contract (ppm, ug/g^2) -> internal (1) for scale and quadratic.
    Eigen::VectorXd to_internal = Eigen::VectorXd::Ones(na);
    to_internal.segment<3>(3).setConstant(1e-6);
    if (na == 12) to_internal.segment<3>(9).setConstant(1e-6);
    Sq.topLeftCorner(na, na) =
        to_internal.asDiagonal() * accel.covariance * to_internal.asDiagonal();
  }
  if (!o.fit_bias) {
    Sq.bottomRightCorner(3, 3) = out.rest_bias_sigma_dps.cwiseAbs2().asDiagonal();
  }
  // Accelerometer parameters the poses did not determine (held): a gyro parameter that moves
  // with one of them is relative to a frame the poses do not fix (e.g. poses that never tip y
  // leave the frame's rotation about x open, and with it gyro_misalignment.zy).
  std::vector<int> accel_held;
  for (int j = 0; j < na; ++j) {
    // into the estimates: 12 of the triad, then the quadratic's 3
    static const int est_index[] = {0, 1, 2, 3, 4, 5, 8, 10, 11, 12, 13, 14};
    const auto e = static_cast<std::size_t>(est_index[j]);
    if (e >= accel.parameters.size()) break;
    if (accel.parameters[e].status == EstimateStatus::kUndetermined) {
      accel_held.push_back(j);
    }
  }
  std::vector<bool> frame_open(static_cast<std::size_t>(np), false);
  if ((Sq.norm() > 0.0 || !accel_held.empty()) && nf > 0) {
    const auto residuals_at = [&](const Eigen::VectorXd& q) {
      TriadModel a = accel.accel;
      a.bias += q.head<3>();
      a.scale_ppm += 1e6 * q.segment<3>(3);
      a.misalignment(1, 0) += q[6];
      a.misalignment(2, 0) += q[7];
      a.misalignment(2, 1) += q[8];
      Eigen::Vector3d quadratic = accel.quadratic_ug_per_g2;
      if (na == 12) quadratic += 1e6 * q.segment<3>(9);
      Eigen::Vector3d b = out.rest_bias_dps;
      if (!o.fit_bias) b += q.tail<3>();
      const std::vector<TurnData> t = make_turns(a, quadratic, b);
      Eigen::VectorXd res(static_cast<Eigen::Index>(2 * t.size()));
      for (std::size_t k = 0; k < t.size(); ++k) {
        double rr[2];
        turn_residual(t[k], p.data(), rr);
        res[static_cast<Eigen::Index>(2 * k)] = rr[0];
        res[static_cast<Eigen::Index>(2 * k + 1)] = rr[1];
      }
      return res;
    };
    Eigen::MatrixXd A(r.size(), nq);
    for (int j = 0; j < nq; ++j) {
      const double sj = std::sqrt(Sq(j, j));
      if (!(sj > 0.0)) {
        A.col(j).setZero();
        continue;
      }
      Eigen::VectorXd dq = Eigen::VectorXd::Zero(nq);
      dq[j] = sj;
      A.col(j) = (residuals_at(dq) - residuals_at(-dq)) / (2.0 * sj);
    }
    const Eigen::MatrixXd K = -Hinv * Jf.transpose() * A;
    cov += K * Sq * K.transpose();
    // Natural units of the accel parameters: bias g, scale, misalignment and quadratic 1.
    for (int q : accel_held) {
      const double h = 1e-4 * (q < 3 ? g : 1.0);
      Eigen::VectorXd dq = Eigen::VectorXd::Zero(nq);
      dq[q] = h;
      const Eigen::VectorXd a_col = (residuals_at(dq) - residuals_at(-dq)) / (2.0 * h);
      const Eigen::VectorXd k = -Hinv * Jf.transpose() * a_col;
      for (Eigen::Index c = 0; c < nf; ++c) {
        const int j = free[static_cast<std::size_t>(c)];
        const double natural_j = j >= 9 ? 100.0 : 1.0;  // bias, G: as `natural` above
        if (std::abs(k[c]) * (q < 3 ? g : 1.0) / natural_j > 0.1) {
          frame_open[static_cast<std::size_t>(j)] = true;
        }
      }
    }
  }

  // To contract units and the output order (bias, scale, misalignment[, G]).
  // internal index -> output index: s 0..2 -> 3..5, m 3..8 -> 6..11, bias 9..11 -> 0..2,
  // G g_offset.. -> 12..20.
  const int n_out = o.fit_g_sensitivity ? 21 : 12;
  out.covariance = Eigen::MatrixXd::Zero(n_out, n_out);
  const auto contract_index = [&](int j) {
    if (j < 9) return j + 3;
    if (g_offset >= 0 && j >= g_offset) return 12 + (j - g_offset);
    return j - 9;
  };
  const auto contract_unit = [](int j) { return j < 3 ? 1e6 : 1.0; };
  for (Eigen::Index a = 0; a < nf; ++a) {
    for (Eigen::Index b = 0; b < nf; ++b) {
      const int i = free[static_cast<std::size_t>(a)];
      const int j = free[static_cast<std::size_t>(b)];
      out.covariance(contract_index(i), contract_index(j)) =
          cov(a, b) * contract_unit(i) * contract_unit(j);
    }
  }
  if (!o.fit_bias) {
    for (int a = 0; a < 3; ++a)
      out.covariance(a, a) = out.rest_bias_sigma_dps[a] * out.rest_bias_sigma_dps[a];
  }
  if (g_offset >= 0) {
    // The bias parameter is the bias at the rest's orientation, b + G f_rest / g0: the
    // contract's bias is b = that - G f_rest / g0.
    const Eigen::Vector3d f_rest = correct_accel(accel, rest_accel) / core::kStandardGravity;
    Eigen::MatrixXd L = Eigen::MatrixXd::Identity(n_out, n_out);
    for (int i = 0; i < 3; ++i) {
      for (int k = 0; k < 3; ++k) {
        L(i, 12 + 3 * i + k) = -f_rest[k];
        out.gyro.bias[i] -= p[static_cast<std::size_t>(g_offset + 3 * i + k)] * f_rest[k];
      }
    }
    out.covariance = L * out.covariance * L.transpose();
  }
  out.parameters = triad_estimates("gyro", out.gyro);
  std::vector<std::string> names = triad_parameter_names("gyro");
  if (g_offset >= 0) {
    static const char* axes = "xyz";
    for (int i = 0; i < 3; ++i) {
      for (int k = 0; k < 3; ++k) {
        const std::string name = std::string("gyro_g_sensitivity.") + axes[i] + axes[k];
        const double v = p[static_cast<std::size_t>(g_offset + 3 * i + k)];
        out.g_sensitivity(i, k) = v;
        out.parameters.push_back({name, v, 0.0, "(deg/s)/g", EstimateStatus::kEstimated});
        names.push_back(name);
      }
    }
  }
  for (int j = 0; j < np; ++j) {
    const int c = contract_index(j);
    if (is_fixed[static_cast<std::size_t>(j)] || frame_open[static_cast<std::size_t>(j)]) {
      out.parameters[static_cast<std::size_t>(c)].status = EstimateStatus::kUndetermined;
      out.undetermined.push_back(names[static_cast<std::size_t>(c)]);
      if (frame_open[static_cast<std::size_t>(j)]) {
        out.frame_open.push_back(names[static_cast<std::size_t>(c)]);
        out.covariance.row(c).setZero();
        out.covariance.col(c).setZero();
      }
    }
  }
  for (int c = 0; c < n_out; ++c) {
    out.parameters[static_cast<std::size_t>(c)].sigma =
        std::sqrt(std::max(0.0, out.covariance(c, c)));
  }

  // Turns in words.
  double sum_sq = 0.0, earth_sq = 0.0;
  for (std::size_t k = 0; k < turns.size(); ++k) {
    const TurnData& d = turns[k];
    double q[4];
    integrate_turn(d, p.data(), q);
    const Eigen::Quaterniond Q(q[0], q[1], q[2], q[3]);
    const Eigen::AngleAxisd aa(Q);
    double rr[2];
    turn_residual(d, p.data(), rr);
    GyroTurn t;
    t.from_interval = holds[k].interval;
    t.to_interval = holds[k + 1].interval;
    t.start_s = samples[d.first].receive_time_s;
    t.end_s = samples[d.last].receive_time_s;
    t.samples = d.last - d.first + 1;
    t.angle_deg = aa.angle() * core::kRadToDeg;
    t.axis_A = aa.axis();
    t.sigma_deg = core::kRadToDeg / d.inv_sigma;
    t.residual_deg = std::hypot(rr[0], rr[1]) / d.inv_sigma * core::kRadToDeg;
    t.earth_rate_bound_deg = 2.0 * earth_dps * (t.end_s - t.start_s);
    sum_sq += t.residual_deg * t.residual_deg;
    earth_sq += 0.5 * t.earth_rate_bound_deg * t.earth_rate_bound_deg;
    out.max_residual_deg = std::max(out.max_residual_deg, t.residual_deg);
    out.turns.push_back(t);
  }
  const double nt = static_cast<double>(std::max<std::size_t>(1, out.turns.size()));
  out.rms_residual_deg = std::sqrt(sum_sq / nt);
  out.earth_rate_rms_deg = std::sqrt(earth_sq / nt);

  std::string quality;
  if (out.dof <= 0) {
    quality = "no redundancy: sigmas from the noise alone";
  } else if (out.sigmas_scaled) {
    quality = fmt::format(
        "chi2/dof {:.3g} against the accel direction and gyro white noise: "
        "sigmas scaled by {:.3g}",
        out.chi2_per_dof, out.sigma_scale);
  } else {
    quality = fmt::format("chi2/dof {:.3g}: the turns agree to their noise", out.chi2_per_dof);
  }
  std::string missing = "every parameter is determined";
  std::vector<std::string> by_turns;
  for (const std::string& n : out.undetermined) {
    if (std::find(out.frame_open.begin(), out.frame_open.end(), n) == out.frame_open.end()) {
      by_turns.push_back(n);
    }
  }
  const auto join = [](const std::vector<std::string>& v) {
    std::string t;
    for (std::size_t i = 0; i < v.size(); ++i) t += (i > 0 ? ", " : "") + v[i];
    return t;
  };
  std::vector<std::string> clauses;
  if (!by_turns.empty()) {
    clauses.push_back("the turns do not determine " + join(by_turns) +
                      " (held at 0: turn about those axes too)");
  }
  if (!out.frame_open.empty()) {
    clauses.push_back(join(out.frame_open) +
                      " undetermined as well: fitted, but relative to an accelerometer frame "
                      "the poses do not fix");
  }
  if (!clauses.empty()) missing = join(clauses);
  out.summary = fmt::format(
      "gyro by integration over {} turns between static poses: gravity direction after each "
      "turn off by {:.3g} deg RMS (largest {:.3g} deg); {}; {}; the Earth rate ({:.4f} deg/s, "
      "not modelled) can move it by about {:.2g} deg RMS over these turns; bias from the "
      "{:.3g} s initial rest (includes the Earth rate there, at most {:.4f} deg/s)",
      out.turns.size(), out.rms_residual_deg, out.max_residual_deg, quality, missing, earth_dps,
      out.earth_rate_rms_deg, out.rest_duration_s, earth_dps);
  return out;
}

nlohmann::json gyro_integration_to_json(const GyroIntegrationResult& r) {
  nlohmann::json j;
  j["method"] = "gyro_integration";
  j["frame"] = kAccelTriadFrameText;
  j["parameters"] = triad_estimates_to_json(r.parameters);
  nlohmann::json rows = nlohmann::json::array();
  nlohmann::json names = nlohmann::json::array();
  for (const TriadEstimate& e : r.parameters) names.push_back(e.name);
  for (Eigen::Index i = 0; i < r.covariance.rows(); ++i) {
    nlohmann::json row = nlohmann::json::array();
    for (Eigen::Index k = 0; k < r.covariance.cols(); ++k) row.push_back(r.covariance(i, k));
    rows.push_back(row);
  }
  j["covariance"] = {{"names", names}, {"matrix", rows}};
  j["undetermined"] = r.undetermined;
  j["frame_open"] = r.frame_open;
  j["rest"] = {{"duration_s", r.rest_duration_s},
               {"bias_dps", {r.rest_bias_dps.x(), r.rest_bias_dps.y(), r.rest_bias_dps.z()}},
               {"bias_sigma_dps",
                {r.rest_bias_sigma_dps.x(), r.rest_bias_sigma_dps.y(), r.rest_bias_sigma_dps.z()}}};
  j["quality"] = {{"turns", r.turns.size()},
                  {"rms_residual_deg", r.rms_residual_deg},
                  {"max_residual_deg", r.max_residual_deg},
                  {"chi2", r.chi2},
                  {"dof", r.dof},
                  {"chi2_per_dof", r.chi2_per_dof},
                  {"sigma_scale", r.sigma_scale},
                  {"sigmas_scaled", r.sigmas_scaled},
                  {"earth_rate_rms_deg", r.earth_rate_rms_deg},
                  {"summary", r.summary}};
  nlohmann::json turns = nlohmann::json::array();
  for (const GyroTurn& t : r.turns) {
    turns.push_back({{"from", t.from_interval},
                     {"to", t.to_interval},
                     {"start_s", t.start_s},
                     {"end_s", t.end_s},
                     {"samples", t.samples},
                     {"angle_deg", t.angle_deg},
                     {"axis_A", {t.axis_A.x(), t.axis_A.y(), t.axis_A.z()}},
                     {"residual_deg", t.residual_deg},
                     {"sigma_deg", t.sigma_deg},
                     {"earth_rate_bound_deg", t.earth_rate_bound_deg}});
  }
  j["turns"] = turns;
  j["solver"] = {{"iterations", r.iterations}, {"converged", r.converged}};
  return j;
}

}  // namespace calstand::solver
