// The VectorNav VN-100 binary output with its ASCII register dialogue as an ImuWireFormat
// (docs/protocols.md, "VectorNav VN-100 class").
#include <memory>

#include "drivers/imu_wire_format.hpp"
#include "drivers/vectornav_decoder.hpp"
#include "drivers/vectornav_device.hpp"
#include "drivers/vectornav_protocol.hpp"

namespace calstand::drivers {
namespace {

class VectornavWireFormat final : public ImuWireFormat {
 public:
  std::string name() const override { return "vectornav"; }
  std::uint64_t sequence_modulus(const WireFormatSettings& /*settings*/) const override {
    return std::uint64_t{1} << 32;  // derived from TimeStartup and unwrapped to 32 bits
  }
  std::unique_ptr<FrameDecoder> make_decoder(const WireFormatSettings& settings) const override {
    const auto options = vectornav::parse_options(settings);
    return std::make_unique<vectornav::VectornavDecoder>(settings.sample_rate_hz,
                                                         options.compensated);
  }
  std::unique_ptr<ImuConfigurator> make_configurator(
      const WireFormatSettings& settings) const override {
    return std::make_unique<vectornav::VectornavConfigurator>(vectornav::parse_options(settings),
                                                              settings.sample_rate_hz);
  }
  std::unique_ptr<ImuDeviceEmulator> make_emulator(const EmulatedUnit& unit) const override {
    return std::make_unique<vectornav::VectornavEmulator>(unit);
  }
};

}  // namespace

const ImuWireFormat& vectornav_wire_format() {
  static const VectornavWireFormat format;
  return format;
}

}  // namespace calstand::drivers
