// The Epson M-G3xx/G5xx UART burst format as an ImuWireFormat (docs/protocols.md).
#include <memory>
#include <string>

#include "drivers/epson_wire.hpp"

namespace calstand::drivers {
namespace epson {

namespace {

class EpsonWireFormat final : public ImuWireFormat {
 public:
  std::string name() const override { return "epson"; }
  std::uint64_t sequence_modulus(const WireFormatSettings& /*settings*/) const override {
    return std::uint64_t{1} << 32;  // COUNT is unwrapped
  }
  std::unique_ptr<FrameDecoder> make_decoder(const WireFormatSettings& settings) const override {
    return std::make_unique<Decoder>(Options::from_settings(settings));
  }
  std::unique_ptr<ImuConfigurator> make_configurator(
      const WireFormatSettings& settings) const override {
    return std::make_unique<Configurator>(settings);
  }
  std::unique_ptr<ImuDeviceEmulator> make_emulator(const EmulatedUnit& unit) const override {
    return std::make_unique<Emulator>(unit);
  }
};

}  // namespace
}  // namespace epson

const ImuWireFormat& epson_wire_format() {
  static const epson::EpsonWireFormat format;
  return format;
}

}  // namespace calstand::drivers
