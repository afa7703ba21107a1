#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "drivers/imu_wire_format.hpp"
#include "drivers/xsens_protocol.hpp"

namespace calstand::drivers::xsens {

/// The device's half of the MTi protocol, for `calstand sim-station --imu-format xsens` and
/// tests. At power-on (the first sample, unless the host spoke first) it sends WakeUp and measures
/// with its stored output configuration (float32, ENU, 100 Hz or the native rate); it answers
/// GoToConfig, GoToMeasurement, WakeUpAck, ReqDID, ReqProductCode, ReqFWRev and
/// SetOutputConfiguration (also the request form without data) as MT0101P describes, and Error 0x04
/// to any other message. It models a unit whose output rates divide its native rate
/// (EmulatedUnit::native_rate_hz; 2000 Hz for an MTi 600-series unit) with temperature up to
/// kMaxTemperatureRateHz: SetOutputConfiguration outside that is refused with Error 0x21.
/// Each item of a packet is encoded in its own XDI's precision and coordinate system.
class XsensEmulator final : public ImuDeviceEmulator {
 public:
  explicit XsensEmulator(const EmulatedUnit& unit);
  std::vector<std::uint8_t> on_host_bytes(std::span<const std::uint8_t> bytes) override;
  std::vector<std::uint8_t> on_sample(const core::ImuSample& sample) override;

  bool measuring() const { return measuring_; }
  const std::vector<OutputItem>& output_configuration() const { return config_; }

 private:
  std::vector<std::uint8_t> answer(const Message& m);
  // The native samples per output of `rate_hz` (0 when the rate cannot be made).
  std::uint32_t divider(std::uint16_t rate_hz) const;

  EmulatedUnit unit_;
  std::vector<std::uint8_t> pending_;  // host bytes not yet a whole message
  bool powered_ = false;               // WakeUp sent
  bool measuring_ = true;
  std::vector<OutputItem> config_;
};

}  // namespace calstand::drivers::xsens
