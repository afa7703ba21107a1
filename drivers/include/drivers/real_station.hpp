#pragma once

#include <memory>
#include <vector>

#include "drivers/station.hpp"

namespace calstand::drivers {

/// A station of real devices: the drivers the station file names (table "acutrol", chamber
/// "modbus", IMUs "serial" or "socketcan", supplies "scpi"), on the steady clock (scaled by the
/// file's time_scale when rehearsing against an accelerated sim-station). Construction parses every
/// connection and opens nothing; bring_up() opens the links.
class RealStation final : public Station {
 public:
  /// Throws core::InputError naming the device field when a backend or connection is wrong.
  /// Its clock reads `start_time_s` now.
  explicit RealStation(const core::StationConfig& config, double start_time_s = 0.0);
  ~RealStation() override;

  const core::StationConfig& config() const override { return config_; }
  core::Clock& clock() override { return clock_; }
  Turntable& table() override { return *table_; }
  Chamber& chamber() override { return *chamber_; }
  std::size_t imu_count() const override { return imus_.size(); }
  Imu& imu(std::size_t index) override { return *imus_.at(index); }
  std::size_t power_supply_count() const override { return supplies_.size(); }
  PowerSupply& power_supply(std::size_t index) override { return *supplies_.at(index); }
  void wait_until(double t_s) override { clock_.sleep_until(t_s); }

 private:
  core::StationConfig config_;
  core::SteadyClock clock_;
  std::unique_ptr<Turntable> table_;
  std::unique_ptr<Chamber> chamber_;
  std::vector<std::unique_ptr<Imu>> imus_;
  std::vector<std::unique_ptr<PowerSupply>> supplies_;
};

}  // namespace calstand::drivers
