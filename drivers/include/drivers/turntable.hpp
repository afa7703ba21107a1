#pragma once

#include <string>
#include <vector>

#include "core/table_state.hpp"
#include "drivers/device.hpp"

namespace calstand::drivers {

enum class TableAxis { kOuter, kInner };

/// What Turntable::close_interlocks() did.
struct InterlockClosure {
  Result result;                    ///< failure: why an interlock could not be closed
  std::vector<std::string> closed;  ///< e.g. "outer axis interlock (door open)"
};

/// A dual-axis rate table. Angles and rates follow error-model.md (right-handed about each
/// axis, deg and deg/s). Commands return at once; read_state() tells when motion has settled.
class Turntable : public Device {
 public:
  /// Both axes to these angles (any wrap; the shortest way round), then hold.
  virtual Result move_to(double outer_deg, double inner_deg) = 0;
  /// One axis turning at a signed rate; the other axis keeps its mode.
  virtual Result set_rate(TableAxis axis, double rate_dps) = 0;
  /// One axis oscillating about the angle it stands at: angle = start + amplitude_deg
  /// sin(2 pi frequency_hz t), t from the command; the other axis keeps its mode. Refused (the
  /// reason in the Result) when the peak rate 2 pi f A or the peak acceleration (2 pi f)^2 A is
  /// beyond the axis's limits. stop() ends it (the axis brakes to rest where it is).
  virtual Result start_sine(TableAxis axis, double amplitude_deg, double frequency_hz) = 0;
  /// Both axes to rest at their acceleration limits and hold: the safe state.
  virtual Result stop() = 0;
  virtual core::TableState read_state() = 0;
  /// Closes the axis interlocks that latched open: an operator's deliberate act, never a side
  /// effect of activate() (which refuses while one is latched). Needs the link (configured);
  /// refused while a cause is still present. A table without interlocks (the in-process
  /// simulator) has none to close.
  virtual InterlockClosure close_interlocks() { return {}; }
};

}  // namespace calstand::drivers
