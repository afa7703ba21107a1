#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/imu_sample.hpp"
#include "core/site.hpp"
#include "sim/imu_truth.hpp"

/// Recordings made without a table: an IMU turned by hand between static poses (the session
/// imu_tk and the gravity-norm method expect), and a Ferraris session (six axis-up/down holds
/// and three 360 deg turns, labelled, as imucal expects). The motion is analytic (orientation,
/// body rate and angular acceleration at any instant), the IMU is the ordinary ImuSim with its
/// datasheet noise (white, bias instability, Gauss-Markov, random walk, turn-on bias, output
/// filter), fed by ImuSim::sample(time, ImuInputs).
///
/// What is and is not modelled:
/// - The world turns with the Earth (Earth rate in every gyro sample); the site's gravity is
///   exact; the temperature is constant at the truth's reference (no thermal terms).
/// - Turns: the relative rotation from one pose to the next about an axis fixed in the body,
///   with a raised-cosine rate profile (zero rate and acceleration at both ends), plus a
///   sideways swing about a perpendicular body axis (up to +-`swing_deg`, back to zero at the
///   end), so the rate direction moves during a turn and an integrator that ignores the order
///   of rotations is wrong. The IMU sits `lever_arm_m` from the centre of the turn (a hand
///   turns an object about the wrist), so a turn carries centripetal and tangential
///   accelerations.
/// - Holds: a hand-held pose is not perfectly still; `tremor_deg` (RMS angle) of slow sway
///   (sinusoids of 0.3-4 Hz on each axis, tapered to zero in the first and last 0.3 s of the
///   hold) is added. Default 0.01 deg: a pose pressed on a surface by hand; set 0 for a pose
///   that rests on its own. No linear tremor acceleration is modelled.
/// - Time stamps: the true sample instants jitter by +-`time_jitter` of a period (uniform), as
///   a USB or serial logger's time stamps do; the noise processes step at the nominal period.
///
/// Frames: the simulator's body frame B is the housing frame of the truth file (misalignments
/// of both triads relative to it). A calibration without a table can only know the
/// accelerometer triad's own frame A (error-model.md: "the body frame is the accelerometer
/// triad's"), fixed by calstand's convention:
///   body x along the accelerometer x sensitive axis, body y in the plane of the accelerometer
///   x and y sensitive axes (towards accel y), body z completing the right-handed frame.
/// The accelerometer matrix T_a = I + diag(s) 1e-6 + M_a then is lower triangular in A:
/// accel_misalignment.xy, .xz and .yz are zero by convention. triad_frame_truth() maps the
/// simulator's truth to A: T_a^B = L Q (L lower triangular with a positive diagonal, Q a
/// rotation: Q = C_AB, vectors in B to A), accel parameters from L, gyro matrix
/// T_g^A = T_g^B Q^T, g-sensitivity G^A = G^B Q^T; biases (measurement space) unchanged.
namespace calstand::sim {

/// The truth of one IMU in the accelerometer-triad frame A (see above), contract units.
struct TriadFrameTruth {
  Eigen::Matrix3d C_AB = Eigen::Matrix3d::Identity();            ///< Q: simulator body B to frame A
  Eigen::Vector3d accel_bias = Eigen::Vector3d::Zero();          ///< m/s^2 (incl. turn-on bias)
  Eigen::Vector3d accel_scale = Eigen::Vector3d::Zero();         ///< ppm
  Eigen::Matrix3d accel_misalignment = Eigen::Matrix3d::Zero();  ///< rad, strictly lower
  /// ug/g^2, as drawn: the contract's f_i are in B, and A differs from B by the milliradians of
  /// the triad's misalignment, which change k f_i^2 by a part in a thousand of k.
  Eigen::Vector3d accel_quadratic = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();           ///< deg/s (incl. turn-on bias)
  Eigen::Vector3d gyro_scale = Eigen::Vector3d::Zero();          ///< ppm
  Eigen::Matrix3d gyro_misalignment = Eigen::Matrix3d::Zero();   ///< rad, zero diagonal
  Eigen::Matrix3d gyro_g_sensitivity = Eigen::Matrix3d::Zero();  ///< (deg/s)/g

