#include "sim/hand_session.hpp"

#include <Eigen/Geometry>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "core/rotation.hpp"
#include "core/table_geometry.hpp"
#include "sim/imu_sim.hpp"
#include "sim/noise.hpp"
#include "sim/spec_sheet.hpp"

namespace calstand::sim {

namespace {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

Mat3 hand_exp_so3(const Vec3& v) {
  const double a = v.norm();
  if (a < 1e-15) return Mat3::Identity() + core::skew(v);
  return Eigen::AngleAxisd(a, v / a).toRotationMatrix();
}

// Right Jacobian of SO(3): the body rate of C0 exp([d x]) is J_r(d) d_dot.
Mat3 hand_right_jacobian(const Vec3& d) {
  const double a = d.norm();
  const Mat3 K = core::skew(d);
  if (a < 1e-8) return Mat3::Identity() - 0.5 * K + K * K / 6.0;
  return Mat3::Identity() - (1.0 - std::cos(a)) / (a * a) * K +
         (a - std::sin(a)) / (a * a * a) * K * K;
}

// A rotation taking the unit vector u to the unit vector v (the shortest one).
Mat3 hand_align(const Vec3& u, const Vec3& v) {
  const Vec3 c = u.cross(v);
  const double s = c.norm();
  const double cosine = u.dot(v);
  if (s < 1e-12) {
    if (cosine > 0.0) return Mat3::Identity();
    // Opposite: half a turn about any axis normal to u.
    Vec3 n = u.cross(Vec3::UnitX());
    if (n.norm() < 1e-6) n = u.cross(Vec3::UnitY());
    return Eigen::AngleAxisd(std::numbers::pi, n.normalized()).toRotationMatrix();
  }
  return Eigen::AngleAxisd(std::atan2(s, cosine), c / s).toRotationMatrix();
}

struct Uniform {
  explicit Uniform(std::uint64_t seed) : rng(seed) {}
  double next() { return static_cast<double>(rng() >> 11U) * 0x1.0p-53; }
  double between(double a, double b) { return a + (b - a) * next(); }
  Rng rng;
};

Vec3 hand_random_unit(NormalSource& n) {
  Vec3 v(n.next(), n.next(), n.next());
  return v.normalized();
}

Mat3 hand_random_rotation(NormalSource& n) {
  Eigen::Quaterniond q(n.next(), n.next(), n.next(), n.next());
  q.normalize();
  return q.toRotationMatrix();
}

// One stretch of motion with an analytic orientation C_LB(t) and body rate.
struct Motion {
  enum class Kind { kHold, kTurn };
  Kind kind = Kind::kHold;
  double t0 = 0.0;
  double t1 = 0.0;
  Mat3 C0 = Mat3::Identity();  // hold: mean orientation; turn: orientation at t0
  // Hold sway: delta(t) = taper(t) * sum of sines on each axis.
  struct Sine {
    int axis;
    double amplitude_rad;
    double freq_hz;
    double phase;
  };
  std::vector<Sine> sway;
  double taper_s = 0.3;
  // Turn: C0 R(axis, theta(t)) R(perp, psi(t)).
  Vec3 axis = Vec3::UnitZ();
  double angle_rad = 0.0;
  Vec3 perp = Vec3::UnitX();
  double swing_rad = 0.0;
  Vec3 lever_m = Vec3::Zero();  // IMU position from the centre of the turn, body frame

  double duration() const { return t1 - t0; }

  // taper and its derivative
  std::pair<double, double> taper(double t) const {
    const double a = t - t0;
    const double b = t1 - t;
    const double w = std::min(taper_s, 0.5 * duration());
    if (w <= 0.0) return {0.0, 0.0};
    if (a < w) {
      const double x = std::numbers::pi * a / (2.0 * w);
      return {std::sin(x) * std::sin(x), std::numbers::pi / (2.0 * w) * std::sin(2.0 * x)};
    }
    if (b < w) {
      const double x = std::numbers::pi * b / (2.0 * w);
      return {std::sin(x) * std::sin(x), -std::numbers::pi / (2.0 * w) * std::sin(2.0 * x)};
    }
    return {1.0, 0.0};
  }

