#pragma once

#include <array>
#include <chrono>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>

#include "core/clock.hpp"
#include "core/station_config.hpp"
#include "drivers/acutrol_protocol.hpp"
#include "drivers/device_support.hpp"
#include "drivers/line_link.hpp"
#include "drivers/serial_port.hpp"
#include "drivers/tcp_client.hpp"
#include "drivers/turntable.hpp"

namespace calstand::drivers {

/// The station file's `table.connection` for the acutrol backend:
///   {"transport": "tcp", "host": "127.0.0.1", "port": 5025, "timeout_ms": 500}
///   {"transport": "serial", "path": "/dev/ttyS0", "baud": 115200, "parity": "none"}
struct AcutrolConnection : LineLink {
  /// How long a command may wait for its reply line [ms]; also bounds each write.
  std::chrono::milliseconds response_timeout{500};

  /// Parses and validates (no I/O). Throws core::InputError naming `table.connection.<field>`
  /// and why (missing, wrong type, out of range, unknown transport or parity).
  static AcutrolConnection from_json(const nlohmann::json& connection);
};

/// A dual-axis rate table driven over the ACUTROL-style command language (acutrol_protocol.hpp,
/// docs/protocols.md), over TCP or a serial line.
///
/// - configure(): opens the link, checks the controller answers `*idn?`, sends each axis's rate
///   and acceleration limits from the TableConfig (`:limit`), reads the interlocks (an open one
///   is reported as an event).
/// - activate(): refused while an axis interlock is latched open: closing it is an operator's
///   decision (close_interlocks(), `calstand device table close-interlock`, the daemon's
///   `POST /station/interlock/close`), never a side effect of a run starting.
/// - close_interlocks(): `:interlock:close` on each axis whose interlock is open; refused
///   while a cause is present, with the controller's text.
/// - move_to()/set_rate()/start_sine(): mode then demand per axis (`:mode:sine N` and
///   `:demand:sine N,<deg>,<Hz>` for a sine); a refusal returns the controller's text.
///   Rates beyond the configured limit are refused before anything is sent.
/// - stop(): both axes to rest; allowed in every state, and tries both axes even when the link
///   is broken (best effort).
/// - read_state(): position, rate and status of both axes, stamped with the station clock
///   (before configure(): both axes faulted "not configured", no I/O).
///   No reply within the response timeout, a lost link, a refusal or a bad reply sets both
///   axes' fault flags with the reason ("table state unreadable: ..."; the last known angles
///   are kept), counts it and queues an event on the first occurrence; the link reconnects by
///   itself (TCP backoff, serial reopen). An open interlock is a fault with fault_text "interlock
///   open: <why>".
///
/// Thread safe: every call holds one mutex for all its exchanges, so status may be read from
/// another thread while the engine commands and replies never cross; a call may wait for
/// another's exchanges (at most 6, each bounded by the response timeout).
/// The cyclic calls return Result and never throw.
class AcutrolTable final : public Turntable {
 public:
  /// Parses config.connection (throws core::InputError as AcutrolConnection::from_json); no I/O.
  AcutrolTable(const core::TableConfig& config, core::Clock& clock);
  /// Over a given transport (tests, or a link opened elsewhere); `response_timeout` per command.
  AcutrolTable(const core::TableConfig& config, core::Clock& clock,
               std::unique_ptr<ByteTransport> transport,
               std::chrono::milliseconds response_timeout);
  ~AcutrolTable() override;

  const std::string& name() const override { return name_; }
  Result configure() override;
  Result activate() override;
  Result deactivate() override;
  DeviceState state() const override { return life_.state(); }
  /// timeouts, link_errors, bad_replies, refused_commands, stray_bytes, reconnects,
  /// interlock_opens.
  std::map<std::string, std::uint64_t> fault_counters() const override;
  std::vector<DeviceEvent> take_events() override { return events_.take(); }

  Result move_to(double outer_deg, double inner_deg) override;
  Result set_rate(TableAxis axis, double rate_dps) override;
  Result start_sine(TableAxis axis, double amplitude_deg, double frequency_hz) override;
  Result stop() override;
  core::TableState read_state() override;
  InterlockClosure close_interlocks() override;

 private:
  /// One command and its reply line, or why there is none.
  struct Exchange {
    enum class Outcome { kReply, kRefused, kTimeout, kLinkError, kBadReply } outcome;
    acutrol::Reply reply;
    std::string message;  ///< why, when not kReply
    bool ok() const { return outcome == Outcome::kReply; }
    /// The failure with `message`: a refusal is the controller's answer; a timeout, a link
    /// error or a garbled reply says nothing about whether the command was taken (link_lost).
    Result failure() const {
      return outcome == Outcome::kRefused ? Result::failure(message)
                                          : Result::link_failure(message);
    }
  };
  // All private members are called with mutex_ held.
  Exchange exchange(const acutrol::Command& command);
  /// exchange() expecting `OK`; the failure names the axis and the command.
  Result command_ok(const acutrol::Command& command);
  /// Link health bookkeeping: events on the transitions only, so a dead link logs once.
  void note_link_failure(const std::string& why);
  void note_link_ok();
  /// A reply that is not what the command expects (counted; one event until a good reading).
  void note_bad_reply(const std::string& why);
  Result open_link();
  /// `angle_time_s`: when the controller read the angle, as well as the station can tell (the
  /// middle of the position query's round trip) [s].
  bool read_axis(int wire_axis, core::AxisState& axis, double& angle_time_s, std::string& why);
  void note_axis_faults(const core::TableState& state);

  std::string name_ = "table";
  core::TableConfig config_;
  core::Clock& clock_;
  AcutrolConnection connection_;
  std::string link_name_;  ///< "tcp host:port", "serial /dev/..." (messages)
  std::unique_ptr<ByteTransport> transport_;
  SerialPort* serial_ = nullptr;  ///< transport_ when it is a serial port (reopened on failure)
  TcpClient* tcp_ = nullptr;      ///< transport_ when it is TCP (closed to resynchronise)
  ReconnectBackoff serial_backoff_{std::chrono::milliseconds(100), std::chrono::milliseconds(5000)};
  acutrol::LineAssembler lines_;

  mutable std::mutex mutex_;
  Lifecycle life_;
  FaultCounters counters_{"timeouts",    "link_errors", "bad_replies",    "refused_commands",
                          "stray_bytes", "reconnects",  "interlock_opens"};
  EventQueue events_;
  bool link_down_ = false;  ///< a failure was reported; the next success is a reconnect
  bool bad_reply_reported_ = false;
  core::TableState last_;  ///< last good reading (kept when the link fails)
  std::array<bool, 2> interlock_open_{false, false};  ///< outer, inner, as last seen
  std::array<bool, 2> axis_fault_{false, false};
};

/// The acutrol backend of a station's table (config.backend == "acutrol"). No I/O until
/// configure(). Throws core::InputError for a bad `table.connection`.
std::unique_ptr<Turntable> make_acutrol_table(const core::TableConfig& config, core::Clock& clock);

}  // namespace calstand::drivers
