#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/imu_sample.hpp"
#include "drivers/device.hpp"

namespace calstand::drivers {

/// Who a unit says it is, where its protocol carries it (a frame field, a CAN id, a query).
struct UnitIdentity {
  std::string model;     ///< empty when the device does not say
  std::string serial;    ///< never empty
  std::string firmware;  ///< empty when the device does not say
};

/// An IMU streaming samples. The driver buffers what arrives; the engine drains it.
class Imu : public Device {
 public:
  /// Every sample received since the last call, oldest first (never blocks).
  virtual std::vector<core::ImuSample> poll() = 0;
  /// The device's nominal output rate [Hz].
  virtual double sample_rate_hz() const = 0;
  /// The sequence counter wraps to 0 at this value (gap detection needs it); up to 2^32.
  virtual std::uint64_t sequence_modulus() const = 0;
  /// The unit's identity as the device reports it, once configured; none when its protocol
  /// cannot say (the calstand serial frame and the CAN map carry none).
  virtual std::optional<UnitIdentity> identity() const { return std::nullopt; }
};

}  // namespace calstand::drivers