  void sway_at(double t, Vec3& d, Vec3& d_dot) const {
    Vec3 s = Vec3::Zero();
    Vec3 s_dot = Vec3::Zero();
    for (const Sine& k : sway) {
      const double arg = kTwoPi * k.freq_hz * (t - t0) + k.phase;
      s[k.axis] += k.amplitude_rad * std::sin(arg);
      s_dot[k.axis] += k.amplitude_rad * kTwoPi * k.freq_hz * std::cos(arg);
    }
    const auto [w, w_dot] = taper(t);
    d = w * s;
    d_dot = w_dot * s + w * s_dot;
  }

  void turn_at(double t, double& theta, double& theta_dot, double& psi, double& psi_dot) const {
    const double T = duration();
    const double tau = std::clamp((t - t0) / T, 0.0, 1.0);
    theta = angle_rad * (tau - std::sin(kTwoPi * tau) / kTwoPi);
    theta_dot = angle_rad / T * (1.0 - std::cos(kTwoPi * tau));
    psi = swing_rad * std::sin(std::numbers::pi * tau) * std::sin(std::numbers::pi * tau);
    psi_dot = swing_rad * std::numbers::pi / T * std::sin(kTwoPi * tau);
  }

  Mat3 orientation(double t) const {
    if (kind == Kind::kHold) {
      Vec3 d, d_dot;
      sway_at(t, d, d_dot);
      return C0 * hand_exp_so3(d);
    }
    double theta, theta_dot, psi, psi_dot;
    turn_at(t, theta, theta_dot, psi, psi_dot);
    return C0 * Eigen::AngleAxisd(theta, axis).toRotationMatrix() *
           Eigen::AngleAxisd(psi, perp).toRotationMatrix();
  }

  // Body rate [rad/s].
  Vec3 rate(double t) const {
    if (kind == Kind::kHold) {
      Vec3 d, d_dot;
      sway_at(t, d, d_dot);
      return hand_right_jacobian(d) * d_dot;
    }
    double theta, theta_dot, psi, psi_dot;
    turn_at(t, theta, theta_dot, psi, psi_dot);
    const Mat3 B = Eigen::AngleAxisd(psi, perp).toRotationMatrix();
    return theta_dot * B.transpose() * axis + psi_dot * perp;
  }

  Mat3 end_orientation() const { return orientation(t1); }
};

// The kinematic timeline of a session and its sampling through an ImuSim.
class Timeline {
 public:
  void add(Motion m) { motions_.push_back(std::move(m)); }
  double end_time() const { return motions_.empty() ? 0.0 : motions_.back().t1; }
  const std::vector<Motion>& motions() const { return motions_; }

  // The motion at t (the last one whose start is <= t), advancing a cursor for sorted queries.
  const Motion& at(double t, std::size_t& cursor) const {
    while (cursor + 1 < motions_.size() && motions_[cursor + 1].t0 <= t) ++cursor;
    while (cursor > 0 && motions_[cursor].t0 > t) --cursor;
    return motions_[cursor];
  }

