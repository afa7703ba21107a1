#pragma once

#include <atomic>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "core/clock.hpp"
#include "core/station_config.hpp"
#include "drivers/chamber.hpp"
#include "drivers/device_support.hpp"
#include "drivers/modbus_chamber_options.hpp"
#include "drivers/modbus_client_link.hpp"

namespace calstand::drivers {

/// A temperature chamber controller over Modbus TCP or RTU (libmodbus), with the register map
/// as data (ChamberRegisterMap).
///
/// A poll thread reads process value, setpoint and mode every poll_period_ms (wall time) and
/// caches a ChamberState stamped with the station clock; read_state() returns that cache and
/// never waits on the link. When the map has no ramp register the same thread steps the setpoint
/// toward the target at the requested ramp, in station time (an accelerated clock ramps faster).
/// Implausible readings (outside [min_c - 20, max_c + 20] degC, NaN, a sensor-fault sentinel), a
/// controller mode that is neither control nor standby, and readings older than stale_after_s
/// are faults in the state, never values. A lost link is retried with backoff by the poll thread
/// (state() is kError meanwhile); the last command (setpoint or standby) is written again when
/// the link is back.
///
/// Thread safety: every public call may come from any thread. Commands and the poll thread share
/// the link under one mutex, so set_temperature()/standby() may wait for one poll cycle (bounded
/// by the response timeout); read_state(), state(), fault_counters() and take_events() never do.
class ModbusChamber final : public Chamber {
 public:
  /// Parses nothing and opens nothing: see make_modbus_chamber() for the station-config path.
  ModbusChamber(ModbusChamberOptions options, core::Clock& clock, std::string name = "chamber");
  ~ModbusChamber() override;
  ModbusChamber(const ModbusChamber&) = delete;
  ModbusChamber& operator=(const ModbusChamber&) = delete;

  const std::string& name() const override { return name_; }
  /// Connects and reads the process value once; failure says which link and why (and leaves
  /// the chamber kError). Starts the poll thread. Configuring again reconnects.
  Result configure() override;
  Result activate() override;
  /// Standby (the safe state), then inactive.
  Result deactivate() override;
  DeviceState state() const override;
  /// timeouts, bad_responses, exceptions, link_losses, reconnects, out_of_range, stale,
  /// refused_commands (ours: outside limits), refused_writes (the controller's exception).
  std::map<std::string, std::uint64_t> fault_counters() const override {
    return counters_.snapshot();
  }
  std::vector<DeviceEvent> take_events() override { return events_.take(); }

  /// Refused (no write) when not active, the link is down, target_c is outside [min_c, max_c],
  /// or the ramp is not in (0, max_ramp_c_per_min]. Otherwise writes the mode (control) and the
  /// first setpoint step (or target and ramp when the controller ramps itself) and returns the
  /// outcome of that write; the poll thread continues the steps. A failed write (timeout,
  /// controller exception) is reported, but the command stands: the poll thread retries it until
  /// it is written or the next command replaces it.
  Result set_temperature(double target_c, std::optional<double> ramp_c_per_min) override;
  /// Writes the controller's off mode, or, without a mode register, the setpoint to ambient_c.
  /// Allowed in every configured state. When the link is down it fails, and the poll thread
  /// writes standby as soon as the link is back.
  Result standby() override;
  /// The cached state; `fault` set (with the reasons) when the link is down, the last reading
  /// was implausible, or no valid reading came for stale_after_s. Never blocks on the link.
  core::ChamberState read_state() override;

  const ModbusChamberOptions& options() const { return options_; }

 private:
  enum class Command { kNone, kControl, kStandby };
  struct Reading;  // one poll's raw values (modbus_chamber.cpp)

  void start_poll_thread();
  void stop_poll_thread();
  void poll_loop();
  /// One read of PV, SP and mode into the cache; link failures handled. Needs link_mutex_.
  void poll_once();
  /// Reads PV, SP and mode (no side effects). Needs link_mutex_.
  LinkStatus read_all(Reading& r);
  /// Puts a reading into the cache (or into reading_fault_ when implausible).
  void apply_reading(const Reading& r);
  /// Writes what the command needs now (mode, the next setpoint step, standby). Needs
  /// link_mutex_. Returns the first failed write, if any.
  LinkStatus drive_command();
  /// drive_command() now, for set_temperature() and standby(); `what` names it in errors.
  Result write_command_now(const char* what);
  LinkStatus write_standby();
  /// Counts the failure; drops the link (kError, event) on a lost connection or after
  /// kMaxConsecutiveFailures timeouts/garbage in a row. Needs link_mutex_.
  void handle_failure(const LinkStatus& status);
  bool try_reconnect();
  /// Counts a write the controller refused (Modbus exception); the first per command is also
  /// an event, since the poll thread retries it every period.
  void note_refused_write(const LinkStatus& status);
  /// Emits fault/info events when the set of fault reasons changes (and counts stale episodes).
  void track_fault_transitions();
  /// The reasons the current state is a fault ("" when none). Needs state_mutex_.
  std::string fault_reasons_locked(double now_s) const;
  /// Classifies one PV reading; "" when plausible.
  std::string implausible_reason(double value_c, const RegisterWords& raw) const;

  static constexpr int kMaxConsecutiveFailures = 3;

  ModbusChamberOptions options_;
  core::Clock& clock_;
  std::string name_;
  Lifecycle life_;
  FaultCounters counters_;
  EventQueue events_;

  std::mutex link_mutex_;  // the libmodbus context is not thread safe
  ModbusClientLink link_;
  int consecutive_failures_ = 0;
  std::atomic<bool> link_up_{false};

  mutable std::mutex state_mutex_;  // never held during I/O
  bool configured_ = false;
  core::ChamberState cache_;
  double last_good_s_ = 0.0;   // station time of the last plausible PV [s]
  std::string reading_fault_;  // implausible PV or unknown mode; "" when fine
  std::string link_error_;     // why the link is down
  double link_lost_s_ = 0.0;
  Command command_ = Command::kNone;
  bool command_dirty_ = false;  // mode/ramp/standby still to be written
  double target_c_ = 0.0;
  double ramp_c_per_min_ = 0.0;
  double ramp_start_c_ = 0.0;
  double ramp_start_s_ = 0.0;
  std::optional<double> written_setpoint_c_;
  bool refusal_reported_ = false;  // one event per command when the controller refuses writes
  // Fault flags as last reported in events: events fire on changes only, since the reasons'
  // texts (ages, values) change every poll.
  bool reported_link_down_ = false;
  bool reported_bad_reading_ = false;
  bool was_stale_ = false;

  std::mutex wake_mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  std::thread poll_thread_;
};

/// The chamber of a station file whose backend is "modbus": options parsed from `config` (throws
/// core::InputError naming `chamber.connection.<field>`), nothing opened. `clock` must outlive it.
std::unique_ptr<Chamber> make_modbus_chamber(const core::ChamberConfig& config, core::Clock& clock);

}  // namespace calstand::drivers
