#pragma once

#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>

#include "drivers/acutrol_server.hpp"

namespace calstand::sim {
class SimWorld;
}

namespace calstand::drivers {

/// A bench supply as its SCPI parser sees it, feeding simulated IMU `imu_index` of `world`
/// (its output switches the unit: SimWorld::set_imu_power). Thread safe: every call locks
/// `world_mutex`, under which another thread advances the world.
///
/// Takes the short forms of the generic command table (scpi_commands.hpp), case-insensitive:
/// `*IDN?`, `*CLS`, `OUTP ON|OFF|1|0`, `OUTP?`, `VOLT <V>`, `VOLT?`, `CURR <A>`, `CURR?`,
/// `MEAS:VOLT?`, `MEAS:CURR?`, `SYST:ERR?`. Set commands are not answered; a bad one queues an
/// error (-113 undefined header, -222 data out of range, -224 illegal parameter value, -109
/// missing parameter) that `SYST:ERR?` reads, oldest first, then `0,"No error"`.
class SimScpiSupply {
 public:
  SimScpiSupply(sim::SimWorld& world, std::mutex& world_mutex, std::size_t imu_index,
                double voltage_v, double current_limit_a);
  /// The reply to one command line, or none (set commands).
  std::optional<std::string> handle(std::string_view line);

  /// Highest voltage the simulated supply takes [V]; more is -222.
  static constexpr double kMaxVoltageV = 60.0;
  static constexpr double kMaxCurrentA = 10.0;  ///< highest current limit [A]
  static constexpr double kLoadPowerW = 12.0;   ///< what a simulated unit draws [W]

 private:
  void push_error(int code, std::string_view text);

  sim::SimWorld& world_;
  std::mutex& mutex_;
  std::size_t imu_index_;
  double voltage_v_;
  double current_limit_a_;
  std::deque<std::pair<int, std::string>> errors_;
};

/// The SCPI protocol simulator of one supply: SimScpiSupply served over TCP (and, if asked, a
/// pseudo-terminal) by the line server the table simulator uses.
class ScpiServer {
 public:
  ScpiServer(sim::SimWorld& world, std::mutex& world_mutex, std::size_t imu_index, double voltage_v,
             double current_limit_a, AcutrolServerOptions options = {});
  void start() { server_->start(); }
  void stop() noexcept { server_->stop(); }
  std::uint16_t port() const { return server_->port(); }
  std::string start_serial() { return server_->start_serial(); }
  /// Drops every client connection now (a broken link); listening goes on.
  void drop_clients() { server_->drop_clients(); }
  /// false: commands are read but never answered (a hung instrument).
  void set_answering(bool answering) { server_->set_answering(answering); }

 private:
  std::unique_ptr<SimScpiSupply> supply_;
  std::unique_ptr<AcutrolServer> server_;
};

}  // namespace calstand::drivers
