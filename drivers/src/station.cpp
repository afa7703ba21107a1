#include "drivers/station.hpp"

#include <stdexcept>
#include <string>

#include "core/error.hpp"
#include "drivers/real_station.hpp"
#include "drivers/sim_station.hpp"

namespace calstand::drivers {

Result Station::bring_up() {
  std::vector<Device*> devices{&table(), &chamber()};
  for (std::size_t i = 0; i < imu_count(); ++i) devices.push_back(&imu(i));
  for (std::size_t i = 0; i < power_supply_count(); ++i) devices.push_back(&power_supply(i));
  for (Device* d : devices) {
    if (auto r = d->configure(); !r) return Result::failure(d->name() + ": " + r.message);
    if (auto r = d->activate(); !r) return Result::failure(d->name() + ": " + r.message);
  }
  return Result::success();
}

Result Station::make_safe() {
  Result first = Result::success();
  auto keep_first = [&](Result r, const std::string& who) {
    if (!r && first) first = Result::failure(who + ": " + r.message);
  };
  keep_first(table().stop(), table().name());
  keep_first(chamber().standby(), chamber().name());
  for (std::size_t i = 0; i < power_supply_count(); ++i) {
    keep_first(power_supply(i).make_safe(), power_supply(i).name());
  }
  return first;
}

PowerSupply* Station::supply_of(const std::string& imu_name) {
  for (std::size_t i = 0; i < power_supply_count(); ++i) {
    if (power_supply(i).imu_name() == imu_name) return &power_supply(i);
  }
  return nullptr;
}

std::unique_ptr<Station> make_station(const core::StationConfig& config, double start_time_s,
                                      std::uint64_t noise_stream) {
  // The station file is simulated or real as a whole (StationConfig::from_json checks it).
  if (config.is_simulated()) {
    return std::make_unique<SimStation>(config, start_time_s, noise_stream);
  }
  return std::make_unique<RealStation>(config, start_time_s);
}

}  // namespace calstand::drivers
