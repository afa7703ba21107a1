#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <optional>
#include <utility>

#include "core/imu_sample.hpp"
#include "core/site.hpp"
#include "core/table_geometry.hpp"
#include "sim/imu_truth.hpp"
#include "sim/noise.hpp"

namespace calstand::sim {

/// True motion of the table at one instant (what the IMU feels, not what the encoders report).
struct TableKinematics {
  double outer_deg = 0.0;
  double outer_rate_dps = 0.0;
  double outer_accel_dps2 = 0.0;
  double inner_deg = 0.0;
  double inner_rate_dps = 0.0;
  double inner_accel_dps2 = 0.0;
};

/// The physical inputs at the IMU for a table state, following error-model.md: rate in B is
/// C_BL (w_table + w_ie) (the real world always turns with the Earth), specific force in B is
/// C_BL (I - [t x]) f_L (exact rotation for the tilt t), plus the lever-arm acceleration
/// wt x (wt x r) + dwt/dt x r. `table_tilt_rad` is the tilt t of the table base about L's East
/// and North axes [rad] (the station's table.tilt_rad); the whole table, axes included, is
/// tilted, so the Earth rate enters the table frame through the same rotation as gravity.
/// Everything that does not change with the table state (gravity, Earth rate, tilt, axes) is
/// computed once at construction: this runs for every sample.
class ImuInputModel {
 public:
  ImuInputModel(const ImuTruth& truth, const core::TableGeometry& geometry, const core::Site& site,
                const Eigen::Vector2d& table_tilt_rad);
  ImuInputs operator()(const TableKinematics& table, double temperature_c) const;

 private:
  Eigen::Vector3d outer_axis_;  // unit, in the table base frame
  Eigen::Vector3d inner_axis_;  // unit, at outer = 0
  Eigen::Matrix3d mount_C_PB_;
  Eigen::Vector3d force_base_mps2_;  // gravity's specific force in the (tilted) base frame
  Eigen::Vector3d earth_base_dps_;   // Earth rate in the base frame [deg/s]
  Eigen::Vector3d lever_arm_m_;
  // The rotations of the last table angles: a static table (most of a campaign) reuses them
  // instead of two sin/cos pairs per sample. Not thread safe, like the simulator that owns it.
  struct RotationCache {
    double outer_deg = std::numeric_limits<double>::quiet_NaN();
    double inner_deg = std::numeric_limits<double>::quiet_NaN();
    Eigen::Matrix3d C_BL;
    Eigen::Vector3d inner_now;
  };
  mutable RotationCache cache_;
};

/// One-off form of ImuInputModel (for tests and tools; the simulator keeps a model).
ImuInputs imu_inputs(const ImuTruth& truth, const core::TableGeometry& geometry,
                     const core::Site& site, const Eigen::Vector2d& table_tilt_rad,
                     const TableKinematics& table, double temperature_c);

/// One simulated IMU: truth terms, noise processes, output filter, quantization, sequence
/// counter and device clock. Seeded: the same seed and the same calls give the same samples.
/// Not thread safe; owned by the simulated world.
class ImuSim {
 public:
  /// `table_tilt_rad`: see ImuInputModel. Each sensor's output filter follows its own
  /// bandwidth (ImuTruth::gyro_bandwidth_hz, accel_bandwidth_hz).
  /// Throws std::invalid_argument when the truth's output settings or noise are unusable.
  ImuSim(ImuTruth truth, core::TableGeometry geometry, core::Site site,
         const Eigen::Vector2d& table_tilt_rad, std::uint64_t seed);

  /// Powers the IMU up at `time_s`: a new turn-on bias per channel, the sequence counter and the
  /// device clock restart, the output filter starts settled. Every power-up draws new values.
  /// From a cold start (`warm` false) the truth's power-on bias transient runs from `time_s`;
  /// `warm` stands for a unit that has been on for long before `time_s` (a simulated world
  /// starting, a run resumed): its transient is over.
  void power_on(double time_s, bool warm = false);
  void power_off() { powered_ = false; }
  bool powered() const { return powered_; }
  int power_cycles() const { return power_cycles_; }

  double sample_period_s() const { return 1.0 / truth_.sample_rate_hz; }

