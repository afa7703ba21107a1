// The Epson M-G3xx/G5xx UART burst format as an ImuWireFormat (docs/protocols.md).
#include <memory>
#include <string>

#include "drivers/epson_wire.hpp"

namespace calstand::drivers {
namespace epson {

namespace {

// Not a process-wide registry by `where`: two stations in one process (a fleet) may both have
// an "imus[0].connection.epson" with different models.
struct EpsonPendingSlot {
  std::string where;
  std::weak_ptr<IdentifiedModel> model;
};
thread_local EpsonPendingSlot epson_pending_slot;

}  // namespace

std::shared_ptr<IdentifiedModel> model_slot_for_decoder(const std::string& where) {
  auto slot = std::make_shared<IdentifiedModel>();
  epson_pending_slot = {where, slot};
  return slot;
}

std::shared_ptr<IdentifiedModel> model_slot_for_configurator(const std::string& where) {
  if (epson_pending_slot.where == where) {
    if (auto slot = epson_pending_slot.model.lock()) {
      epson_pending_slot = {};
      return slot;
    }
  }
  return std::make_shared<IdentifiedModel>();
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
                                     model_slot_for_decoder(settings.where));
  }
  std::unique_ptr<ImuConfigurator> make_configurator(
      const WireFormatSettings& settings) const override {
    return std::make_unique<Configurator>(settings, model_slot_for_configurator(settings.where));
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
