#pragma once

#include <array>
#include <chrono>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "core/clock.hpp"
#include "core/station_config.hpp"
#include "drivers/command_set.hpp"
#include "drivers/device_support.hpp"
#include "drivers/line_session.hpp"
#include "drivers/turntable.hpp"

namespace calstand::drivers {

/// A dual-axis rate table whose controller speaks a line protocol given as a command set
/// (drivers/command_set.hpp, docs/protocols.md "Command sets"): ACUTROL3000, Ideal Aerosmith,
/// Actidyn, Aerotech A3200 or a lab's own file. The operations it uses, each optional unless
/// said: identify, set_limits, position (required), rate (required), sine, stop (required),
/// read_position (required), read_rate, read_status, read_interlock, close_interlock.
///
/// - configure(): opens the link, runs identify (its `identity` becomes an event), sends each
///   axis's rate and acceleration limits from the TableConfig (set_limits), reads the
///   interlocks (an open one is an event). What the set lacks is said once, as an event.
/// - activate(): refused while an axis interlock is latched open: closing it is an operator's
///   decision (close_interlocks()), never a side effect of a run starting.
/// - move_to()/set_rate()/start_sine(): the set's position/rate/sine operation per axis; rates
///   and sines beyond the configured limits are refused before anything is sent; a refusal
///   carries the controller's words; an operation that reports the axis's `mode` must report
///   the mode asked for. start_sine() is refused, saying why, when the set has no sine.
/// - stop(): the set's stop on both axes; allowed in every state, tries both axes even when the
///   link is broken (best effort).
/// - read_state(): read_position, read_rate and read_status per axis (and read_interlock:
///   an open interlock is a fault "interlock open: <why>"). Without read_rate (and no `rate_dps`
///   in the position reply) the rate is the difference of successive angles over their times;
///   without an `in_position` from the controller, in_position is derived: position mode, the
///   angle within the axis's position_tolerance_deg of the demand for settle_time_s; rate mode,
///   the rate within rate_tolerance_dps of the demand for settle_time_s; sine mode, settle_time_s
///   after the start. The state's time is the middle of the outer angle's query, the inner
///   angle moved back to it at its rate. A reading that fails sets both axes' faults with the
///   reason ("table state unreadable: ...", last known angles kept) and, when the controller
///   could not be reached (timeout, link error), `link_lost`; the link reconnects by itself.
///   Before configure(): both axes faulted "not configured", no I/O. Never throws.
///
/// Thread safe: one mutex around every call, so replies never cross.
class LineTable final : public Turntable {
 public:
  /// Reads config.connection for `set` (throws core::InputError naming table.connection.<field>);
  /// no I/O.
  LineTable(const core::TableConfig& config, core::Clock& clock, line::CommandSet set);
  /// Over a given transport (tests); `timeout` per reply.
  LineTable(const core::TableConfig& config, core::Clock& clock, line::CommandSet set,
            std::unique_ptr<ByteTransport> transport, std::chrono::milliseconds timeout);
  ~LineTable() override;

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
  /// What the driver keeps per axis beyond the controller's words: the demand, for the
  /// derived in-position and rate.
  struct AxisTrack {
    core::AxisMode commanded = core::AxisMode::kRest;
    double demand_deg = 0.0;                ///< position mode: the demanded angle, wrapped [deg]
    double demand_rate_dps = 0.0;           ///< rate mode: the demanded rate [deg/s]
    double commanded_at_s = 0.0;            ///< station clock when the demand was sent [s]
    std::optional<double> settled_since_s;  ///< in tolerance since [s]
    std::optional<double> last_angle_deg;   ///< previous reading, for the rate by difference
    double last_angle_time_s = 0.0;
    double unwrapped_deg = 0.0;  ///< the angle without its wraps [deg]
    /// (station time [s], unwrapped angle [deg]) over the last kDerivedRateWindowS
    std::deque<std::pair<double, double>> history;
  };
  /// An axis interlock as read.
  struct Interlock {
    bool open = false;
    std::string why;
  };
  // All private members are called with mutex_ held.
  line::Arguments axis_args(std::size_t axis) const;
  /// session_->run that never throws (a template naming an argument not given is a bad reply).
  line::Outcome run(const char* operation, const line::Arguments& args);
  /// Runs a motion operation; `expect` is the mode the axis must report when the reply says.
  Result run_motion(const char* operation, std::size_t axis, const line::Arguments& args,
                    const char* expect);
  /// The axis's interlock, or nullopt with why (`link_lost`: the controller was not reached).
  std::optional<Interlock> read_interlock(std::size_t axis, std::string& why,
                                          bool* link_lost = nullptr);
  bool read_axis(std::size_t axis, core::AxisState& out, double& angle_time_s, std::string& why,
                 bool& link_lost);
  void note_axis_faults(const core::TableState& state);

  std::string name_ = "table";
  core::TableConfig config_;
  core::Clock& clock_;
  line::CommandSet set_;
  FaultCounters counters_{"timeouts",    "link_errors", "bad_replies",    "refused_commands",
                          "stray_bytes", "reconnects",  "interlock_opens"};
  EventQueue events_;
  std::unique_ptr<line::LineSession> session_;

  mutable std::mutex mutex_;
  Lifecycle life_;
  core::TableState last_;  ///< last good reading (kept when the link fails)
  std::array<AxisTrack, 2> track_{};
  std::array<bool, 2> interlock_open_{false, false};  ///< outer, inner, as last seen
  std::array<bool, 2> axis_fault_{false, false};
};

/// A command-set table (station `table.backend` naming a built-in set or "line" with a
/// `command_set` file). No I/O until configure(). Throws core::InputError for a bad
/// `table.connection`.
std::unique_ptr<Turntable> make_line_table(const core::TableConfig& config, core::Clock& clock,
                                           const line::CommandSet& set);

}  // namespace calstand::drivers
