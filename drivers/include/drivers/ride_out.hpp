#pragma once
// Riding out a dropped link outside a run, as the engine does inside one: `calstand device`
// repeats a harmless command (a read, a setpoint, a position or rate demand, a stop) that got
// no answer while its device's link is down, for up to the station's policy.link_outage_s.

#include <functional>
#include <string>

#include "core/chamber_state.hpp"
#include "core/clock.hpp"
#include "core/station_config.hpp"
#include "core/table_state.hpp"
#include "drivers/device.hpp"

namespace calstand::drivers {

class Chamber;
class Turntable;

/// How long and how often to try again.
struct RideOutPolicy {
  /// Give up once the link has been down this long [station s] (the station's
  /// policy.link_outage_s).
  double limit_s = 5.0;
  /// Pause before the first repeat [station s]; doubles after each up to max_pause_s. The
  /// drivers reconnect on each try, so this is also their reconnect backoff.
  double first_pause_s = 0.2;
  double max_pause_s = 2.0;

  /// The station's rule: limit_s is its policy.link_outage_s, as a run's engine has it.
  static RideOutPolicy from_policy(const core::FaultPolicy& policy);
  /// Throws core::InputError naming `where`.<field> for a negative or non-finite limit or a
  /// pause that is not positive.
  void validate(const std::string& where) const;
};

/// Calls `attempt` until it succeeds, fails for a reason other than its link (Result::link_lost
/// false: the device refused; returned as it is), or the link has been down longer than
/// `policy.limit_s` on `clock`: then the failure reads "DEVICE link down for X s (more than the
/// policy's Y s): <the last failure>" with link_lost set. Only for commands that are harmless
/// to repeat: one that got no reply may have been taken. On a virtual clock (which only its
/// owner moves) there is one attempt: waiting on it would never end.
Result ride_out(const std::string& device, core::Clock& clock, const RideOutPolicy& policy,
                const std::function<Result()>& attempt);

/// A state read through an outage: `state` is the last one read; `result` fails when the
/// controller could not be read within the policy (link_lost state throughout).
template <typename State>
struct RiddenRead {
  State state;
  Result result;
};

/// table.read_state() until its link_lost is false, within the policy.
RiddenRead<core::TableState> read_riding_out(Turntable& table, core::Clock& clock,
                                             const RideOutPolicy& policy);
/// chamber.read_state() until its link_lost is false, within the policy.
RiddenRead<core::ChamberState> read_riding_out(Chamber& chamber, core::Clock& clock,
                                               const RideOutPolicy& policy);

}  // namespace calstand::drivers