 private:
  std::vector<Motion> motions_;
};

ImuTruth hand_prepare_truth(const SessionImu& imu, std::uint64_t seed) {
  ImuTruth truth;
  if (imu.truth) {
    truth = *imu.truth;
  } else {
    const auto spec = builtin_spec(imu.spec);
    if (!spec) throw std::invalid_argument("session: unknown IMU spec sheet \"" + imu.spec + "\"");
    truth = truth_from_spec(*spec, imu.spec, derive_seed(seed, "session-truth"));
  }
  if (imu.sample_rate_hz > 0.0) {
    truth.sample_rate_hz = imu.sample_rate_hz;
    if (truth.gyro_bandwidth_hz >= truth.sample_rate_hz / 2.0) truth.gyro_bandwidth_hz = 0.0;
    if (truth.accel_bandwidth_hz >= truth.sample_rate_hz / 2.0) truth.accel_bandwidth_hz = 0.0;
  }
  if (!imu.keep_unmodelled_terms) {
    truth.gyro_g_sensitivity.setZero();
    truth.gyro_scale_asymmetry.setZero();
    truth.gyro_quadratic.setZero();
    truth.accel_scale_asymmetry.setZero();
    truth.accel_quadratic.setZero();
  }
  truth.accel_lever_arm.setZero();  // the session's own lever arm is in the motion
  return truth;
}

core::Site hand_site(const SessionImu& imu) {
  core::Site site;
  site.latitude_deg = imu.latitude_deg;
  site.height_m = imu.height_m;
  if (imu.gravity_mps2 > 0.0) site.gravity_mps2 = imu.gravity_mps2;
  return site;
}

// Samples the timeline; fills samples, the hold/turn sample ranges and the slow-noise means.
void hand_sample(const Timeline& timeline, SimSession& s, double time_jitter, std::uint64_t seed) {
  ImuSim imu(s.sim_truth, core::TableGeometry{}, s.site, Eigen::Vector2d::Zero(),
             derive_seed(seed, "session-imu"));
  imu.power_on(0.0);
  s.turn_on_gyro_dps = imu.turn_on_gyro_bias();
  s.turn_on_accel_mps2 = imu.turn_on_accel_bias();
  s.truth = triad_frame_truth(s.sim_truth, s.turn_on_gyro_dps, s.turn_on_accel_mps2);

  const double g = s.gravity_mps2;
  const Vec3 force_L(0.0, 0.0, g);
  const Vec3 earth_L_dps = s.site.earth_rate_level_radps() * core::kRadToDeg;
  const double dt = 1.0 / s.sample_rate_hz;
  Uniform jitter(derive_seed(seed, "session-jitter"));
  const auto n = static_cast<std::size_t>(std::floor(timeline.end_time() / dt)) + 1;
  s.samples.reserve(n);

  std::size_t cursor = 0;
  std::array<double, 6> sum_rest{};
  std::size_t count_rest = 0;
  Vec3 rest_rate_sum = Vec3::Zero();
  const SessionHold* rest = s.kind == "hand" && !s.holds.empty() ? &s.holds.front() : nullptr;
  std::vector<std::array<double, 6>> hold_sum(s.holds.size(), std::array<double, 6>{});
  std::vector<std::size_t> hold_count(s.holds.size(), 0);
  std::size_t hold_cursor = 0;
  for (std::size_t k = 0; k < n; ++k) {
    double t = static_cast<double>(k) * dt;
    if (time_jitter > 0.0 && k > 0) t += time_jitter * dt * (2.0 * jitter.next() - 1.0);
    t = std::min(t, timeline.end_time());
    const Motion& m = timeline.at(t, cursor);
    const Mat3 C = m.orientation(t);
    const Vec3 w = m.rate(t);
    ImuInputs in;
    in.rate_dps = w * core::kRadToDeg + C.transpose() * earth_L_dps;
    in.force_mps2 = C.transpose() * force_L;
    if (!m.lever_m.isZero()) {
      const double h = 1e-5;
      const Vec3 alpha = (m.rate(t + h) - m.rate(t - h)) / (2.0 * h);
      in.force_mps2 += w.cross(w.cross(m.lever_m)) + alpha.cross(m.lever_m);
    }
    in.temperature_c = s.sim_truth.temperature_ref_c;
    core::ImuSample sample = imu.sample(t, in);
    sample.receive_time_s = t;
    sample.device_time_s = t;
    s.samples.push_back(sample);

    if (rest != nullptr && t >= rest->start_s && t <= rest->end_s) {
      for (std::size_t c = 0; c < 6; ++c) sum_rest[c] += imu.last_slow_noise()[c];
      rest_rate_sum += in.rate_dps;
      ++count_rest;
    }
    while (hold_cursor + 1 < s.holds.size() && s.holds[hold_cursor].end_s < t) ++hold_cursor;
    if (hold_cursor < s.holds.size() && t >= s.holds[hold_cursor].start_s &&
        t <= s.holds[hold_cursor].end_s) {
      for (std::size_t c = 0; c < 6; ++c) hold_sum[hold_cursor][c] += imu.last_slow_noise()[c];
      ++hold_count[hold_cursor];
    }
  }
  // Per hold, then the holds' plain average (each pose weighs alike in the fits).
  std::size_t used = 0;
  for (std::size_t h = 0; h < s.holds.size(); ++h) {
    if (hold_count[h] == 0) continue;
    for (std::size_t c = 0; c < 6; ++c) {
      s.holds[h].slow_noise_mean[c] = hold_sum[h][c] / static_cast<double>(hold_count[h]);
    }
    if (rest != nullptr && h == 0) continue;
    for (std::size_t c = 0; c < 6; ++c) s.slow_noise_mean_holds[c] += s.holds[h].slow_noise_mean[c];
    ++used;
  }
  for (std::size_t c = 0; c < 6; ++c) {
    if (used > 0) s.slow_noise_mean_holds[c] /= static_cast<double>(used);
    if (count_rest > 0) s.slow_noise_mean_rest[c] = sum_rest[c] / static_cast<double>(count_rest);
  }
  if (count_rest > 0) {
    s.rest_true_rate_A_dps = s.truth.C_AB * rest_rate_sum / static_cast<double>(count_rest);
  }
  // Sample ranges of holds and turns.
  const auto first_at_or_after = [&](double t) {
    return static_cast<std::size_t>(
        std::lower_bound(s.samples.begin(), s.samples.end(), t,
                         [](const core::ImuSample& a, double x) { return a.receive_time_s < x; }) -
        s.samples.begin());
  };
  for (SessionHold& h : s.holds) {
    h.begin = first_at_or_after(h.start_s);
    h.end = first_at_or_after(std::nextafter(h.end_s, 1e300));
  }
  for (SessionTurn& turn : s.turns) {
    turn.begin = first_at_or_after(turn.start_s);
    turn.end = first_at_or_after(std::nextafter(turn.end_s, 1e300));
  }
}

Motion hand_hold(double t0, double t1, const Mat3& C, double tremor_deg, Uniform& u) {
  Motion m;
  m.kind = Motion::Kind::kHold;
  m.t0 = t0;
  m.t1 = t1;
  m.C0 = C;
  if (tremor_deg > 0.0) {
    // Two sines per axis: total RMS angle^2 = 6 * A^2 / 2.
    const double amplitude = tremor_deg * core::kDegToRad / std::sqrt(3.0);
    for (int axis = 0; axis < 3; ++axis) {
      for (int j = 0; j < 2; ++j) {
        m.sway.push_back({axis, amplitude, u.between(0.3, 4.0), u.between(0.0, kTwoPi)});
      }
    }
  }
  return m;
}

// A hand turn from C_from to C_to starting at t0; returns the motion (its t1 set).
Motion hand_turn(double t0, const Mat3& C_from, const Mat3& C_to, double min_s, double max_s,
                 double max_rate_dps, double swing_deg, double lever_arm_m, Uniform& u,
                 NormalSource& n) {
  Motion m;
  m.kind = Motion::Kind::kTurn;
  m.t0 = t0;
  m.C0 = C_from;
  const Eigen::AngleAxisd rel(Mat3(C_from.transpose() * C_to));
  m.angle_rad = rel.angle();
  m.axis = m.angle_rad > 1e-12 ? Vec3(rel.axis()) : Vec3::UnitZ();
  double T = u.between(min_s, max_s);
  // Raised cosine: peak rate is twice the mean; the swing adds its own rate.
  const double swing = swing_deg * core::kDegToRad * u.between(-1.0, 1.0);
  const double peak =
      (2.0 * std::abs(m.angle_rad) + std::numbers::pi * std::abs(swing)) * core::kRadToDeg;
  T = std::max(T, peak / max_rate_dps);
  m.t1 = t0 + T;
  Vec3 p = m.axis.cross(hand_random_unit(n));
  if (p.norm() < 1e-6) p = m.axis.cross(Vec3::UnitX());
  m.perp = p.normalized();
  m.swing_rad = swing;
  m.lever_m = lever_arm_m * hand_random_unit(n);
  return m;
}

SessionTurn hand_turn_record(const Motion& m, const Mat3& C_AB) {
  SessionTurn t;
  t.start_s = m.t0;
  t.end_s = m.t1;
  t.axis_A = C_AB * m.axis;
  t.angle_deg = m.angle_rad * core::kRadToDeg;
  t.peak_rate_dps = 2.0 * std::abs(m.angle_rad) / m.duration() * core::kRadToDeg;
  return t;
}

SessionHold hand_hold_record(const Motion& m, const Mat3& C_AB) {
  SessionHold h;
  h.start_s = m.t0;
  h.end_s = m.t1;
  h.C_LB = m.C0;
  h.up_A = (C_AB * m.C0.transpose() * Vec3::UnitZ()).normalized();
  return h;
}

void hand_check_range(double lo, double hi, const char* what) {
  if (!(lo > 0.0) || !(hi >= lo) || !std::isfinite(hi)) {
    throw std::invalid_argument(std::string("session: ") + what +
                                " range must be positive and ordered");
  }
}

}  // namespace

std::vector<std::pair<std::string, double>> TriadFrameTruth::parameters() const {
  static const char* axes[] = {"x", "y", "z"};
  std::vector<std::pair<std::string, double>> out;
  for (int i = 0; i < 3; ++i) out.emplace_back(std::string("accel_bias.") + axes[i], accel_bias[i]);
  for (int i = 0; i < 3; ++i) {
    out.emplace_back(std::string("accel_scale.") + axes[i], accel_scale[i]);
  }
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (i != j) {
        out.emplace_back(std::string("accel_misalignment.") + axes[i] + axes[j],
                         accel_misalignment(i, j));
      }
    }
  }
  for (int i = 0; i < 3; ++i) out.emplace_back(std::string("gyro_bias.") + axes[i], gyro_bias[i]);
  for (int i = 0; i < 3; ++i) out.emplace_back(std::string("gyro_scale.") + axes[i], gyro_scale[i]);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (i != j) {
        out.emplace_back(std::string("gyro_misalignment.") + axes[i] + axes[j],
                         gyro_misalignment(i, j));
      }
    }
  }
  if (!accel_quadratic.isZero()) {
    for (int i = 0; i < 3; ++i) {
      out.emplace_back(std::string("accel_quadratic.") + axes[i], accel_quadratic[i]);
    }
  }
  if (!gyro_g_sensitivity.isZero()) {
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        out.emplace_back(std::string("gyro_g_sensitivity.") + axes[i] + axes[j],
                         gyro_g_sensitivity(i, j));
      }
    }
  }
  return out;
}

