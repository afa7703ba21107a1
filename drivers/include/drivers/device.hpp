#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace calstand::drivers {

/// Outcome of a device call. The cyclic driver path returns this and never throws: a refused
/// command or a lost link says why, and the engine decides what follows.
struct Result {
  bool ok = true;
  std::string message;  ///< why it failed; empty when ok
  /// Failed because the device could not be reached (link down, no reply), not because it
  /// refused: a harmless command may be repeated once the link is back (ride_out.hpp).
  bool link_lost = false;

  static Result success() { return {}; }
  static Result failure(std::string why) { return {false, std::move(why)}; }
  static Result link_failure(std::string why) { return {false, std::move(why), true}; }
  /// This failure with `context` before its message ("outer axis: ..."), link_lost kept.
  Result in(const std::string& context) const {
    return ok ? *this : Result{false, context + ": " + message, link_lost};
  }
  explicit operator bool() const { return ok; }
};

/// Lifecycle of a device (as ros2_control's hardware components): constructed with no I/O,
/// configured (connection opened, identity checked), activated (accepting commands),
/// deactivated (safe, still connected). A failure moves it to kError.
enum class DeviceState { kUnconfigured, kInactive, kActive, kError };

std::string_view to_string(DeviceState state);

/// Something a device saw that belongs in the run's event log: a fault (CRC errors, a lost
/// link, an out-of-range reading) or information (link back). Drivers queue them; the engine
/// records them with the device's name.
struct DeviceEvent {
  double time_s = 0.0;  ///< station clock when it was seen [s]
  bool fault = true;    ///< fault (true) or information (false)
  std::string message;
};

/// What every device has: a name, a lifecycle and named fault counters for `status`.
class Device {
 public:
  virtual ~Device() = default;
  virtual const std::string& name() const = 0;
  virtual Result configure() = 0;
  virtual Result activate() = 0;
  virtual Result deactivate() = 0;
  virtual DeviceState state() const = 0;
  /// Named counters of faults seen since construction (e.g. "sequence_gaps", "timeouts").
  virtual std::map<std::string, std::uint64_t> fault_counters() const = 0;
  /// Events seen since the last call, oldest first (never blocks). Simulated devices have none.
  virtual std::vector<DeviceEvent> take_events() { return {}; }
};

}  // namespace calstand::drivers
