#include "daemon/service/station_watch.hpp"

#include <spdlog/spdlog.h>

namespace calstand::daemon::service {
namespace {

DeviceStatus status_of(const char* kind, drivers::Device& device, const std::string& backend) {
  return {kind, device.name(), backend, std::string(to_string(device.state())),
          device.fault_counters()};
}

}  // namespace

std::vector<DeviceStatus> offline_devices(const core::StationConfig& config) {
  std::vector<DeviceStatus> out{{"table", "table", config.table.backend, "offline", {}},
                                {"chamber", "chamber", config.chamber.backend, "offline", {}}};
  for (const auto& imu : config.imus) out.push_back({"imu", imu.name, imu.backend, "offline", {}});
  return out;
}

std::vector<DeviceStatus> read_devices(drivers::Station& station) {
  const auto& config = station.config();
  std::vector<DeviceStatus> out{status_of("table", station.table(), config.table.backend),
                                status_of("chamber", station.chamber(), config.chamber.backend)};
  for (std::size_t i = 0; i < station.imu_count(); ++i) {
    out.push_back(status_of("imu", station.imu(i), config.imus.at(i).backend));
  }
  return out;
}

IdleStationWatch::Reading IdleStationWatch::read() {
  const auto now = std::chrono::steady_clock::now();
  auto broken = [](drivers::Device& d) { return d.state() == drivers::DeviceState::kError; };
  if (station_ && (broken(station_->table()) || broken(station_->chamber())) && now >= next_open_) {
    station_.reset();  // open again from scratch, as a run would
  }
  if (!station_ && now >= next_open_) {
    next_open_ = now + kRetry;
    try {
      auto station = drivers::make_station(config_);
      for (drivers::Device* d : {static_cast<drivers::Device*>(&station->table()),
                                 static_cast<drivers::Device*>(&station->chamber())}) {
        if (auto r = d->configure(); !r) spdlog::warn("station between runs: {}", r.message);
      }
      station_ = std::move(station);
    } catch (const std::exception& e) {
      spdlog::warn("station between runs: {}", e.what());
    }
  }
  Reading out;
  if (!station_) {
    out.devices = offline_devices(config_);
    return out;
  }
  out.devices = read_devices(*station_);
  for (auto& d : out.devices) {
    if (d.kind == "imu") d.state = "offline";
  }
  if (!broken(station_->table())) out.table = station_->table().read_state();
  if (!broken(station_->chamber())) out.chamber = station_->chamber().read_state();
  return out;
}

drivers::InterlockClosure IdleStationWatch::close_interlocks() {
  next_open_ = {};  // an operator is waiting: open the links now if they are down
  read();
  if (!station_ || station_->table().state() == drivers::DeviceState::kError) {
    drivers::InterlockClosure out;
    out.result = drivers::Result::failure("the table's link is not up");
    return out;
  }
  return station_->table().close_interlocks();
}

}  // namespace calstand::daemon::service
