// The Xsens MTi format (docs/protocols.md, "Xsens MTi"): Xbus messages with MTData2 packets,
// the configuration dialogue and an emulated unit.
#include <memory>

#include "drivers/imu_wire_format.hpp"
#include "drivers/xsens_configurator.hpp"
#include "drivers/xsens_decoder.hpp"
#include "drivers/xsens_emulator.hpp"

namespace calstand::drivers {
namespace {

class XsensWireFormat final : public ImuWireFormat {
 public:
  std::string name() const override { return "xsens"; }
  std::uint64_t sequence_modulus(const WireFormatSettings& /*settings*/) const override {
    return std::uint64_t{1} << 16;  // PacketCounter is a u16 (MT0101P, XDI 0x1020)
  }
  std::unique_ptr<FrameDecoder> make_decoder(const WireFormatSettings& settings) const override {
    // The decoder reads each XDI's own format bits; the options are checked all the same, so a
    // wrong one fails where the station file is read.
    xsens::parse_options(settings);
    return std::make_unique<xsens::XsensDecoder>();
  }
  std::unique_ptr<ImuConfigurator> make_configurator(
      const WireFormatSettings& settings) const override {
    return std::make_unique<xsens::XsensConfigurator>(settings);
  }
  std::unique_ptr<ImuDeviceEmulator> make_emulator(const EmulatedUnit& unit) const override {
    return std::make_unique<xsens::XsensEmulator>(unit);
  }
};

}  // namespace

const ImuWireFormat& xsens_wire_format() {
  static const XsensWireFormat format;
  return format;
}

}  // namespace calstand::drivers
