// The Epson M-G3xx/G5xx UART burst format as an ImuWireFormat (docs/protocols.md).
#include <map>
#include <mutex>

#include "drivers/epson_wire.hpp"

namespace calstand::drivers {
namespace epson {

std::shared_ptr<IdentifiedModel> identified_model_for(const std::string& where) {
  static std::mutex mutex;
  static std::map<std::string, std::weak_ptr<IdentifiedModel>> slots;
  const std::lock_guard lock(mutex);
  auto& slot = slots[where];
  auto shared = slot.lock();
  if (!shared) {
    shared = std::make_shared<IdentifiedModel>();
    slot = shared;
  }
  return shared;
}

namespace {

class EpsonWireFormat final : public ImuWireFormat {
 public:
  std::string name() const override { return "epson"; }
  std::uint64_t sequence_modulus(const WireFormatSettings& /*settings*/) const override {
    return std::uint64_t{1} << 32;  // COUNT is unwrapped
  }
  std::unique_ptr<FrameDecoder> make_decoder(const WireFormatSettings& settings) const override {
    return std::make_unique<Decoder>(Options::from_settings(settings),
                                     identified_model_for(settings.where));
  }
  std::unique_ptr<ImuConfigurator> make_configurator(
      const WireFormatSettings& settings) const override {
    return std::make_unique<Configurator>(settings, identified_model_for(settings.where));
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