TriadFrameTruth triad_frame_truth(const ImuTruth& truth, const Eigen::Vector3d& turn_on_gyro_dps,
                                  const Eigen::Vector3d& turn_on_accel_mps2) {
  Mat3 Ta = Mat3::Identity();
  Ta.diagonal() += 1e-6 * truth.accel_scale;
  Ta += truth.accel_misalignment - Mat3(truth.accel_misalignment.diagonal().asDiagonal());
  if (!(std::abs(Ta.determinant()) > 1e-9)) {
    throw std::invalid_argument("triad_frame_truth: the accelerometer matrix is singular");
  }
  // Ta^T = Qr Rr (Rr upper triangular): Ta = Rr^T Qr^T = L Q.
  const Eigen::HouseholderQR<Mat3> qr(Ta.transpose());
  Mat3 Qr = qr.householderQ();
  Mat3 Rr = qr.matrixQR().triangularView<Eigen::Upper>();
  for (int i = 0; i < 3; ++i) {
    if (Rr(i, i) < 0.0) {
      Rr.row(i) *= -1.0;
      Qr.col(i) *= -1.0;
    }
  }
  const Mat3 L = Rr.transpose();
  const Mat3 Q = Qr.transpose();

  TriadFrameTruth out;
  out.C_AB = Q;
  out.accel_bias = truth.accel_bias + turn_on_accel_mps2;
  out.accel_quadratic = truth.accel_quadratic;
  for (int i = 0; i < 3; ++i) {
    out.accel_scale[i] = (L(i, i) - 1.0) * 1e6;
    for (int j = 0; j < i; ++j) out.accel_misalignment(i, j) = L(i, j);
  }
  Mat3 Tg = Mat3::Identity();
  Tg.diagonal() += 1e-6 * truth.gyro_scale;
  Tg += truth.gyro_misalignment - Mat3(truth.gyro_misalignment.diagonal().asDiagonal());
  const Mat3 TgA = Tg * Q.transpose();
  out.gyro_bias = truth.gyro_bias + turn_on_gyro_dps;
  for (int i = 0; i < 3; ++i) {
    out.gyro_scale[i] = (TgA(i, i) - 1.0) * 1e6;
    for (int j = 0; j < 3; ++j) {
      if (i != j) out.gyro_misalignment(i, j) = TgA(i, j);
    }
  }
  out.gyro_g_sensitivity = truth.gyro_g_sensitivity * Q.transpose();
  return out;
}

