#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/chamber_state.hpp"
#include "core/clock.hpp"
#include "core/imu_sample.hpp"
#include "core/station_config.hpp"
#include "core/table_state.hpp"
#include "sim/chamber_sim.hpp"
#include "sim/imu_sim.hpp"
#include "sim/table_sim.hpp"

namespace calstand::sim {

/// The embedded default simulated station (sim/stations/default.json).
core::StationConfig default_station();

/// The station file at `path`, or the embedded default station when `path` is empty (what
/// every `--station` option means).
core::StationConfig load_station_or_default(const std::string& path);

/// The truth of simulated IMU `index` of a station: drawn from its built-in model or spec file
/// (seeded by the station seed and the index), read from its truth file, or inline.
/// Throws core::InputError / core::SchemaError naming the file and field on bad input.
ImuTruth resolve_imu_truth(const core::ImuConfig& imu, std::uint64_t station_seed,
                           std::size_t index);

/// The seed of a station's noise processes (IMU noise, turn-on draws, chamber control noise)
/// in noise stream `stream`: the station seed itself for stream 0, else one derived from both.
/// The unit drawn from its model and the table's tilt keep the station seed in every stream: the
/// same unit on the same table, recorded anew.
std::uint64_t noise_seed(std::uint64_t station_seed, std::uint64_t stream);

/// The simulator of IMU `index` of a station as SimWorld builds it (truth from
/// resolve_imu_truth(), the station's geometry with the IMU's mount, the site and the table
/// tilt, its noise seeded by noise_seed(station seed, `noise_stream`)), not yet powered. Throws
/// core::InputError naming `imus[index]` when the truth cannot be simulated
/// (std::invalid_argument from ImuSim).
std::unique_ptr<ImuSim> make_imu_sim(const core::StationConfig& config, std::size_t index,
                                     std::uint64_t noise_stream = 0);

/// The simulated physical world of one station: table, chamber, the IMUs on the table, and the
/// virtual clock they share. Time moves only through advance()/advance_to(), as fast as the CPU
/// allows; the physics steps from one IMU sample instant to the next (at most max_step_s), the
/// thermal model every thermal_step_s. Not thread safe: one owner drives it.
class SimWorld {
 public:
  /// Receives every IMU sample as it is produced (imu index, sample).
  using SampleSink = std::function<void(std::size_t, const core::ImuSample&)>;

  /// Builds the world of `config` (every device backend must be "sim") and powers the IMUs on
  /// at `start_time_s` (the virtual clock starts there: a run resumed after a crash continues
  /// its station time instead of going back to 0). Throws core::InputError when a device is
  /// not simulated or a truth is invalid. `noise_stream` picks the noise (noise_seed()): each
  /// recorded run of a station has its own, so that two runs are two recordings.
  explicit SimWorld(const core::StationConfig& config, double start_time_s = 0.0,
                    std::uint64_t noise_stream = 0);

  /// Advances the world by dt_s (>= 0) of virtual time.
  void advance(double dt_s) { advance_to(clock_.now_s() + dt_s); }
  /// Advances the world to virtual time t_s (no-op when t_s is not later than now).
  void advance_to(double t_s);

  core::VirtualClock& clock() { return clock_; }
  double now_s() const { return clock_.now_s(); }

  TableSim& table() { return table_; }
  ChamberSim& chamber() { return chamber_; }
  std::size_t imu_count() const { return imus_.size(); }
  ImuSim& imu(std::size_t i) { return *imus_.at(i).sim; }
  const std::string& imu_name(std::size_t i) const { return imus_.at(i).name; }

  /// Every sample goes to `sink` from now on instead of the buffers (nullptr: buffer again).
  void set_sample_sink(SampleSink sink) { sink_ = std::move(sink); }
  /// Buffered samples of IMU i since the last call, oldest first.
  std::vector<core::ImuSample> take_samples(std::size_t i);

  /// Device faults for rehearsing the engine's interlocks: the next `count` samples of IMU i
  /// are generated (the sequence counter advances) but not delivered.
  void drop_samples(std::size_t i, std::uint32_t count) { imus_.at(i).drop_remaining += count; }
  /// A stalled IMU delivers nothing until released (its clock and counter keep running).
  void set_imu_stalled(std::size_t i, bool stalled) { imus_.at(i).stalled = stalled; }
  /// Powers IMU i off and on again now: a new turn-on bias (bias repeatability).
  void power_cycle_imu(std::size_t i);
  /// Switches IMU i's supply (a power supply's output). Off: the unit produces no samples (its
  /// stream stops) and cools towards the air. On after off: a cold start (ImuSim::power_on: a
  /// new turn-on bias, the truth's bias transient) and self-heating that settles from the air's
  /// temperature with the chamber's imu_time_constant_s. Switching to the state it is in does
  /// nothing.
  void set_imu_power(std::size_t i, bool on);
  bool imu_powered(std::size_t i) const { return imus_.at(i).sim->powered(); }
  /// IMU i's own temperature: the chamber's IMU temperature less the self-heating it has not
  /// (yet) built up since its last power-up [degC].
  double imu_temperature_c(std::size_t i) const;

  core::TableState table_state() const { return table_.state(clock_.now_s()); }
  core::ChamberState chamber_state() const { return chamber_.state(clock_.now_s()); }
  TableKinematics table_kinematics() const;
  const core::StationConfig& config() const { return config_; }

 private:
  struct SimulatedImu {
    std::string name;
    std::unique_ptr<ImuSim> sim;
    double first_sample_s = 0.0;
    std::uint64_t next_index = 0;  // samples are due at first_sample_s + index * period
    std::uint32_t drop_remaining = 0;
    bool stalled = false;
    /// Self-heating built up [degC]: the chamber's imu_self_heating_c when on long, 0 when off
    /// long; it moves towards either with the chamber's imu_time_constant_s.
    double self_heating_c = 0.0;
    std::vector<core::ImuSample> buffer;
    double next_due_s() const {
      return first_sample_s + static_cast<double>(next_index) * sim->sample_period_s();
    }
  };

  core::StationConfig config_;
  core::VirtualClock clock_;
  TableSim table_;
  ChamberSim chamber_;
  std::vector<SimulatedImu> imus_;
  SampleSink sink_;
  double thermal_pending_s_ = 0.0;
};

}  // namespace calstand::sim
