// Sensonor STIM300 as an ImuWireFormat (docs/protocols.md, "Sensonor STIM300").
#include <memory>

#include "drivers/imu_wire_format.hpp"
#include "drivers/stim300_configurator.hpp"
#include "drivers/stim300_decoder.hpp"
#include "drivers/stim300_emulator.hpp"

namespace calstand::drivers {
namespace {

class Stim300WireFormat final : public ImuWireFormat {
 public:
  std::string name() const override { return "stim300"; }
  /// The 8-bit counter is unwrapped to 32 bits by the decoder.
  std::uint64_t sequence_modulus(const WireFormatSettings& /*settings*/) const override {
    return std::uint64_t{1} << 32;
  }
  std::unique_ptr<FrameDecoder> make_decoder(const WireFormatSettings& settings) const override {
    return std::make_unique<stim300::Stim300Decoder>(stim300::parse_stim300_options(settings),
                                                     settings.sample_rate_hz);
  }
  std::unique_ptr<ImuConfigurator> make_configurator(
      const WireFormatSettings& settings) const override {
    return std::make_unique<stim300::Stim300Configurator>(settings,
                                                          stim300::parse_stim300_options(settings));
  }
  std::unique_ptr<ImuDeviceEmulator> make_emulator(const EmulatedUnit& unit) const override {
    return std::make_unique<stim300::Stim300Emulator>(unit, stim300::Stim300EmulatorSettings{});
  }
};

}  // namespace

const ImuWireFormat& stim300_wire_format() {
  static const Stim300WireFormat format;
  return format;
}

}  // namespace calstand::drivers
