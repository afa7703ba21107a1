#pragma once

#include <chrono>

#include "drivers/imu_wire_format.hpp"
#include "drivers/xsens_protocol.hpp"

namespace calstand::drivers::xsens {

/// The host's half of the MTi dialogue (MT0101P): GoToConfig (from measurement or config
/// state), ReqDID, ReqProductCode, ReqFWRev, SetOutputConfiguration (PacketCounter and
/// SampleTimeFine with every packet, Acceleration and RateOfTurn at the sample rate,
/// Temperature at its own rate, in the configured precision and coordinate system),
/// GoToMeasurement. Each request waits for its ack (the request's MID + 1) or an Error
/// message, which fails configure() with the device's error text.
class XsensConfigurator final : public ImuConfigurator {
 public:
  /// Throws core::InputError for options it cannot honour (parse_options()).
  explicit XsensConfigurator(const WireFormatSettings& settings,
                             std::chrono::milliseconds timeout = std::chrono::milliseconds(500),
                             int attempts = 3);
  UnitIdentity configure(ByteTransport& link) override;

 private:
  // The reply to a request (ack `reply_mid`); throws DeviceConfigError on an Error or no reply.
  Message exchange(ByteTransport& link, std::uint8_t mid, std::span<const std::uint8_t> data,
                   std::uint8_t reply_mid, const std::string& what);

  double sample_rate_hz_;
  Options options_;
  std::chrono::milliseconds timeout_;
  int attempts_;
};

}  // namespace calstand::drivers::xsens
