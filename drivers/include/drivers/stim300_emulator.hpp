#pragma once

// The STIM300's side of the line, for `calstand sim-station` and tests.

#include <cstdint>
#include <string>
#include <vector>

#include "drivers/imu_wire_format.hpp"
#include "drivers/stim300_protocol.hpp"

namespace calstand::drivers::stim300 {

/// How the emulated unit is set up (what its service mode would have stored).
struct Stim300EmulatorSettings {
  std::uint8_t datagram_id = kRateAccInclTemp;
  /// Output rate [Hz]; 0: the highest STIM300 rate that divides the native rate.
  double sample_rate_hz = 0.0;
  bool termination = true;
  int accel_range_g = 10;
  GyroOutput gyro_output = GyroOutput::kAngularRate;
  AccelOutput accel_output = AccelOutput::kAcceleration;
  std::uint16_t latency_us = 500;  ///< [us] reported in each datagram
};

/// Streams normal-mode datagrams from power-on (after its part number, serial number and
/// configuration datagrams, as a unit leaving init mode); answers N, I, C with their datagrams
/// and R with a reset (counter from 0, the start-up datagrams again). The part number datagram
/// carries the hex digits of EmulatedUnit::model, the serial number datagram those of
/// EmulatedUnit::serial; the configuration bytes are zero (calstand does not read them). Values are
/// quantised to the datagram's counts; the counter is sample.sequence / decimation mod 256.
class Stim300Emulator final : public ImuDeviceEmulator {
 public:
  Stim300Emulator(EmulatedUnit unit, Stim300EmulatorSettings settings);

  std::vector<std::uint8_t> on_host_bytes(std::span<const std::uint8_t> bytes) override;
  std::vector<std::uint8_t> on_sample(const core::ImuSample& sample) override;

  double sample_rate_hz() const { return rate_hz_; }

 private:
  std::vector<std::uint8_t> startup_datagrams() const;

  EmulatedUnit unit_;
  Stim300EmulatorSettings settings_;
  double rate_hz_ = 0.0;
  std::uint64_t decimation_ = 1;
  std::uint64_t samples_ = 0;       // native samples since power-on or reset
  std::uint64_t counter_base_ = 0;  // sequence / decimation at the last reset
  bool reset_pending_ = false;      // R received: the next sample restarts the counter at 0
  bool powered_ = false;            // the start-up datagrams were sent
  std::string line_;                // command characters until CR
};

}  // namespace calstand::drivers::stim300