  /// The sample at station time `time_s` (the caller steps time at sample_period_s()).
  core::ImuSample sample(double time_s, const TableKinematics& table, double temperature_c);
  /// The sample at `time_s` for physical inputs the caller has computed itself (a motion that
  /// no table makes, e.g. an IMU turned by hand: sim/hand_session.hpp). `in.rate_dps` must
  /// already hold the Earth rate when the world is to have one. Same error terms, noise and
  /// output chain as the table form.
  core::ImuSample sample(double time_s, const ImuInputs& in);

  /// The slowly varying noise (bias instability, Gauss-Markov, random walk; not the white
  /// noise) each channel added to the last sample, before the output filter [deg/s for gyro
  /// x y z, m/s^2 for accel x y z]. What a calibration of a short session sees as part of the
  /// bias; a simulator of sessions averages it to state that bias exactly.
  const std::array<double, 6>& last_slow_noise() const { return last_slow_noise_; }

  /// What a noise-free copy of this IMU reads at `table` and `temperature_c`: the same
  /// deterministic errors and the turn-on bias in force, without noise, output filter or
  /// quantization (the simulator's truth, which a real station would not know) [deg/s, m/s^2].
  std::pair<Eigen::Vector3d, Eigen::Vector3d> noise_free_reading(const TableKinematics& table,
                                                                 double temperature_c) const;

  /// The power-on transient's bias offsets at `time_s` (zero before the last power_on(), after
  /// a warm one, or for a truth without a transient) [deg/s, m/s^2].
  std::pair<Eigen::Vector3d, Eigen::Vector3d> power_on_transient(double time_s) const;

  /// The turn-on bias in force since the last power_on() [deg/s, m/s^2].
  const Eigen::Vector3d& turn_on_gyro_bias() const { return turn_on_gyro_; }
  const Eigen::Vector3d& turn_on_accel_bias() const { return turn_on_accel_; }
  /// The turn-on scale-factor changes in force since the last power_on() [ppm].
  const Eigen::Vector3d& turn_on_gyro_scale_ppm() const { return turn_on_gyro_scale_ppm_; }
  const Eigen::Vector3d& turn_on_accel_scale_ppm() const { return turn_on_accel_scale_ppm_; }

  const ImuTruth& truth() const { return truth_; }
  const core::TableGeometry& geometry() const { return geometry_; }

 private:
  /// The hysteresis branch at `temperature_c`: (T - y) / width of the play operator y, which
  /// this advances, in [-1/2, 1/2].
  double hysteresis_branch(double temperature_c);
  /// The turn-on scale-factor change's part of a reading of true input `input` (gyro or
  /// accelerometer) [deg/s, m/s^2].
  Eigen::Vector3d turn_on_scale_error(const Eigen::Vector3d& input, bool gyro) const {
    return 1e-6 * (gyro ? turn_on_gyro_scale_ppm_ : turn_on_accel_scale_ppm_).cwiseProduct(input);
  }
  double play_c_ = 0.0;  ///< the play operator's state [degC]
  bool play_started_ = false;

  // Noise and output chain of one axis of one sensor.
  struct Channel {
    std::optional<WhiteNoise> white;
    std::optional<BiasInstability> bias_instability;
    std::optional<RandomWalk> random_walk;
    std::optional<GaussMarkov> gauss_markov;
    std::optional<ButterworthLowPass> low_pass;
    Quantizer quantizer{0.0};
    /// The sum of every process; `slow` gets the part without the white noise.
    double noise(double& slow);
  };
  void build_channels();

  ImuTruth truth_;
  core::TableGeometry geometry_;
  core::Site site_;
  ImuInputModel input_model_;
  std::uint64_t seed_;
  std::array<Channel, 6> channels_;  // gyro x y z, accel x y z
  NormalSource turn_on_draw_;
  Eigen::Vector3d turn_on_gyro_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d turn_on_accel_ = Eigen::Vector3d::Zero();
  // Its own stream: a truth without a turn-on scale draws the same turn-on biases as before.
  NormalSource turn_on_scale_draw_;
  Eigen::Vector3d turn_on_gyro_scale_ppm_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d turn_on_accel_scale_ppm_ = Eigen::Vector3d::Zero();
  bool powered_ = false;
  bool filter_primed_ = false;
  int power_cycles_ = 0;
  double power_on_time_s_ = 0.0;
  bool transient_running_ = false;  ///< the last power-up was cold
  std::uint32_t sequence_ = 0;
  std::array<double, 6> last_slow_noise_{};
};

}  // namespace calstand::sim