namespace {

// A session of `kind` before any sample: the IMU's truth drawn for `seed`, its rate, the site.
SimSession hand_new_session(const char* kind, const SessionImu& imu, std::uint64_t seed) {
  SimSession s;
  s.kind = kind;
  s.seed = seed;
  s.sim_truth = hand_prepare_truth(imu, seed);
  s.model_name = s.sim_truth.name;
  s.sample_rate_hz = s.sim_truth.sample_rate_hz;
  s.site = hand_site(imu);
  s.gravity_mps2 = s.site.gravity();
  return s;
}

}  // namespace

SimSession simulate_hand_session(const HandSessionOptions& o, std::uint64_t seed) {
  if (o.poses < 0) throw std::invalid_argument("hand session: poses must not be negative");
  hand_check_range(o.hold_min_s, o.hold_max_s, "hold duration");
  hand_check_range(o.turn_min_s, o.turn_max_s, "turn duration");
  if (!(o.initial_rest_s > 0.0)) {
    throw std::invalid_argument("hand session: initial_rest_s must be positive");
  }
  if (!(o.max_rate_dps > 0.0)) throw std::invalid_argument("hand session: max_rate_dps <= 0");

  SimSession s = hand_new_session("hand", o.imu, seed);
  // The frame A depends on the truth only (not on the turn-on biases): known before sampling.
  const Mat3 C_AB = triad_frame_truth(s.sim_truth, Vec3::Zero(), Vec3::Zero()).C_AB;

  Uniform u(derive_seed(seed, "hand-session-uniform"));
  NormalSource n(derive_seed(seed, "hand-session-normal"));

  // Gravity directions in the body: a Fibonacci lattice of poses + 1 points (the rest first),
  // rotated at random, visited in a random order with a minimum separation.
  const int count = o.poses + 1;
  const Mat3 spin = hand_random_rotation(n);
  std::vector<Vec3> lattice;
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
  for (int k = 0; k < count; ++k) {
    const double z = 1.0 - 2.0 * (k + 0.5) / count;
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    lattice.push_back(spin * Vec3(r * std::cos(golden * k), r * std::sin(golden * k), z));
  }
  std::vector<Vec3> order;
  {
    std::vector<Vec3> left = lattice;
    const double min_sep = std::cos(o.min_pose_separation_deg * core::kDegToRad);
    auto pick = static_cast<std::size_t>(u.next() * static_cast<double>(left.size()));
    pick = std::min(pick, left.size() - 1);
    order.push_back(left[pick]);
    left.erase(left.begin() + static_cast<std::ptrdiff_t>(pick));
    while (!left.empty()) {
      std::vector<std::size_t> ok;
      for (std::size_t i = 0; i < left.size(); ++i) {
        if (left[i].dot(order.back()) <= min_sep) ok.push_back(i);
      }
      std::size_t choice = 0;
      if (ok.empty()) {
        double best = 2.0;
        for (std::size_t i = 0; i < left.size(); ++i) {
          if (left[i].dot(order.back()) < best) {
            best = left[i].dot(order.back());
            choice = i;
          }
        }
      } else {
        auto j = static_cast<std::size_t>(u.next() * static_cast<double>(ok.size()));
        choice = ok[std::min(j, ok.size() - 1)];
      }
      order.push_back(left[choice]);
      left.erase(left.begin() + static_cast<std::ptrdiff_t>(choice));
    }
  }
  // Orientations: C_LB maps the body gravity direction u to Up, then a random heading.
  const auto pose_orientation = [&](const Vec3& up_body) {
    const Mat3 heading =
        Eigen::AngleAxisd(u.between(-std::numbers::pi, std::numbers::pi), Vec3::UnitZ())
            .toRotationMatrix();
    return Mat3(heading * hand_align(up_body, Vec3::UnitZ()));
  };

  std::vector<Mat3> orientations;
  if (o.single_turn_axis) {
    const Vec3 a = o.single_turn_axis->normalized();
    // Gravity across the axis at the rest; then turns about the axis only.
    Vec3 up = a.cross(hand_random_unit(n));
    if (up.norm() < 1e-6) up = a.cross(Vec3::UnitX());
    Mat3 Ck = pose_orientation(up.normalized());
    orientations.push_back(Ck);
    for (int k = 1; k < count; ++k) {
      const double step = u.between(30.0, 150.0) * (u.next() < 0.5 ? -1.0 : 1.0);
      Ck = Ck * Eigen::AngleAxisd(step * core::kDegToRad, a).toRotationMatrix();
      orientations.push_back(Ck);
    }
  } else {
    for (const Vec3& up : order) orientations.push_back(pose_orientation(up));
  }
  const double swing_deg = o.single_turn_axis ? 0.0 : o.swing_deg;

  Timeline timeline;
  double t = 0.0;
  Mat3 C = orientations[0];
  {
    Motion rest = hand_hold(t, o.initial_rest_s, C, 0.0, u);  // the rest lies on the bench
    s.holds.push_back(hand_hold_record(rest, C_AB));
    timeline.add(rest);
    t = o.initial_rest_s;
  }
  for (int k = 1; k < count; ++k) {
    const Mat3 C_next = orientations[static_cast<std::size_t>(k)];
    Motion turn = hand_turn(t, C, C_next, o.turn_min_s, o.turn_max_s, o.max_rate_dps, swing_deg,
                            o.lever_arm_m, u, n);
    s.turns.push_back(hand_turn_record(turn, C_AB));
    t = turn.t1;
    timeline.add(turn);
    const double hold_s = u.between(o.hold_min_s, o.hold_max_s);
    Motion hold = hand_hold(t, t + hold_s, C_next, o.tremor_deg, u);
    s.holds.push_back(hand_hold_record(hold, C_AB));
    timeline.add(hold);
    t += hold_s;
    C = C_next;
  }
  hand_sample(timeline, s, o.time_jitter, seed);
  return s;
}

