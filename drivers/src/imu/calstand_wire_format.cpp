// The calstand frame (docs/protocols.md, "IMU serial frame") as an ImuWireFormat: a device
// that streams from power-on and has nothing to configure or identify.
#include <memory>

#include "drivers/imu_wire_format.hpp"

namespace calstand::drivers {
namespace {

class CalstandEmulator final : public ImuDeviceEmulator {
 public:
  std::vector<std::uint8_t> on_host_bytes(std::span<const std::uint8_t> /*bytes*/) override {
    return {};  // the frame has no commands: what the host says is ignored, as by the device
  }
  std::vector<std::uint8_t> on_sample(const core::ImuSample& sample) override {
    return encode_imu_frame(sample);
  }
};

class CalstandWireFormat final : public ImuWireFormat {
 public:
  std::string name() const override { return "calstand"; }
  /// `sequence_modulus` in the options (the connection's, checked by the schema), else 2^32.
  std::uint64_t sequence_modulus(const WireFormatSettings& settings) const override {
    return settings.options.value("sequence_modulus", std::uint64_t{1} << 32);
  }
  std::unique_ptr<FrameDecoder> make_decoder(const WireFormatSettings& settings) const override {
    return std::make_unique<CalstandFrameDecoder>(sequence_modulus(settings));
  }
  std::unique_ptr<ImuConfigurator> make_configurator(
      const WireFormatSettings& /*settings*/) const override {
    return nullptr;
  }
  std::unique_ptr<ImuDeviceEmulator> make_emulator(const EmulatedUnit& /*unit*/) const override {
    return std::make_unique<CalstandEmulator>();
  }
};

}  // namespace

const ImuWireFormat& calstand_wire_format() {
  static const CalstandWireFormat format;
  return format;
}

}  // namespace calstand::drivers
