#include "drivers/ride_out.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "drivers/chamber.hpp"
#include "drivers/turntable.hpp"

namespace calstand::drivers {

RideOutPolicy RideOutPolicy::from_policy(const core::FaultPolicy& policy) {
  RideOutPolicy out;
  out.limit_s = policy.link_outage_s;
  return out;
}

void RideOutPolicy::validate(const std::string& where) const {
  if (!std::isfinite(limit_s) || limit_s < 0.0) {
    throw core::InputError(where + ".limit_s", fmt::format("{} s is not >= 0", limit_s));
  }
  if (!std::isfinite(first_pause_s) || first_pause_s <= 0.0) {
    throw core::InputError(where + ".first_pause_s", fmt::format("{} s is not > 0", first_pause_s));
  }
  if (!std::isfinite(max_pause_s) || max_pause_s < first_pause_s) {
    throw core::InputError(
        where + ".max_pause_s",
        fmt::format("{} s is not >= first_pause_s ({} s)", max_pause_s, first_pause_s));
  }
}

Result ride_out(const std::string& device, core::Clock& clock, const RideOutPolicy& policy,
                const std::function<Result()>& attempt) {
  Result r = attempt();
  if (r || !r.link_lost || clock.is_virtual()) return r;
  // Counted from the first failure: when the link went is unknown, and a command given while it
  // was already down gets the whole allowance, as the engine gives a run.
  const double down_since_s = clock.now_s();
  double pause_s = policy.first_pause_s;
  for (;;) {
    const double down_for_s = clock.now_s() - down_since_s;
    if (down_for_s >= policy.limit_s) {
      return Result::link_failure(
          fmt::format("{} link down for {:.1f} s (more than the policy's {:g} s): {}", device,
                      down_for_s, policy.limit_s, r.message));
    }
    clock.sleep_until(std::min(clock.now_s() + pause_s, down_since_s + policy.limit_s));
    pause_s = std::min(2.0 * pause_s, policy.max_pause_s);
    r = attempt();
    if (r || !r.link_lost) return r;
  }
}

namespace {

/// Reads `device` until its state's link_lost is false (the generic part of read_riding_out).
template <typename Device, typename State, typename Why>
RiddenRead<State> read_until_linked(Device& device, core::Clock& clock, const RideOutPolicy& policy,
                                    Why why) {
  RiddenRead<State> out;
  out.result = ride_out(device.name(), clock, policy, [&] {
    out.state = device.read_state();
    return out.state.link_lost ? Result::link_failure(why(out.state)) : Result::success();
  });
  return out;
}

}  // namespace

RiddenRead<core::TableState> read_riding_out(Turntable& table, core::Clock& clock,
                                             const RideOutPolicy& policy) {
  return read_until_linked<Turntable, core::TableState>(
      table, clock, policy, [](const core::TableState& s) { return s.outer.fault_text; });
}

RiddenRead<core::ChamberState> read_riding_out(Chamber& chamber, core::Clock& clock,
                                               const RideOutPolicy& policy) {
  return read_until_linked<Chamber, core::ChamberState>(
      chamber, clock, policy, [](const core::ChamberState& s) { return s.fault_text; });
}

}  // namespace calstand::drivers
