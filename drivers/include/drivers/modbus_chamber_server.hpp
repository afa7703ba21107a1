#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "core/chamber_state.hpp"
#include "drivers/chamber_register_map.hpp"
#include "drivers/device.hpp"
#include "drivers/pseudo_terminal.hpp"
#include "sim/sim_world.hpp"

namespace calstand::drivers {

/// What a chamber controller does, as the Modbus server sees it. Called from the server's
/// thread; implementations synchronise with whatever else touches the chamber.
class ChamberServerBackend {
 public:
  enum class Mode { kControl, kStandby };
  virtual ~ChamberServerBackend() = default;
  /// Air temperature, setpoint (the one the controller holds, even in standby) and mode.
  virtual core::ChamberState state() = 0;
  /// The controller's setpoint [degC]: followed at once when controlling, kept for later in
  /// standby. A failure is answered with Modbus exception 3 (illegal data value).
  virtual Result set_setpoint(double setpoint_c) = 0;
  virtual Result set_mode(Mode mode) = 0;
  /// The controller's own ramp [degC/min], for maps with a ramp register.
  virtual Result set_ramp(double ramp_c_per_min) = 0;
};

/// The chamber of a simulated world behind a Modbus server. Locks `world_mutex` on every call,
/// since another thread advances the world under it. Both must outlive the backend.
class SimChamberBackend final : public ChamberServerBackend {
 public:
  SimChamberBackend(sim::SimWorld& world, std::mutex& world_mutex);
  core::ChamberState state() override;
  Result set_setpoint(double setpoint_c) override;
  Result set_mode(Mode mode) override;
  Result set_ramp(double ramp_c_per_min) override;

 private:
  sim::SimWorld& world_;
  std::mutex& mutex_;
  double setpoint_c_;                     // held while in standby, as a real controller does
  std::optional<double> ramp_c_per_min_;  // default: the simulated chamber's own maximum
};

/// A protocol simulator: serves a chamber to Modbus clients through a register map, as the
/// controller would. Reads reflect the backend's state at each request; writes to the setpoint,
/// mode and ramp registers act on it (a refused value is answered with exception 3, a write to
/// any other register with exception 2). A map without a mode register (F4) starts control on
/// a setpoint write, as that controller does.
///
/// Two transports: Modbus TCP, bound to 127.0.0.1 by default (any number of clients), or Modbus RTU
/// on a pseudo-terminal whose slave a client opens as its serial port. start()/stop() run and end a
/// server thread; stop() is also how tests make the controller vanish: TCP clients see the
/// connection closed, RTU clients see no answer. start() again serves on the same port or pty.
/// Not thread safe itself (one owner calls start/stop); the backend is called from its thread.
class ModbusChamberServer {
 public:
  /// Modbus TCP on `bind_host`:`port` (0: an ephemeral port, see port() after start()).
  /// `bind_host` is an IPv4 address (libmodbus does not resolve names); the default keeps the
  /// simulator off the lab network.
  static std::unique_ptr<ModbusChamberServer> tcp(ChamberRegisterMap map,
                                                  ChamberServerBackend& backend, int port = 0,
                                                  int unit_id = 1,
                                                  std::string bind_host = "127.0.0.1");
  /// Modbus RTU on a new pseudo-terminal (see slave_path()). Throws std::runtime_error when
  /// no pseudo-terminal can be made.
  static std::unique_ptr<ModbusChamberServer> rtu(ChamberRegisterMap map,
                                                  ChamberServerBackend& backend, int unit_id = 1);
  ~ModbusChamberServer();
  ModbusChamberServer(const ModbusChamberServer&) = delete;
  ModbusChamberServer& operator=(const ModbusChamberServer&) = delete;

  /// Binds (TCP) and starts serving. Throws std::runtime_error naming the address and the OS
  /// error when it cannot listen. No-op when running.
  void start();
  /// Stops serving and joins the thread; closes TCP connections. Never throws.
  void stop() noexcept;
  bool running() const { return thread_.joinable(); }

  int port() const { return port_; }                    ///< TCP: the bound port (after start())
  std::string slave_path() const;                       ///< RTU: the path clients open
  std::uint64_t requests() const { return requests_; }  ///< requests answered (any outcome)

 private:
  struct Impl;
  ModbusChamberServer(ChamberRegisterMap map, ChamberServerBackend& backend, int port, int unit_id,
                      bool rtu, std::string bind_host);
  void serve_tcp();
  void serve_rtu();
  /// Answers one request of `length` bytes in `query` (refreshes registers, applies writes).
  void answer(const std::uint8_t* query, int length);

  ChamberRegisterMap map_;
  ChamberServerBackend& backend_;
  int port_;
  int unit_id_;
  std::string bind_host_;
  std::unique_ptr<PseudoTerminal> pty_;
  std::unique_ptr<Impl> impl_;
  std::atomic<bool> stopping_{false};
  std::atomic<std::uint64_t> requests_{0};
  std::thread thread_;
};

}  // namespace calstand::drivers
