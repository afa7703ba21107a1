// PLACEHOLDER until the xsens format lands (issue 29): refuses to be used.
#include <stdexcept>

#include "drivers/imu_wire_format.hpp"

namespace calstand::drivers {
namespace {

class Missing_xsens final : public ImuWireFormat {
 public:
  std::string name() const override { return "xsens"; }
  std::uint64_t sequence_modulus(const WireFormatSettings&) const override { return 0; }
  std::unique_ptr<FrameDecoder> make_decoder(const WireFormatSettings&) const override {
    throw std::logic_error("xsens: not built yet");
  }
  std::unique_ptr<ImuConfigurator> make_configurator(const WireFormatSettings&) const override {
    throw std::logic_error("xsens: not built yet");
  }
  std::unique_ptr<ImuDeviceEmulator> make_emulator(const EmulatedUnit&) const override {
    throw std::logic_error("xsens: not built yet");
  }
};

}  // namespace

const ImuWireFormat& xsens_wire_format() {
  static const Missing_xsens format;
  return format;
}

}  // namespace calstand::drivers