SimSession simulate_ferraris_session(const FerrarisSessionOptions& o, std::uint64_t seed) {
  hand_check_range(o.hold_min_s, o.hold_max_s, "hold duration");
  hand_check_range(o.move_min_s, o.move_max_s, "move duration");
  if (!(o.turn_s > 0.0) || !(o.turn_pad_s >= 0.0)) {
    throw std::invalid_argument("ferraris session: turn_s must be positive, turn_pad_s >= 0");
  }
  SimSession s = hand_new_session("ferraris", o.imu, seed);
  const Mat3 C_AB = triad_frame_truth(s.sim_truth, Vec3::Zero(), Vec3::Zero()).C_AB;

  Uniform u(derive_seed(seed, "ferraris-session-uniform"));
  NormalSource n(derive_seed(seed, "ferraris-session-normal"));

  // A placement with housing axis `up` (signed unit) up: random heading, random tilt.
  const double tilt_sigma = o.placement_tilt_deg * core::kDegToRad / std::sqrt(2.0);
  const auto place = [&](const Vec3& up, double& tilt_deg) {
    const Mat3 heading =
        Eigen::AngleAxisd(u.between(-std::numbers::pi, std::numbers::pi), Vec3::UnitZ())
            .toRotationMatrix();
    const Vec3 tilt(tilt_sigma * n.next(), tilt_sigma * n.next(), 0.0);
    tilt_deg = tilt.norm() * core::kRadToDeg;
    return Mat3(hand_exp_so3(tilt) * heading * hand_align(up, Vec3::UnitZ()));
  };

  struct Section {
    const char* label;
    Vec3 up;
    bool turn;
  };
  const Section sections[] = {
      {"x_p", Vec3::UnitX(), false},  {"x_a", -Vec3::UnitX(), false},
      {"y_p", Vec3::UnitY(), false},  {"y_a", -Vec3::UnitY(), false},
      {"z_p", Vec3::UnitZ(), false},  {"z_a", -Vec3::UnitZ(), false},
      {"x_rot", Vec3::UnitX(), true}, {"y_rot", Vec3::UnitY(), true},
      {"z_rot", Vec3::UnitZ(), true},
  };

  Timeline timeline;
  std::vector<std::pair<double, int>> step_starts;  // (start time, step)
  double t = 0.0;
  Mat3 C = Mat3::Identity();
  int move_step = 10;
  int step = 1;
  for (const Section& sec : sections) {
    double tilt_deg = 0.0;
    const Mat3 C_place = place(sec.up, tilt_deg);
    if (step > 1) {
      Motion move = hand_turn(t, C, C_place, o.move_min_s, o.move_max_s, 300.0, 15.0, 0.05, u, n);
      step_starts.emplace_back(t, move_step++);
      t = move.t1;
      timeline.add(move);
    }
    step_starts.emplace_back(t, step);
    s.step_labels.emplace_back(step, sec.label);
    if (!sec.turn) {
      const double hold_s = u.between(o.hold_min_s, o.hold_max_s);
      Motion hold = hand_hold(t, t + hold_s, C_place, o.tremor_deg, u);
      SessionHold rec = hand_hold_record(hold, C_AB);
      rec.label = sec.label;
      rec.placement_tilt_deg = tilt_deg;
      s.holds.push_back(rec);
      timeline.add(hold);
      t += hold_s;
      C = C_place;
    } else {
      const double section_start = t;
      timeline.add(hand_hold(t, t + o.turn_pad_s, C_place, o.tremor_deg, u));
      t += o.turn_pad_s;
      // About the vertical: the body axis C^T Up is fixed in the body.
      Motion turn;
      turn.kind = Motion::Kind::kTurn;
      turn.t0 = t;
      turn.t1 = t + o.turn_s;
      turn.C0 = C_place;
      turn.axis = (C_place.transpose() * Vec3::UnitZ()).normalized();
      turn.angle_rad = o.turn_angle_deg * core::kDegToRad;
      Vec3 r = turn.axis.cross(hand_random_unit(n));
      turn.lever_m = o.lever_arm_m * r.normalized();
      const Mat3 C_after = turn.end_orientation();
      timeline.add(turn);
      t = turn.t1;
      timeline.add(hand_hold(t, t + o.turn_pad_s, C_after, o.tremor_deg, u));
      t += o.turn_pad_s;
      SessionTurn rec = hand_turn_record(turn, C_AB);
      rec.start_s = section_start;
      rec.end_s = t;
      rec.label = sec.label;
      s.turns.push_back(rec);
      C = C_after;
    }
    ++step;
  }
  hand_sample(timeline, s, o.time_jitter, seed);
  s.steps.resize(s.samples.size());
  std::size_t j = 0;
  for (std::size_t k = 0; k < s.samples.size(); ++k) {
    const double tk = s.samples[k].receive_time_s;
    while (j + 1 < step_starts.size() && step_starts[j + 1].first <= tk) ++j;
    s.steps[k] = step_starts[j].second;
  }
  return s;
}

}  // namespace calstand::sim
