#pragma once
// A temperature chamber whose controller speaks a line protocol given as a command set
// (command_set.hpp, docs/protocols.md "Command sets"): ESPEC, Weiss/Voetsch SimServ, Thermotron
// or a lab's own file.

#include <atomic>
#include <chrono>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "core/clock.hpp"
#include "core/station_config.hpp"
#include "drivers/chamber.hpp"
#include "drivers/command_set.hpp"
#include "drivers/device_support.hpp"
#include "drivers/line_session.hpp"

namespace calstand::drivers::line {

/// A chamber driven through a CommandSet's operations over one LineSession.
///
/// - configure(): opens the link, runs `identify` when the set has it (an information event
///   with the controller's identity), and reads the state once (read_air must answer).
/// - set_temperature(): refused before anything is sent when the target is outside the
///   station's [min_c, max_c] or the ramp is not in (0, max_ramp_c_per_min] (default: the
///   station's max_ramp_c_per_min). A set with `set_ramp` gets the ramp and the target at once
///   and the controller ramps; otherwise the driver ramps: it writes the setpoint in steps from
///   the air's temperature (or the last step written while controlling) toward the target,
///   never further from the start than ramp x elapsed station time, on every poll. Then `start`.
///   A refusal returns the controller's words.
/// - standby(): `standby` (the safe state); allowed in every configured state. When the
///   controller cannot be reached it fails, and the first poll that reaches it sends standby.
/// - read_state(): polls at most every `min_poll_interval` (wall time; between polls the last
///   poll's state is returned): read_air (+ read_setpoint, read_mode when the set has them, and
///   read_alarms on every poll: an alarm is what stops a run safely, and one more short
///   exchange a poll is cheap next to a missed alarm), then the next ramp step. setpoint_c is
///   the target the engine asked for while controlling (the engine's soak and capture band
///   compare the air with the step's target; a ramp step reported as the setpoint would say
///   the chamber is somewhere the engine never asked it to be), else the controller's setpoint.
///   A controller that cannot be read (no reply, link down, a reply out of step) sets
///   link_lost and a fault "link down: ..." with the last known values; an alarm or a fault
///   mode is a fault in the controller's words and an event. Never throws.
///
/// Thread safety: every public call holds one mutex for all its exchanges (commands and polls
/// never cross); state(), fault_counters() and take_events() do not wait for it.
class LineChamber final : public Chamber {
 public:
  /// Reads config.connection against the set (throws core::InputError naming
  /// `chamber.connection.<field>`); no I/O.
  LineChamber(const core::ChamberConfig& config, core::Clock& clock, CommandSet set,
              std::chrono::milliseconds min_poll_interval = std::chrono::milliseconds(200));
  /// Over a given transport (tests, a link opened elsewhere); `timeout` per reply.
  LineChamber(const core::ChamberConfig& config, core::Clock& clock, CommandSet set,
              std::unique_ptr<ByteTransport> transport, std::string link_name,
              std::chrono::milliseconds timeout,
              std::chrono::milliseconds min_poll_interval = std::chrono::milliseconds(0));
  ~LineChamber() override;
  LineChamber(const LineChamber&) = delete;
  LineChamber& operator=(const LineChamber&) = delete;

  const std::string& name() const override { return name_; }
  Result configure() override;
  Result activate() override;
  /// Standby, then inactive.
  Result deactivate() override;
  /// kError while the link is down after configure().
  DeviceState state() const override;
  /// timeouts, link_errors, bad_replies, refused_commands (the controller's), stray_bytes,
  /// reconnects, limit_refusals (ours: outside the station's limits), alarms.
  std::map<std::string, std::uint64_t> fault_counters() const override {
    return counters_.snapshot();
  }
  std::vector<DeviceEvent> take_events() override { return events_.take(); }

  Result set_temperature(double target_c, std::optional<double> ramp_c_per_min) override;
  Result standby() override;
  core::ChamberState read_state() override;

  const CommandSet& command_set() const { return session_->command_set(); }
  /// True when the driver ramps the setpoint itself (the set has no set_ramp).
  bool driver_ramps() const { return !session_->has("set_ramp"); }

 private:
  enum class Command { kNone, kControl, kStandby };

  // All private members are called with mutex_ held.
  /// One poll: reads, alarms, the next ramp step. False when the controller could not be read.
  bool poll();
  /// Writes the ramp's next setpoint when it is due (driver ramping only).
  void step_ramp();
  /// Runs `operation`; a link failure is noted in the state (link_lost, link_error_).
  Outcome run(const char* operation, const Arguments& args = {});
  void note_read_failure(const Outcome& o);
  void note_alarm(bool active, const std::string& words);
  core::ChamberState compose(double now_s) const;
  /// The failure Result of a command, in the controller's words.
  Result command_failure(const char* what, const Outcome& o);
  double setpoint_resolution_c() const;

  std::string name_ = "chamber";
  core::ChamberConfig config_;
  core::Clock& clock_;
  std::chrono::milliseconds min_poll_interval_;
  FaultCounters counters_{"timeouts",    "link_errors", "bad_replies",    "refused_commands",
                          "stray_bytes", "reconnects",  "limit_refusals", "alarms"};
  EventQueue events_;
  Lifecycle life_;

  mutable std::mutex mutex_;
  std::unique_ptr<LineSession> session_;
  std::atomic<bool> configured_{false};  ///< also read by state() without the lock
  bool have_reading_ = false;
  std::optional<std::chrono::steady_clock::time_point> last_poll_;
  core::ChamberState last_;  ///< last values read (kept while the link is down)
  std::optional<double> read_setpoint_c_;
  std::optional<std::string> mode_text_;  ///< read_mode's value, when the set has it
  std::atomic<bool> link_lost_{false};    ///< also read by state() without the lock
  std::string link_error_;
  std::string read_fault_;  ///< a read the controller refused, in its words
  bool alarm_ = false;
  std::string alarm_words_;
  std::string ramp_fault_;  ///< a ramp step the controller refused, in its words

  Command command_ = Command::kNone;
  double target_c_ = 0.0;
  double ramp_c_per_min_ = 0.0;
  double ramp_start_c_ = 0.0;
  double ramp_start_s_ = 0.0;
  std::optional<double> written_setpoint_c_;
  bool standby_pending_ = false;  ///< standby not reached the controller: the next poll sends it
};

/// The chamber of a station file whose backend speaks a command set ("espec", "simserv",
/// "thermotron", "line"): `set` already loaded, config.connection read against it (throws
/// core::InputError naming `chamber.connection.<field>`), nothing opened. `clock` must outlive
/// it.
std::unique_ptr<Chamber> make_line_chamber(const core::ChamberConfig& config, core::Clock& clock,
                                           const CommandSet& set);

}  // namespace calstand::drivers::line
