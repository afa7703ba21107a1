#pragma once

#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/imu_sample.hpp"
#include "drivers/imu.hpp"
#include "drivers/imu_frame.hpp"
#include "drivers/serial_port.hpp"

namespace calstand::drivers {

/// What the station asks of a serial IMU, whatever its wire format (docs/protocols.md).
struct WireFormatSettings {
  double sample_rate_hz = 0.0;  ///< the output rate the station wants [Hz]
  /// The format's own options, `connection.<format>` of the station file (already checked by
  /// the schema's `<format>_options`); an empty object when none are given.
  nlohmann::json options = nlohmann::json::object();
  /// Where the options sit in the station file ("imus[0].connection.xsens"), for errors.
  std::string where;
  /// Station seconds per wall second (`calstand sim-station --time-scale K` runs the units K
  /// times faster): a dialogue that times the unit's stream on the wall clock divides by it.
  double time_scale = 1.0;
};

/// A device that refused its configuration or did not answer it. what() says which request
/// and why: the device's own words (an Xsens Error message, a VectorNav `$VNERR`), or "no reply
/// to ReqDID within 500 ms (3 attempts)".
class DeviceConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The host's half of a device's configuration dialogue: run by SerialImu::configure() on an
/// open link, before the reader starts.
class ImuConfigurator {
 public:
  virtual ~ImuConfigurator() = default;
  /// Brings the device from whatever state it is in (streaming, or configuring, or just
  /// powered) to streaming the configured output at the configured rate, and returns the
  /// identity it reports over the wire (model, serial, firmware). Throws DeviceConfigError.
  virtual UnitIdentity configure(ByteTransport& link) = 0;
};

/// Who a simulated device says it is, and how fast it samples (`calstand sim-station`).
struct EmulatedUnit {
  std::string model;      ///< as the device reports it (product code, model register)
  std::string serial;     ///< as the device reports it
  std::string firmware;   ///< as the device reports it
  double native_rate_hz;  ///< the rate on_sample() is called at [Hz]
};

/// The device's half of a wire format: what `calstand sim-station --imu-format F` puts on the
/// line for a simulated IMU, and what tests use as a second peer. It answers the host's
/// configuration and identity messages as the real device does and encodes samples while it
/// measures. Not thread safe.
class ImuDeviceEmulator {
 public:
  virtual ~ImuDeviceEmulator() = default;
  /// Bytes from the host, any split; returns what the device answers (possibly nothing).
  virtual std::vector<std::uint8_t> on_host_bytes(std::span<const std::uint8_t> bytes) = 0;
  /// One sample of the simulated sensor (called at EmulatedUnit::native_rate_hz): the bytes
  /// the device sends for it, none while it is in configuration or between the outputs of a
  /// decimated rate. Device time, counters and quantisation are the format's.
  virtual std::vector<std::uint8_t> on_sample(const core::ImuSample& sample) = 0;
};

/// One serial wire format: its decoder, its host dialogue and its device emulator.
class ImuWireFormat {
 public:
  virtual ~ImuWireFormat() = default;
  /// The name a station file gives as `connection.format`.
  virtual std::string name() const = 0;
  /// What the decoded samples' `sequence` wraps at (the device's counter, or 2^32 where the
  /// decoder unwraps it).
  virtual std::uint64_t sequence_modulus(const WireFormatSettings& settings) const = 0;
  /// A decoder for a stream configured with `settings`. Throws core::InputError naming
  /// settings.where for options it cannot honour.
  virtual std::unique_ptr<FrameDecoder> make_decoder(const WireFormatSettings& settings) const = 0;
  /// The host dialogue; null when the device has nothing to configure (calstand frames).
  virtual std::unique_ptr<ImuConfigurator> make_configurator(
      const WireFormatSettings& settings) const = 0;
  /// The device's side, for sim-station and tests.
  virtual std::unique_ptr<ImuDeviceEmulator> make_emulator(const EmulatedUnit& unit) const = 0;
};

/// The built-in formats, one per file (src/imu/calstand_wire_format.cpp, src/<format>/).
const ImuWireFormat& calstand_wire_format();
const ImuWireFormat& xsens_wire_format();
const ImuWireFormat& vectornav_wire_format();
const ImuWireFormat& epson_wire_format();
const ImuWireFormat& stim300_wire_format();

/// The format named `name`; throws core::InputError naming `where` and the known formats.
const ImuWireFormat& imu_wire_format(const std::string& name, const std::string& where);
/// "calstand", "xsens", "vectornav", "epson", "stim300".
std::vector<std::string> imu_wire_format_names();

}  // namespace calstand::drivers
