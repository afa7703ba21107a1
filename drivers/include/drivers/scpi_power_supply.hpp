#pragma once

#include <chrono>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "core/clock.hpp"
#include "core/station_config.hpp"
#include "drivers/acutrol_protocol.hpp"
#include "drivers/device_support.hpp"
#include "drivers/line_link.hpp"
#include "drivers/power_supply.hpp"
#include "drivers/scpi_commands.hpp"
#include "drivers/serial_port.hpp"
#include "drivers/tcp_client.hpp"

namespace calstand::drivers {

/// The station file's `power_supplies[].connection` for the scpi backend:
///   {"transport": "tcp", "host": "192.168.10.30", "port": 5025, "model": "generic"}
///   {"transport": "serial", "path": "/dev/ttyUSB1", "baud": 9600}
struct ScpiConnection : LineLink {
  const scpi::CommandSet* commands = &scpi::kCommandSets[0];
  /// How long a query may wait for its reply line [ms]; also bounds each write.
  std::chrono::milliseconds response_timeout{1000};

  /// Parses and validates (no I/O) against the schema's `scpi_connection`. Throws
  /// core::InputError naming `<where>.<field>`.
  static ScpiConnection from_json(const nlohmann::json& connection, const std::string& where);
};

/// A programmable bench supply over SCPI (docs/protocols.md, Power supply over SCPI), over TCP
/// or a serial line, speaking the command set of its model (scpi_commands.hpp).
///
/// - configure(): opens the link, `*IDN?` (an event names the instrument), `*CLS`, then sets
///   the voltage and current limit of the station file. The output is left as it is.
/// - Every set command is followed by `SYST:ERR?`: an error the supply reports fails the call
///   with its code and text (`refused_commands`), and the rest of its error queue is read out.
/// - set_output() confirms the state with the output query.
/// - No reply within the response timeout, or a lost link: the call fails (`timeouts`,
///   `link_errors`), one `link lost` event, the link is reopened on the next call (TCP with
///   backoff), and a `link back` event follows the first good reply (`reconnects`).
/// - make_safe(): safe_state "off" sends the output off in every lifecycle state; "on" sends
///   nothing.
///
/// Thread safe: one mutex around each call's exchanges. Never throws after construction.
class ScpiPowerSupply final : public PowerSupply {
 public:
  /// Parses config.connection (throws core::InputError naming `where`); no I/O.
  ScpiPowerSupply(const core::PowerSupplyConfig& config, core::Clock& clock,
                  const std::string& where = "power_supplies[].connection");
  ~ScpiPowerSupply() override;

  const std::string& name() const override { return config_.name; }
  const std::string& imu_name() const override { return config_.imu; }
  Result configure() override;
  Result activate() override;
  Result deactivate() override;
  DeviceState state() const override { return life_.state(); }
  /// timeouts, link_errors, bad_replies, refused_commands, reconnects.
  std::map<std::string, std::uint64_t> fault_counters() const override;
  std::vector<DeviceEvent> take_events() override { return events_.take(); }

  Result set_output(bool on) override;
  Result set_voltage(double volts) override;
  Result set_current_limit(double amps) override;
  PowerReading read() override;
  Result make_safe() override;

 private:
  // All private members are called with mutex_ held.
  /// Sends one line; with `want_reply`, returns the reply line. Failure: why.
  Result send(const std::string& line, bool want_reply, std::string* reply);
  /// A set command, then `SYST:ERR?`: fails with the supply's error when it reports one.
  Result command(const std::string& line);
  /// A query answered by a number.
  Result query_number(std::string_view query, double& value);
  Result query_boolean(std::string_view query, bool& value);
  Result output_locked(bool on);
  Result open_link();
  void note_link_failure(const std::string& why);
  void note_link_ok();

  core::PowerSupplyConfig config_;
  core::Clock& clock_;
  ScpiConnection connection_;
  std::unique_ptr<ByteTransport> transport_;
  SerialPort* serial_ = nullptr;
  TcpClient* tcp_ = nullptr;
  ReconnectBackoff serial_backoff_{std::chrono::milliseconds(100), std::chrono::milliseconds(5000)};
  acutrol::LineAssembler lines_;  ///< the same LF-terminated line framing as the table's

  mutable std::mutex mutex_;
  Lifecycle life_;
  FaultCounters counters_{"timeouts", "link_errors", "bad_replies", "refused_commands",
                          "reconnects"};
  EventQueue events_;
  bool link_down_ = false;
  PowerReading last_;
};

/// The scpi backend of a station's supply (config.backend == "scpi"). No I/O until
/// configure(). Throws core::InputError for a bad connection, naming `where`.
std::unique_ptr<PowerSupply> make_scpi_power_supply(const core::PowerSupplyConfig& config,
                                                    core::Clock& clock, const std::string& where);

}  // namespace calstand::drivers
