#pragma once

#include <memory>
#include <string>
#include <vector>

#include "drivers/station.hpp"
#include "sim/sim_world.hpp"

namespace calstand::drivers {

/// The in-process simulator backend of every device: a sim::SimWorld behind the device
/// interfaces, on its virtual clock. Ships in the product (procedure rehearsal, CI stations,
/// teaching); tests reach the world through world() to inject faults.
class SimStation final : public Station {
 public:
  /// The simulated station of `config`, its virtual clock starting at `start_time_s`.
  /// `noise_stream`: sim::SimWorld's (each recorded run its own).
  explicit SimStation(const core::StationConfig& config, double start_time_s = 0.0,
                      std::uint64_t noise_stream = 0);
  ~SimStation() override;

  const core::StationConfig& config() const override { return world_.config(); }
  core::Clock& clock() override { return world_.clock(); }
  Turntable& table() override;
  Chamber& chamber() override;
  std::size_t imu_count() const override { return imus_.size(); }
  Imu& imu(std::size_t index) override;
  std::size_t power_supply_count() const override { return supplies_.size(); }
  PowerSupply& power_supply(std::size_t index) override;
  void wait_until(double t_s) override { world_.advance_to(t_s); }

  sim::SimWorld& world() { return world_; }

 private:
  class SimTurntable;
  class SimChamber;
  class SimImu;
  class SimPowerSupply;
  sim::SimWorld world_;
  std::unique_ptr<SimTurntable> table_;
  std::unique_ptr<SimChamber> chamber_;
  std::vector<std::unique_ptr<SimImu>> imus_;
  std::vector<std::unique_ptr<SimPowerSupply>> supplies_;
};

}  // namespace calstand::drivers
