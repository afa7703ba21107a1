#pragma once

#include <chrono>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "drivers/imu_wire_format.hpp"
#include "drivers/vectornav_protocol.hpp"

namespace calstand::drivers::vectornav {

/// The host's dialogue with a VN-100 [UM001 §5.1 read/write register commands]:
///   $VNWRG,06,0        Async Data Output Type off (no ASCII async output on this port)
///   $VNRRG,01 .. 04    model number, hardware revision, serial number, firmware version
///   $VNWRG,75,...      Binary Output Register 1: AsyncMode = port, RateDivisor, groups
///                      Common (TimeStartup) and IMU (accel, gyro, temperature); the unit
///                      streams from this write on.
/// Each request is sent up to 3 times and its reply (the register echoed, or `$VNERR`) awaited
/// for `timeout`; a `$VNERR` reply is a DeviceConfigError in the device's words.
class VectornavConfigurator final : public ImuConfigurator {
 public:
  VectornavConfigurator(Options options, double sample_rate_hz,
                        std::chrono::milliseconds timeout = std::chrono::milliseconds(500));
  UnitIdentity configure(ByteTransport& link) override;

 private:
  // Sends `body` as a checksummed command; returns the reply's fields (after the register).
  std::vector<std::string> command(ByteTransport& link, const std::string& body,
                                   const std::string& what);

  Options options_;
  double sample_rate_hz_;
  std::chrono::milliseconds timeout_;
};

/// A VN-100 on the line for `calstand sim-station` and tests. Answers the registers the
/// configurator uses (1-4, 6, 75) and reports `$VNERR` for others, bad checksums or bad
/// parameters as the unit does; starts with its binary output off and emits nothing until
/// Binary Output Register 1 asks for output (whatever AsyncMode's port: it stands for the
/// port the host is on). The output rate is the VN-100's 800 Hz IMU rate over the RateDivisor:
/// every RateDivisor-th sample at a native rate of 800 Hz, by phase at any other native rate.
/// The ASCII async output (register 6) is accepted but never sent.
class VectornavEmulator final : public ImuDeviceEmulator {
 public:
  VectornavEmulator(EmulatedUnit unit, std::string hardware_revision = "1");
  std::vector<std::uint8_t> on_host_bytes(std::span<const std::uint8_t> bytes) override;
  std::vector<std::uint8_t> on_sample(const core::ImuSample& sample) override;

 private:
  std::string answer(const AsciiMessage& message);
  std::string binary_output_fields() const;

  EmulatedUnit unit_;
  std::string hardware_revision_;
  std::vector<std::uint8_t> input_;
  int ador_ = 0;
  int async_mode_ = 0;
  int divisor_ = 1;
  std::uint16_t common_ = 0;
  std::uint16_t imu_ = 0;
  std::uint64_t samples_ = 0;
};

}  // namespace calstand::drivers::vectornav
