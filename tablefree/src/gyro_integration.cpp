#include "tablefree/gyro_integration.hpp"

#include <ceres/ceres.h>
#include <ceres/rotation.h>
#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <numbers>

#include "ceres_solve.hpp"
#include "core/error.hpp"
#include "core/rotation.hpp"
#include "core/site.hpp"

namespace calstand::solver {

namespace {

constexpr const char* kGyroWhere = "gyro integration";
// Internal parameters: s x y z [1], m xy xz yx yz zx zy [rad], (bias x y z [deg/s]).
// (g-sensitivity G row-major [(deg/s)/g], after the bias when both are fitted).
// (psi, the azimuth of North at the rest [rad], last when the Earth rate is modelled.)
constexpr int kGyroMax = 22;
// The heading of the rest counts as found when the turns fix it to this [rad]: the linearised
// sigma means something, and the horizontal Earth rate's part of the bias is known to a
// fraction of itself.
constexpr double kHeadingDeterminedRad = 0.5;

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
  Eigen::Vector3d u_end = Eigen::Vector3d::UnitZ();  // measured at the start of the next pose
  Eigen::Vector3d e1 = Eigen::Vector3d::UnitX();
  Eigen::Vector3d e2 = Eigen::Vector3d::UnitY();
  double inv_sigma = 1.0;
  bool fit_bias = false;
  int g_offset = -1;  // index of G in the parameters, -1: not fitted
  // Calibrated specific force of each sample of the turn minus the rest's, over g0.
  std::vector<Eigen::Vector3d> force_g;
  // The Earth rate [rad/s, frame A] when modelled (psi_index >= 0: the parameter psi, the
  // azimuth of North about gravity at the rest): W sin(lat) along gravity plus W cos(lat)
  // (cos psi h1 + sin psi h2) across it, h1 and h2 a horizontal basis. At the rest (what the
  // rest mean holds besides the bias) and at the turn's start (the rest's basis carried there
  // by the gyro, carry_north()).
  int psi_index = -1;
  Eigen::Vector3d rest_vertical = Eigen::Vector3d::Zero();
  Eigen::Vector3d rest_h1 = Eigen::Vector3d::Zero();
  Eigen::Vector3d rest_h2 = Eigen::Vector3d::Zero();
  Eigen::Vector3d start_vertical = Eigen::Vector3d::Zero();
  Eigen::Vector3d start_h1 = Eigen::Vector3d::Zero();
  Eigen::Vector3d start_h2 = Eigen::Vector3d::Zero();
};

// The Earth rate [rad/s] vertical + cos(psi) h1 + sin(psi) h2.
template <typename T>
void earth_rate_at(const Eigen::Vector3d& vertical, const Eigen::Vector3d& h1,
                   const Eigen::Vector3d& h2, const T& psi, T w[3]) {
  const T c = ceres::cos(psi);
  const T s = ceres::sin(psi);
  for (int a = 0; a < 3; ++a) w[a] = T(vertical[a]) + c * h1[a] + s * h2[a];
}

// Integrates the calibrated rate over a turn: q = q_{B_start B_end} (w, x, y, z), the rotation
// of the body in an inertial frame (the gyro's). The bias is the rest mean, which holds the
// Earth rate at the rest as well: w = T_g^-1 (w_meas - rest mean) + w_ie(rest).
template <typename T>
void integrate_turn(const TurnData& d, const T* p, T q[4]) {
  T inv[9];
  gyro_inverse(p, inv);
  const double deg = core::kDegToRad;
  T earth_rest[3] = {T(0.0), T(0.0), T(0.0)};
  if (d.psi_index >= 0 && !d.fit_bias) {
    earth_rate_at(d.rest_vertical, d.rest_h1, d.rest_h2, p[d.psi_index], earth_rest);
  }
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
    for (int a = 0; a < 3; ++a) {
      w[a] = inv[3 * a] * m[0] + inv[3 * a + 1] * m[1] + inv[3 * a + 2] * m[2] + earth_rest[a];
    }
  };
  q[0] = T(1.0);
  q[1] = q[2] = q[3] = T(0.0);
  T prev[3];
  calibrated(d.first, prev);
  for (std::size_t i = d.first; i < d.last; ++i) {
    T next[3];
    calibrated(i + 1, next);
    const double dt = d.samples[i + 1].receive_time_s - d.samples[i].receive_time_s;
    // The rotation vector of a rate linear over the interval, to second order (Bortz):
    // the trapezoid plus (w_i x w_i+1) dt^2 / 12, the coning term a turn whose axis moves
    // (the hand's swing) makes at every sample.
    T theta[3];
    T cross[3];
    ceres::CrossProduct(prev, next, cross);
    for (int a = 0; a < 3; ++a) {
      theta[a] = 0.5 * (prev[a] + next[a]) * dt + cross[a] * (dt * dt / 12.0);
    }
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
  T u[3] = {T(d.u_start[0]), T(d.u_start[1]), T(d.u_start[2])};
  if (d.psi_index >= 0) {
    // Gravity is fixed in the level frame, which turns with the Earth: in the inertial frame
    // of the turn's start it has turned by w_ie(start) times the turn's duration when the
    // turn ends (only the horizontal part moves it).
    const double duration = d.samples[d.last].receive_time_s - d.samples[d.first].receive_time_s;
    T w[3];
    earth_rate_at(d.start_vertical, d.start_h1, d.start_h2, p[d.psi_index], w);
    T angle_axis[3] = {w[0] * duration, w[1] * duration, w[2] * duration};
    T moved[3];
    ceres::AngleAxisRotatePoint(angle_axis, u, moved);
    for (int a = 0; a < 3; ++a) u[a] = moved[a];
  }
  // Predicted direction at the end: R^T u_start = rotate by the conjugate.
  const T qc[4] = {q[0], -q[1], -q[2], -q[3]};
  T pred[3];
  ceres::UnitQuaternionRotatePoint(qc, u, pred);
  r[0] = (d.e1[0] * pred[0] + d.e1[1] * pred[1] + d.e1[2] * pred[2]) * d.inv_sigma;
  r[1] = (d.e2[0] * pred[0] + d.e2[1] * pred[1] + d.e2[2] * pred[2]) * d.inv_sigma;
}

struct TurnResidual {
  const TurnData* d;  // owned by the caller's vector, which outlives the cost
  template <typename T>
  bool operator()(const T* p, T* r) const {
    turn_residual(*d, p, r);
    return true;
  }
};

template <int N>
ceres::CostFunction* turn_cost(const TurnData* d) {
  return new ceres::AutoDiffCostFunction<TurnResidual, 2, N>(new TurnResidual{d});
}

// The cost of one turn over `np` parameters (9 scale and misalignment, then 3 bias, 9 G and
// psi as fitted).
ceres::CostFunction* make_turn_cost(const TurnData* d, int np) {
  switch (np) {
    case 9:
      return turn_cost<9>(d);
    case 10:
      return turn_cost<10>(d);
    case 12:
      return turn_cost<12>(d);
    case 13:
      return turn_cost<13>(d);
    case 18:
      return turn_cost<18>(d);
    case 19:
      return turn_cost<19>(d);
    case 21:
      return turn_cost<21>(d);
    default:
      return turn_cost<22>(d);
  }
}

// The accel mean of a hold referred to its first (at_end false) or last sample by the gyro,
// the hold's own mean rate removed.
Eigen::Vector3d referred_mean(std::span<const core::ImuSample> s, std::size_t begin,
                              std::size_t end, bool at_end,
                              const std::optional<Eigen::Vector3d>& still_rate_dps = {}) {
  Eigen::Vector3d mean_rate = Eigen::Vector3d::Zero();
  for (std::size_t k = begin; k < end; ++k) mean_rate += s[k].gyro_dps;
  mean_rate /= static_cast<double>(end - begin);
  if (still_rate_dps) mean_rate = *still_rate_dps;
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

// The gyro's noise as its initial rest shows it: the white density (from the rest mean's own
// sigma, which counts correlated samples: an output filter narrows the samples' scatter but
// not the integrated noise) and the wander of the bias beyond it (the overlapping Allan
// variance at a quarter of the rest less the white part, doubled: the variance of the
// difference of two such means, the rest's and a turn's).
struct GyroRestNoise {
  double density_rad = 0.0;  // rad/s/sqrt(Hz)
  double wander_rad = 0.0;   // rad/s
};

GyroRestNoise gyro_rest_noise(std::span<const core::ImuSample> s, std::size_t begin,
                              std::size_t end) {
  GyroRestNoise out;
  const StaticMean m = static_mean(s, begin, end, TriadSensor::kGyro);
  const double duration = s[end - 1].receive_time_s - s[begin].receive_time_s;
  const std::size_t n = end - begin;
  if (n < 16 || !(duration > 0.0)) return out;
  const double dt = duration / static_cast<double>(n - 1);
  const std::size_t w = n / 4;
  const double tau = static_cast<double>(w) * dt;
  double density2 = 0.0, excess = 0.0;
  for (int a = 0; a < 3; ++a) {
    const double d = m.sigma_of_mean[a] * std::sqrt(duration) * core::kDegToRad;
    density2 += d * d / 3.0;
    // Overlapping Allan variance from cumulative sums.
    std::vector<double> c(n + 1, 0.0);
    for (std::size_t k = 0; k < n; ++k) c[k + 1] = c[k] + s[begin + k].gyro_dps[a];
    double sum = 0.0;
    std::size_t count = 0;
    for (std::size_t k = 0; k + 2 * w <= n; ++k) {
      const double m1 = (c[k + w] - c[k]) / static_cast<double>(w);
      const double m2 = (c[k + 2 * w] - c[k + w]) / static_cast<double>(w);
      sum += 0.5 * (m2 - m1) * (m2 - m1);
      ++count;
    }
    const double avar = sum / static_cast<double>(std::max<std::size_t>(1, count)) *
                        core::kDegToRad * core::kDegToRad;
    excess += std::max(0.0, avar - d * d / tau) / 3.0;
  }
  out.density_rad = std::sqrt(density2);
  out.wander_rad = std::sqrt(2.0 * excess);
  return out;
}

// A unit basis across u.
void across(const Eigen::Vector3d& u, Eigen::Vector3d& e1, Eigen::Vector3d& e2) {
  Eigen::Vector3d t = std::abs(u.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  e1 = (t - t.dot(u) * u).normalized();
  e2 = u.cross(e1);
}

// Carries the rest's horizontal basis (rest_e1, rest_e2) to the start of every turn and sets
// the turn's Earth rate there (W sin(lat) along the measured gravity, W cos(lat) times the
// carried basis): the gyro turns the basis over each turn (and the Earth turns the level frame
// under it), a hold keeps it (a hold does not turn on average), and each start's basis is made
// horizontal again against the gravity measured there. The carry needs no great accuracy: the
// horizontal Earth rate moves a turn's end by about W cos(lat) times its duration (1e-4 rad),
// so a heading off by 0.01 rad changes that by 1e-6 rad.
// `hold_earth`, when given, gets the Earth rate at every pose [rad/s, frame A]: the rest's,
// then the one after each turn.
void carry_north(std::vector<TurnData>& turns, const double* p, const Eigen::Vector3d& rest_e1,
                 const Eigen::Vector3d& rest_e2, double w_sin_lat, double w_cos_lat,
                 std::vector<Eigen::Vector3d>* hold_earth = nullptr) {
  Eigen::Vector3d a = rest_e1;
  Eigen::Vector3d b = rest_e2;
  if (hold_earth != nullptr && !turns.empty()) {
    const TurnData& d = turns.front();
    double w[3];
    earth_rate_at(d.rest_vertical, d.rest_h1, d.rest_h2, p[d.psi_index], w);
    hold_earth->assign(1, Eigen::Vector3d(w[0], w[1], w[2]));
  }
  for (TurnData& d : turns) {
    const Eigen::Vector3d& u = d.u_start;
    a = (a - a.dot(u) * u).normalized();
    b = u.cross(a);
    d.start_vertical = w_sin_lat * u;
    d.start_h1 = w_cos_lat * a;
    d.start_h2 = w_cos_lat * b;
    double q[4];
    integrate_turn(d, p, q);
    const Eigen::Quaterniond Q(q[0], q[1], q[2], q[3]);
    double w[3];
    earth_rate_at(d.start_vertical, d.start_h1, d.start_h2, p[d.psi_index], w);
    const double duration = d.samples[d.last].receive_time_s - d.samples[d.first].receive_time_s;
    const Eigen::Vector3d earth_turn = Eigen::Vector3d(w[0], w[1], w[2]) * duration;
    const double angle = earth_turn.norm();
    const Eigen::Matrix3d level =
        angle > 0.0 ? core::axis_angle(earth_turn / angle, angle) : Eigen::Matrix3d::Identity();
    a = Q.conjugate() * (level * a);
    b = Q.conjugate() * (level * b);
    if (hold_earth != nullptr) {
      const Eigen::Vector3d& v = d.u_end;
      const Eigen::Vector3d a_end = (a - a.dot(v) * v).normalized();
      const Eigen::Vector3d b_end = v.cross(a_end);
      const double psi = p[d.psi_index];
      hold_earth->push_back(w_sin_lat * v +
                            w_cos_lat * (std::cos(psi) * a_end + std::sin(psi) * b_end));
    }
  }
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
  double duration_s = 0.0;
  Eigen::Vector3d mean_rate_dps = Eigen::Vector3d::Zero();    // raw gyro mean
  Eigen::Vector3d mean_accel_mps2 = Eigen::Vector3d::Zero();  // raw accel mean
  // Mean square (per axis) of the angle the gyro turns within the pose, its mean rate removed,
  // about its mean [rad^2]: the sway and the gyro's noise, what a net turn is bounded by.
  double excursion_rad2 = 0.0;
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
  const GyroRestNoise rest_noise = gyro_rest_noise(samples, rest->begin, rest->end);
  const double density_rad = rest_noise.density_rad;
  const double wander_rad = rest_noise.wander_rad;

  // Holds: referred means and direction sigma. `still_dps`: the rate the hold has when it does
  // not turn (bias and Earth rate), per hold; empty: the hold's own mean rate (the first pass;
  // without the Earth rate, always). `referral_var`: what the referral adds to the direction's
  // variance per component [rad^2].
  const auto refer_holds = [&](const std::vector<std::optional<Eigen::Vector3d>>& still_dps,
                               const std::vector<double>& referral_var) {
    std::vector<GyroHold> out_holds;
    for (std::size_t i = 0; i < intervals.size(); ++i) {
      const StaticInterval& in = intervals[i];
      const StaticMean am = static_mean(samples, in.begin, in.end, TriadSensor::kAccel);
      GyroHold h;
      h.interval = i;
      h.duration_s = in.duration_s();
      h.mean_rate_dps = static_mean(samples, in.begin, in.end, TriadSensor::kGyro).mean;
      h.mean_accel_mps2 = am.mean;
      {
        std::vector<Eigen::Vector3d> phi(1, Eigen::Vector3d::Zero());
        for (std::size_t k = in.begin + 1; k < in.end; ++k) {
          const double dt = samples[k].receive_time_s - samples[k - 1].receive_time_s;
          phi.push_back(
              phi.back() +
              0.5 * (samples[k].gyro_dps + samples[k - 1].gyro_dps - 2.0 * h.mean_rate_dps) * dt *
                  core::kDegToRad);
        }
        Eigen::Vector3d mean = Eigen::Vector3d::Zero();
        for (const Eigen::Vector3d& x : phi) mean += x;
        mean /= static_cast<double>(phi.size());
        for (const Eigen::Vector3d& x : phi) h.excursion_rad2 += (x - mean).squaredNorm();
        h.excursion_rad2 /= 3.0 * static_cast<double>(phi.size());
      }
      // The accel mean's white noise and the wander its pose means share (the gravity norm's
      // noise model, REML): the wander moves the direction as much as the norm.
      double v =
          (am.sigma_of_mean.cwiseAbs2().mean() + accel.noise.pose_sigma * accel.noise.pose_sigma) /
          (g * g);
      if (o.refer_hold_means) {
        h.m_start = referred_mean(samples, in.begin, in.end, false, still_dps[i]);
        h.m_end = referred_mean(samples, in.begin, in.end, true, still_dps[i]);
        v += referral_var[i];
      } else {
        h.m_start = h.m_end = am.mean;
      }
      h.sigma_dir = std::sqrt(v);
      out_holds.push_back(h);
    }
    return out_holds;
  };
  std::vector<std::optional<Eigen::Vector3d>> still_dps(intervals.size());
  // Referred with its own mean rate, a hold's direction carries the gyro's white noise
  // integrated against (t/T - 1/2): N^2 T / 12 per component.
  std::vector<double> referral_var(intervals.size(), 0.0);
  for (std::size_t i = 0; i < intervals.size(); ++i) {
    referral_var[i] = density_rad * density_rad * intervals[i].duration_s() / 12.0;
  }
  const bool referrals_given = o.referrals.size() == intervals.size();
  if (referrals_given) {
    for (std::size_t i = 0; i < intervals.size(); ++i) {
      still_dps[i] = o.referrals[i].still_rate_dps;
      referral_var[i] = o.referrals[i].variance_rad2;
    }
  }
  std::vector<GyroHold> holds = refer_holds(still_dps, referral_var);

  const double earth_dps = core::kEarthRateRadPerS * core::kRadToDeg;
  const Eigen::Vector3d rest_accel =
      static_mean(samples, rest->begin, rest->end, TriadSensor::kAccel).mean;
  // The Earth rate (error-model.md: w_ie_L = W (0, cos(lat), sin(lat)) in ENU): along the
  // measured gravity W sin(lat), needing no heading; across it W cos(lat) towards North, whose
  // azimuth about gravity at the rest is the nuisance parameter psi.
  const bool earth = o.latitude_deg.has_value() && std::isfinite(*o.latitude_deg);
  out.earth_rate_modelled = earth;
  const double latitude_rad = earth ? *o.latitude_deg * core::kDegToRad : 0.0;
  const double w_sin_lat = core::kEarthRateRadPerS * std::sin(latitude_rad);
  const double w_cos_lat = core::kEarthRateRadPerS * std::cos(latitude_rad);
  if (earth) out.latitude_deg = *o.latitude_deg;

  const int np_gyro = 9 + (o.fit_bias ? 3 : 0) + (o.fit_g_sensitivity ? 9 : 0);
  const int psi_index = earth ? np_gyro : -1;
  const int np = np_gyro + (earth ? 1 : 0);
  const int g_offset = o.fit_g_sensitivity ? (o.fit_bias ? 12 : 9) : -1;
  // The noise of a turn's residual, each component across gravity [rad].
  const auto turn_sigma = [&](std::size_t first, std::size_t last, const GyroHold& from,
                              const GyroHold& to) {
    const double duration = samples[last].receive_time_s - samples[first].receive_time_s;
    // The gyro's white noise integrated over the turn, and its bias's wander since the rest
    // (the bias comes from there) integrated as a constant over the turn.
    const double white = density_rad * density_rad * duration;
    const double wander = wander_rad * wander_rad * duration * duration;
    return std::sqrt(from.sigma_dir * from.sigma_dir + to.sigma_dir * to.sigma_dir + white +
                     wander);
  };
  // The accelerometer model corrects every reading the same way the accel fit does (with its
  // quadratic when fitted).
  const auto make_turns = [&](const TriadModel& a_model, const Eigen::Vector3d& a_quadratic,
                              const Eigen::Vector3d& bias) {
    const auto correct = [&](const Eigen::Vector3d& m) {
      return correct_accel(a_model, a_quadratic, m);
    };
    const Eigen::Vector3d u_rest = correct(rest_accel).normalized();
    Eigen::Vector3d rest_e1, rest_e2;
    across(u_rest, rest_e1, rest_e2);
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
      if (earth) {
        d.psi_index = psi_index;
        d.rest_vertical = w_sin_lat * u_rest;
        d.rest_h1 = w_cos_lat * rest_e1;
        d.rest_h2 = w_cos_lat * rest_e2;
      }
      d.u_start = correct(holds[k].m_end).normalized();
      d.u_end = correct(holds[k + 1].m_start).normalized();
      across(d.u_end, d.e1, d.e2);
      const double sigma = turn_sigma(d.first, d.last, holds[k], holds[k + 1]);
      d.inv_sigma = 1.0 / std::max(sigma, 1e-9);
      turns.push_back(d);
    }
    return turns;
  };
  // The rest's horizontal basis, as make_turns() builds it, for carry_north().
  const auto rest_basis = [&](const TriadModel& a_model, const Eigen::Vector3d& a_quadratic) {
    const Eigen::Vector3d u_rest = correct_accel(a_model, a_quadratic, rest_accel).normalized();
    std::pair<Eigen::Vector3d, Eigen::Vector3d> e;
    across(u_rest, e.first, e.second);
    return e;
  };
  std::vector<TurnData> turns =
      make_turns(accel.accel, accel.quadratic_ug_per_g2, out.rest_bias_dps);
  std::array<double, kGyroMax> p{};
  for (int a = 0; a < 3; ++a) p[static_cast<std::size_t>(9 + a)] = out.rest_bias_dps[a];
  const auto carry = [&](std::vector<TurnData>& t, const TriadModel& a_model,
                         const Eigen::Vector3d& a_quadratic,
                         std::vector<Eigen::Vector3d>* hold_earth = nullptr) {
    if (!earth) return;
    const auto [e1, e2] = rest_basis(a_model, a_quadratic);
    carry_north(t, p.data(), e1, e2, w_sin_lat, w_cos_lat, hold_earth);
  };
  carry(turns, accel.accel, accel.quadratic_ug_per_g2);

  std::vector<std::unique_ptr<ceres::CostFunction>> costs;
  for (const TurnData& d : turns) costs.emplace_back(make_turn_cost(&d, np));

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
      out.iterations += solved.iterations;
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

  // What the turns determine is judged at the nominal gyro (T_g = I), then the fit. psi is no
  // gyro parameter: its effect is the Earth rate's, far below a scale error's, and it is held
  // only where there is no horizontal Earth rate (at a pole).
  Eigen::MatrixXd J;
  Eigen::VectorXd r;
  solve({}, 0, J, r);
  // A 100 deg/s bias (or 100 (deg/s)/g) moves a turn like a unit scale error.
  Eigen::VectorXd natural = Eigen::VectorXd::Ones(np_gyro);
  natural.tail(np_gyro - 9).setConstant(100.0);
  std::vector<int> fixed = undetermined_columns(J.leftCols(np_gyro), natural, o.null_tolerance);
  const bool fit_psi = earth && std::abs(w_cos_lat) > 1e-6 * core::kEarthRateRadPerS;
  if (earth && !fit_psi) fixed.push_back(psi_index);
  if (fit_psi) {
    // The heading enters through cos(psi) and sin(psi) only: fit the gyro with psi held,
    // start psi where the residual, nearly linear in (cos psi, sin psi), is least, then fit
    // both (the carried basis refreshed with the gyro found: it moves with the scale).
    std::vector<int> held = fixed;
    held.push_back(psi_index);
    solve(held, o.max_iterations, J, r);
    const auto residual_at = [&](double psi) {
      p[static_cast<std::size_t>(psi_index)] = psi;
      solve(held, 0, J, r);
      return Eigen::VectorXd(r);
    };
    const Eigen::VectorXd r0 = residual_at(0.0);
    const Eigen::VectorXd r90 = residual_at(0.5 * std::numbers::pi);
    const Eigen::VectorXd r180 = residual_at(std::numbers::pi);
    const Eigen::VectorXd mid = 0.5 * (r0 + r180);
    Eigen::MatrixXd A(r0.size(), 2);
    A.col(0) = 0.5 * (r0 - r180);
    A.col(1) = r90 - mid;
    const Eigen::Vector2d cs = A.colPivHouseholderQr().solve(-mid);
    p[static_cast<std::size_t>(psi_index)] = std::atan2(cs[1], cs[0]);
    for (int pass = 0; pass < 2; ++pass) {
      carry(turns, accel.accel, accel.quadratic_ug_per_g2);
      solve(fixed, o.max_iterations, J, r);
    }
  } else {
    solve(fixed, o.max_iterations, J, r);  // undetermined ones held at nominal (0)
  }
  // Two rounds: the second with the gyro, G and heading the first one found with better holds.
  for (int round = 0;
       round < 2 && earth && o.refer_hold_means && !referrals_given && !turns.empty(); ++round) {
    // The holds again, each referred with the rate it has when still. A hand's hold turns a
    // little over the interval the detector found (the sway does not end where it cuts), and
    // its own mean rate takes that net turn for bias: the referred direction is then off by
    // half of it. The rate a still hold has is also known from the rest (its mean plus the
    // change of the Earth rate, now that the heading is fitted, and of G f), to the bias's
    // wander and what the fit leaves uncertain. Each hold takes the mix of the two with the
    // least variance, the hand's net turn estimated from how far the holds' mean rates stray
    // from the known rate beyond both noises.
    std::vector<Eigen::Vector3d> hold_earth;
    carry(turns, accel.accel, accel.quadratic_ug_per_g2, &hold_earth);
    double psi_sigma = 10.0;
    Eigen::Matrix3d g_var = Eigen::Matrix3d::Zero();  // ((deg/s)/g)^2 of each G element
    {
      std::vector<int> cols;
      for (int j = 0; j < np; ++j) {
        if (std::find(fixed.begin(), fixed.end(), j) == fixed.end()) cols.push_back(j);
      }
      Eigen::MatrixXd Jc(J.rows(), static_cast<Eigen::Index>(cols.size()));
      for (std::size_t c = 0; c < cols.size(); ++c) {
        Jc.col(static_cast<Eigen::Index>(c)) = J.col(cols[c]);
      }
      const Eigen::MatrixXd Hc = Jc.transpose() * Jc;
      const Eigen::MatrixXd Hci = Hc.ldlt().solve(Eigen::MatrixXd::Identity(Hc.rows(), Hc.cols()));
      const int dof = static_cast<int>(J.rows()) - static_cast<int>(cols.size());
      const double scale = dof > 0 ? std::max(1.0, r.squaredNorm() / dof) : 1.0;
      for (std::size_t c = 0; c < cols.size(); ++c) {
        const auto C = static_cast<Eigen::Index>(c);
        const double v = std::max(0.0, Hci(C, C) * scale);
        if (cols[c] == psi_index) psi_sigma = std::sqrt(v);
        if (g_offset >= 0 && cols[c] >= g_offset && cols[c] < g_offset + 9) {
          g_var((cols[c] - g_offset) / 3, (cols[c] - g_offset) % 3) = v;
        }
      }
    }
    const Eigen::Matrix3d T_g = gyro_model(p.data(), o.fit_bias, out.rest_bias_dps).matrix();
    const double n2 = density_rad * density_rad;
    const double heading_var = w_cos_lat * w_cos_lat * std::pow(std::min(psi_sigma, 1.5), 2.0);
    const double var_rest =
        wander_rad * wander_rad + n2 / std::max(out.rest_duration_s, 1e-3) + heading_var;
    std::vector<Eigen::Vector3d> known(holds.size());
    std::vector<double> var_known(holds.size(), var_rest);  // per component [(rad/s)^2]
    std::vector<bool> trusted(holds.size(), true);
    double sway_sum = 0.0;
    int sway_n = 0;
    for (std::size_t k = 0; k < holds.size() && k < hold_earth.size(); ++k) {
      known[k] = out.rest_bias_dps + T_g * (hold_earth[k] - hold_earth[0]) * core::kRadToDeg;
      if (g_offset >= 0) {
        // ... and the g-sensitivity's change since the rest.
        const Eigen::Vector3d df =
            (correct_accel(accel, holds[k].mean_accel_mps2) - correct_accel(accel, rest_accel)) /
            core::kStandardGravity;
        for (int i = 0; i < 3; ++i) {
          for (int c = 0; c < 3; ++c) {
            known[k][i] += p[static_cast<std::size_t>(g_offset + 3 * i + c)] * df[c];
            var_known[k] += g_var(i, c) * df[c] * df[c] / 3.0 * core::kDegToRad * core::kDegToRad;
          }
        }
      }
      if (k == 0) continue;
      const double T = holds[k].duration_s;
      const Eigen::Vector3d D = (holds[k].mean_rate_dps - known[k]) * core::kDegToRad;
      // A net turn the hold's own excursion cannot hold is no sway: the known rate misses an
      // effect the model lacks (a g-sensitivity not fitted), and the hold keeps its mean.
      const double net2 = T * T * D.squaredNorm() / 3.0;
      if (net2 > 9.0 * (4.0 * holds[k].excursion_rad2 + n2 * T + var_known[k] * T * T)) {
        trusted[k] = false;
        continue;
      }
      sway_sum += net2 - n2 * T - var_known[k] * T * T;
      ++sway_n;
    }
    const double sway_var = sway_n > 0 ? std::max(0.0, sway_sum / sway_n) : 0.0;
    out.hold_sway_rad = std::sqrt(sway_var);
    for (std::size_t k = 1; k < holds.size() && k < hold_earth.size(); ++k) {
      const double T = holds[k].duration_s;
      if (!trusted[k]) {
        still_dps[k].reset();
        referral_var[k] = n2 * T / 12.0;
        continue;
      }
      double best_w = 1.0, best_var = 1e300;
      for (int step = 0; step <= 20; ++step) {
        const double w = step / 20.0;
        const double v = n2 * T * (1.0 / 3.0 - w / 2.0 + w * w / 4.0) + w * w * sway_var / 4.0 +
                         (1.0 - w) * (1.0 - w) * var_known[k] * T * T / 4.0;
        if (v < best_var) {
          best_var = v;
          best_w = w;
        }
      }
      still_dps[k] = best_w * holds[k].mean_rate_dps + (1.0 - best_w) * known[k];
      referral_var[k] = best_var;
    }
    holds = refer_holds(still_dps, referral_var);
    turns = make_turns(accel.accel, accel.quadratic_ug_per_g2, out.rest_bias_dps);
    costs.clear();
    for (const TurnData& d : turns) costs.emplace_back(make_turn_cost(&d, np));
    carry(turns, accel.accel, accel.quadratic_ug_per_g2);
    solve(fixed, o.max_iterations, J, r);
  }
  for (std::size_t i = 0; i < intervals.size(); ++i) {
    out.referrals.push_back({still_dps[i], referral_var[i]});
  }
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
      std::vector<TurnData> t = make_turns(a, quadratic, b);
      carry(t, a, quadratic);
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
        if (j == psi_index) continue;                   // the heading is no gyro parameter
        const double natural_j = j >= 9 ? 100.0 : 1.0;  // bias, G: as `natural` above
        if (std::abs(k[c]) * (q < 3 ? g : 1.0) / natural_j > 0.1) {
          frame_open[static_cast<std::size_t>(j)] = true;
        }
      }
    }
  }

  // To contract units and the output order (bias, scale, misalignment[, G]), psi last while
  // the bias is formed (then dropped: it is no contract parameter).
  // internal index -> output index: s 0..2 -> 3..5, m 3..8 -> 6..11, bias 9..11 -> 0..2,
  // G g_offset.. -> 12..20, psi -> n_out.
  const int n_out = o.fit_g_sensitivity ? 21 : 12;
  const int n_all = n_out + (earth ? 1 : 0);
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(n_all, n_all);
  const auto contract_index = [&](int j) {
    if (j < 9) return j + 3;
    if (j == psi_index) return n_out;
    if (g_offset >= 0 && j >= g_offset) return 12 + (j - g_offset);
    return j - 9;
  };
  const auto contract_unit = [](int j) { return j < 3 ? 1e6 : 1.0; };
  for (Eigen::Index a = 0; a < nf; ++a) {
    for (Eigen::Index b = 0; b < nf; ++b) {
      const int i = free[static_cast<std::size_t>(a)];
      const int j = free[static_cast<std::size_t>(b)];
      C(contract_index(i), contract_index(j)) = cov(a, b) * contract_unit(i) * contract_unit(j);
    }
  }
  if (!o.fit_bias) {
    for (int a = 0; a < 3; ++a) C(a, a) = out.rest_bias_sigma_dps[a] * out.rest_bias_sigma_dps[a];
  }
  // The bias parameter is the bias at the rest's orientation: the rest mean holds the
  // contract's b, G f_rest / g0 and the Earth rate there seen through the gyro, T_g w_ie(rest).
  Eigen::MatrixXd L = Eigen::MatrixXd::Identity(n_all, n_all);
  Eigen::Matrix3d extra_bias_cov = Eigen::Matrix3d::Zero();  // (deg/s)^2
  if (g_offset >= 0) {
    const Eigen::Vector3d f_rest = correct_accel(accel, rest_accel) / core::kStandardGravity;
    for (int i = 0; i < 3; ++i) {
      for (int k = 0; k < 3; ++k) {
        L(i, 12 + 3 * i + k) = -f_rest[k];
        out.gyro.bias[i] -= p[static_cast<std::size_t>(g_offset + 3 * i + k)] * f_rest[k];
      }
    }
  }
  if (earth) {
    const double psi = p[static_cast<std::size_t>(psi_index)];
    const double psi_sigma = std::sqrt(std::max(0.0, C(n_out, n_out)));
    out.rest_north_azimuth_deg = std::remainder(psi, 2.0 * std::numbers::pi) * core::kRadToDeg;
    out.rest_north_azimuth_sigma_deg = psi_sigma * core::kRadToDeg;
    // The heading is taken when the turns fix it to half a radian (the LN200 class: a few
    // hundredths); else its horizontal Earth rate at the rest, of known size in an unknown
    // direction, is left in the bias as a variance (W cos(lat))^2 / 2 per horizontal axis.
    out.heading_determined = fit_psi && psi_sigma < kHeadingDeterminedRad;
    const TurnData& d0 = turns.front();
    const Eigen::Matrix3d T_g = out.gyro.matrix();
    Eigen::Vector3d w_rest = d0.rest_vertical;
    if (out.heading_determined) {
      w_rest += std::cos(psi) * d0.rest_h1 + std::sin(psi) * d0.rest_h2;
      const Eigen::Vector3d dw = T_g * (-std::sin(psi) * d0.rest_h1 + std::cos(psi) * d0.rest_h2);
      for (int i = 0; i < 3; ++i) L(i, n_out) = -dw[i] * core::kRadToDeg;
    } else {
      const double h2 = 0.5 * w_cos_lat * w_cos_lat * core::kRadToDeg * core::kRadToDeg;
      const Eigen::Vector3d e1 = d0.rest_h1.normalized();
      const Eigen::Vector3d e2 = d0.rest_h2.normalized();
      extra_bias_cov = T_g * (h2 * (e1 * e1.transpose() + e2 * e2.transpose())) * T_g.transpose();
    }
    out.rest_earth_rate_dps = w_rest * core::kRadToDeg;
    if (!o.fit_bias) out.gyro.bias -= T_g * w_rest * core::kRadToDeg;
  }
  C = L * C * L.transpose();
  C.topLeftCorner<3, 3>() += extra_bias_cov;
  out.covariance = C.topLeftCorner(n_out, n_out);
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
  for (int j = 0; j < np_gyro; ++j) {
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
        "chi2/dof {:.3g} against the turns' noise model (gyro noise and bias wander, the "
        "poses' accel noise and wander, the holds' referral): sigmas scaled by {:.3g}",
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
  std::string earth_text;
  if (earth) {
    const std::string heading =
        out.heading_determined
            ? fmt::format("the rest's heading fitted (North {:.1f} +- {:.1f} deg about gravity)",
                          out.rest_north_azimuth_deg, out.rest_north_azimuth_sigma_deg)
            : fmt::format(
                  "the rest's heading fitted but not determined by these turns (sigma "
                  "{:.0f} deg): its horizontal part, {:.4f} deg/s, is in the bias's sigma",
                  out.rest_north_azimuth_sigma_deg, w_cos_lat * core::kRadToDeg);
    earth_text = fmt::format(
        "the Earth rate ({:.4f} deg/s) modelled: {:.4f} deg/s along gravity at latitude "
        "{:.2f} deg, {}; unmodelled it would move the gravity direction by about {:.2g} deg "
        "RMS over these turns; bias from the {:.3g} s initial rest less the Earth rate there",
        earth_dps, w_sin_lat * core::kRadToDeg, *o.latitude_deg, heading, out.earth_rate_rms_deg,
        out.rest_duration_s);
  } else {
    earth_text = fmt::format(
        "the Earth rate ({:.4f} deg/s, not modelled: the site's latitude is not known) can move "
        "it by about {:.2g} deg RMS over these turns; bias from the {:.3g} s initial rest "
        "(includes the Earth rate there, at most {:.4f} deg/s)",
        earth_dps, out.earth_rate_rms_deg, out.rest_duration_s, earth_dps);
  }
  out.summary = fmt::format(
      "gyro by integration over {} turns between static poses: gravity direction after each "
      "turn off by {:.3g} deg RMS (largest {:.3g} deg); {}; {}; {}",
      out.turns.size(), out.rms_residual_deg, out.max_residual_deg, quality, missing, earth_text);
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
  nlohmann::json earth = {{"modelled", r.earth_rate_modelled}};
  if (r.earth_rate_modelled) {
    earth["latitude_deg"] = r.latitude_deg;
    earth["rest_north_azimuth_deg"] = r.rest_north_azimuth_deg;
    earth["rest_north_azimuth_sigma_deg"] = r.rest_north_azimuth_sigma_deg;
    earth["heading_determined"] = r.heading_determined;
    earth["rest_earth_rate_dps"] = {r.rest_earth_rate_dps.x(), r.rest_earth_rate_dps.y(),
                                    r.rest_earth_rate_dps.z()};
  }
  j["earth_rate"] = earth;
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
