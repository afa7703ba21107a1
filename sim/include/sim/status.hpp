#pragma once

#include <string>

namespace calstand::sim {

/// Outcome of a command to a simulated device: refused commands say why, as a real controller's
/// error reply would.
struct Status {
  bool ok = true;
  std::string message;  ///< why the command was refused; empty when ok

  static Status success() { return {}; }
  static Status refused(std::string why) { return {false, std::move(why)}; }
  explicit operator bool() const { return ok; }
};

}  // namespace calstand::sim
