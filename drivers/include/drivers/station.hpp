#pragma once

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/clock.hpp"
#include "core/station_config.hpp"
#include "drivers/chamber.hpp"
#include "drivers/imu.hpp"
#include "drivers/power_supply.hpp"
#include "drivers/turntable.hpp"

namespace calstand::drivers {

/// A whole station: its devices and the clock they share. The engine talks only to this.
class Station {
 public:
  virtual ~Station() = default;
  virtual const core::StationConfig& config() const = 0;
  virtual core::Clock& clock() = 0;
  virtual Turntable& table() = 0;
  virtual Chamber& chamber() = 0;
  virtual std::size_t imu_count() const = 0;
  virtual Imu& imu(std::size_t index) = 0;
  /// The supplies of the station file's `power_supplies`, in its order.
  virtual std::size_t power_supply_count() const { return 0; }
  /// (Defined inline: the base part's SimStation links without the station part.)
  virtual PowerSupply& power_supply(std::size_t index) {
    throw std::out_of_range("station has no power supply " + std::to_string(index));
  }
  /// The supply feeding IMU `imu_name`, or nullptr when the station does not switch it.
  PowerSupply* supply_of(const std::string& imu_name);
  /// Lets station time pass until `t_s`: a simulated station advances its world (as fast as
  /// the CPU allows), a real one sleeps.
  virtual void wait_until(double t_s) = 0;
  /// configure() and activate() every device; the first failure is returned.
  Result bring_up();
  /// Table to rest, chamber to standby, each supply to its safe state (off, or left on, per
  /// the station file): the safe state; best effort on every device, the first failure is
  /// returned.
  Result make_safe();
};

/// The station of `config`: a SimStation when its devices are simulated (its virtual clock
/// starting at `start_time_s`), a RealStation of drivers otherwise (on the steady clock, which
/// reads `start_time_s` now). Throws core::InputError naming the device on a bad connection.
/// `noise_stream` picks a simulated station's noise (sim::SimWorld); a real station has its own.
std::unique_ptr<Station> make_station(const core::StationConfig& config, double start_time_s = 0.0,
                                      std::uint64_t noise_stream = 0);

}  // namespace calstand::drivers