  /// Every parameter by contract name (accel_bias.x ... gyro_misalignment.zy; the three accel
  /// misalignments fixed at zero by the convention included; accel_quadratic and
  /// gyro_g_sensitivity when non-zero), in contract units.
  std::vector<std::pair<std::string, double>> parameters() const;
};

/// The truth in frame A of an IMU whose simulator truth is `truth`, with the turn-on biases of
/// its current power-up added to the fixed biases. Throws std::invalid_argument when the
/// accelerometer matrix is singular.
TriadFrameTruth triad_frame_truth(const ImuTruth& truth, const Eigen::Vector3d& turn_on_gyro_dps,
                                  const Eigen::Vector3d& turn_on_accel_mps2);

/// A static stretch of a session (the initial rest, a hand-held pose, a Ferraris hold).
struct SessionHold {
  double start_s = 0.0;             ///< first instant of the hold (motion stopped)
  double end_s = 0.0;               ///< last instant (motion starts)
  std::size_t begin = 0;            ///< first sample index inside [start_s, end_s]
  std::size_t end = 0;              ///< one past the last sample index inside
  Eigen::Matrix3d C_LB;             ///< mean orientation of the housing (B to level frame L)
  Eigen::Vector3d up_A;             ///< unit specific force direction in frame A
  std::string label;                ///< Ferraris: x_p, x_a, ...; hand: empty
  double placement_tilt_deg = 0.0;  ///< Ferraris: the drawn placement error (angle)
  /// Mean slow noise over the hold's samples (gyro x y z [deg/s], accel x y z [m/s^2]).
  std::array<double, 6> slow_noise_mean{};
};

/// A turn between holds (or a labelled Ferraris turn).
struct SessionTurn {
  double start_s = 0.0;
  double end_s = 0.0;
  std::size_t begin = 0;
  std::size_t end = 0;
  Eigen::Vector3d axis_A;  ///< main rotation axis, fixed in the body, in frame A (unit)
  double angle_deg = 0.0;  ///< right-handed about axis_A
  double peak_rate_dps = 0.0;
  std::string label;  ///< Ferraris: x_rot, y_rot, z_rot; hand: empty
};

/// One simulated session: samples and everything that is true about them.
struct SimSession {
  std::string kind;  ///< "hand" or "ferraris"
  std::string model_name;
  std::uint64_t seed = 0;
  double sample_rate_hz = 0.0;
  core::Site site;
  double gravity_mps2 = 0.0;
  /// Samples; receive_time_s and device_time_s are the (jittered) true sample instants.
  std::vector<core::ImuSample> samples;
  /// Ferraris: the section step of every sample (1..9 for the labelled sections in time order,
  /// the moves between them numbered on, never labelled); hand: empty.
  std::vector<int> steps;
  /// Ferraris: step number -> section (hold or turn) index; see SessionHold/SessionTurn label.
  std::vector<std::pair<int, std::string>> step_labels;
  std::vector<SessionHold> holds;  ///< hand: [0] is the initial rest
  std::vector<SessionTurn> turns;  ///< hand: turns[k] joins holds[k] and holds[k+1]
  ImuTruth sim_truth;              ///< simulator frame, as drawn
  Eigen::Vector3d turn_on_gyro_dps = Eigen::Vector3d::Zero();
  Eigen::Vector3d turn_on_accel_mps2 = Eigen::Vector3d::Zero();
  TriadFrameTruth truth;  ///< frame A
  /// Mean of the slow noise processes (bias instability, Gauss-Markov, random walk) per channel
  /// (gyro x y z [deg/s], accel x y z [m/s^2]): the plain average of the holds' own means
  /// (SessionHold::slow_noise_mean) except the initial rest's, and over the initial rest: what a
  /// calibration of this session sees as part of the bias (a 5-minute session cannot tell a bias
  /// from the slow noise's offset).
  std::array<double, 6> slow_noise_mean_holds{};
  std::array<double, 6> slow_noise_mean_rest{};
  /// True mean rate over the initial rest in frame A [deg/s] (the Earth rate there).
  Eigen::Vector3d rest_true_rate_A_dps = Eigen::Vector3d::Zero();
};

/// Which IMU a session uses and where.
struct SessionImu {
  std::string spec = "adis16488";  ///< built-in spec sheet name (ln200, adis16488)
  /// A truth to use instead of a draw from `spec` (e.g. a noise-free or a hand-made unit);
  /// sample_rate_hz and keep_unmodelled_terms still apply.
  std::optional<ImuTruth> truth;
  /// Output rate [Hz]; 0 keeps the sheet's. Lower rates stand for a decimated output; the
  /// sheet's output filter is kept only when its bandwidth is below the new Nyquist frequency.
  double sample_rate_hz = 0.0;
  /// Keep the terms these methods do not estimate (g-sensitivity, scale asymmetry, quadratic);
  /// false zeroes them so the session holds exactly the model that is fitted.
  bool keep_unmodelled_terms = false;
  double latitude_deg = 45.41;
  double height_m = 12.0;
  double gravity_mps2 = 9.81744;  ///< Padova, as imu_tk's test data
};

struct HandSessionOptions {
  SessionImu imu;
  int poses = 30;                ///< static poses after the initial rest (0: a record at rest)
  double initial_rest_s = 50.0;  ///< at rest before the first turn
  double hold_min_s = 3.0;
  double hold_max_s = 10.0;
  double turn_min_s = 1.0;
  double turn_max_s = 3.0;
  double max_rate_dps = 300.0;  ///< a turn is slowed down until its peak rate is below this
  double swing_deg = 15.0;      ///< sideways swing amplitude during a turn (random up to it)
  double tremor_deg = 0.01;     ///< RMS sway angle during holds
  double lever_arm_m = 0.05;    ///< distance of the IMU from the centre of each turn
  double time_jitter = 0.05;    ///< sample-instant jitter, fraction of a period
  double min_pose_separation_deg = 30.0;  ///< gravity direction change between poses
  /// A degenerate session for checks of what it cannot determine: every pose reached from the
  /// rest by turns about this housing axis only (unit; gravity stays across it), in steps of
  /// 30-150 deg; no swing. Empty: the spread poses above.
  std::optional<Eigen::Vector3d> single_turn_axis;
};

/// A hand-held session: initial rest, then `poses` poses whose gravity directions are spread
/// over the sphere (a Fibonacci lattice under a random rotation, visited in a random order with
/// at least `min_pose_separation_deg` between consecutive ones, random heading), each held for
/// a random time, joined by hand-like turns; with no poses, the initial rest alone (a static
/// record, as a noise test records). Throws std::invalid_argument on unusable options (poses
/// < 0, a negative or inverted duration range, an unknown spec).
SimSession simulate_hand_session(const HandSessionOptions& options, std::uint64_t seed);

struct FerrarisSessionOptions {
  SessionImu imu;
  double hold_min_s = 4.0;
  double hold_max_s = 8.0;
  double move_min_s = 1.5;  ///< hand moves between sections
  double move_max_s = 3.0;
  double placement_tilt_deg = 1.0;  ///< RMS tilt of each placement (two random horizontal axes)
  double turn_s = 5.0;              ///< duration of each 360 deg turn
  double turn_pad_s = 1.0;          ///< still time inside a turn section before and after
  double turn_angle_deg = 360.0;    ///< signed: +360 counter-clockwise seen from above
  double tremor_deg = 0.01;
  double lever_arm_m = 0.03;  ///< IMU offset from the turn axis
  double time_jitter = 0.05;
};

/// A Ferraris session: x_p, x_a, y_p, y_a, z_p, z_a holds (the named housing axis up, i.e.
/// reading +g, or down), each placed with a random tilt and heading, then x_rot, y_rot, z_rot:
/// that axis up (placed with a tilt too), still, one turn of `turn_angle_deg` about the
/// vertical, still. Sections in this order, joined by unlabelled hand moves.
SimSession simulate_ferraris_session(const FerrarisSessionOptions& options, std::uint64_t seed);

}  // namespace calstand::sim
