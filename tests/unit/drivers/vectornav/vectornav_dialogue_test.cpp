// The configuration dialogue against the emulator over an in-memory link, a silent device,
// a refusing device, and the emulator -> decoder round trip.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <deque>
#include <functional>
#include <string>
#include <thread>

#include "drivers/imu_wire_format.hpp"
#include "drivers/vectornav_decoder.hpp"
#include "drivers/vectornav_device.hpp"

namespace calstand::drivers::vectornav {
namespace {

using namespace std::chrono_literals;

EmulatedUnit vn_unit() { return {"VN-100T-CR", "0100012345", "2.1.0.0", 800.0}; }

core::ImuSample vn_sim_sample(std::uint64_t n) {
  core::ImuSample s;
  s.sequence = static_cast<std::uint32_t>(n);
  s.device_time_s = 2.0 + static_cast<double>(n) / 800.0;
  s.gyro_dps = {30.0 * std::sin(static_cast<double>(n) / 50.0), -4.5,
                0.001 * static_cast<double>(n)};
  s.accel_mps2 = {0.02, 0.5 * std::cos(static_cast<double>(n) / 80.0), -9.80665};
  s.temperature_c = 24.0 + 0.001 * static_cast<double>(n);
  return s;
}

/// The host's side of a line to a device: what the host writes goes to `device`, whose
/// answers (and, while `streaming`, a sample per read) come back on read().
class VnDeviceLink final : public ByteTransport {
 public:
  explicit VnDeviceLink(ImuDeviceEmulator* device) : device_(device) {}
  IoResult read(std::span<std::uint8_t> buffer, std::chrono::milliseconds timeout) override {
    if (device_) {
      const auto bytes = device_->on_sample(vn_sim_sample(samples_++));
      pending_.insert(pending_.end(), bytes.begin(), bytes.end());
    }
    if (pending_.empty()) {
      std::this_thread::sleep_for(std::min(timeout, std::chrono::milliseconds(5)));
      return {};
    }
    const std::size_t n = std::min(buffer.size(), pending_.size());
    std::copy_n(pending_.begin(), n, buffer.begin());
    pending_.erase(pending_.begin(), pending_.begin() + static_cast<std::ptrdiff_t>(n));
    return {n, {}};
  }
  IoResult write(std::span<const std::uint8_t> bytes, std::chrono::milliseconds) override {
    written_.append(bytes.begin(), bytes.end());
    if (reply_) {
      const std::string r = reply_(std::string(bytes.begin(), bytes.end()));
      pending_.insert(pending_.end(), r.begin(), r.end());
    } else if (device_) {
      const auto r = device_->on_host_bytes(bytes);
      pending_.insert(pending_.end(), r.begin(), r.end());
    }
    return {bytes.size(), {}};
  }
  std::function<std::string(const std::string&)> reply_;  ///< a scripted device instead
  std::string written_;

 private:
  ImuDeviceEmulator* device_;
  std::deque<std::uint8_t> pending_;
  std::uint64_t samples_ = 0;
};

TEST(VectornavDialogue, ConfiguresTheEmulatorAndReadsItsIdentity) {
  VectornavEmulator device(vn_unit(), "4");
  VnDeviceLink link(&device);
  VectornavConfigurator configurator(Options{}, 100.0, 100ms);
  const UnitIdentity id = configurator.configure(link);
  EXPECT_EQ(id.model, "VN-100T-CR (hardware revision 4)");
  EXPECT_EQ(id.serial, "0100012345");
  EXPECT_EQ(id.firmware, "2.1.0.0");
  EXPECT_NE(link.written_.find("$VNWRG,06,0*"), std::string::npos);
  EXPECT_NE(link.written_.find(ascii_message("VNWRG,75,1,8,05,0001,001C")), std::string::npos);
  // The emulator now streams every 8th sample.
  std::vector<std::uint8_t> bytes;
  int messages = 0;
  for (std::uint64_t n = 0; n < 80; ++n) {
    const auto m = device.on_sample(vn_sim_sample(n));
    if (!m.empty()) ++messages;
    bytes.insert(bytes.end(), m.begin(), m.end());
  }
  EXPECT_EQ(messages, 10);
  // And answers a read of the register it was given.
  const std::string read = ascii_message("VNRRG,75");
  const auto r = device.on_host_bytes(
      std::span(reinterpret_cast<const std::uint8_t*>(read.data()), read.size()));
  EXPECT_EQ(std::string(r.begin(), r.end()), ascii_message("VNRRG,75,1,8,05,0001,001C"));
}

TEST(VectornavDialogue, ConfiguresADeviceThatIsAlreadyStreaming) {
  VectornavEmulator device(vn_unit());
  // Streaming at 800 Hz from an earlier session.
  const std::string start = ascii_message("VNWRG,75,1,1,05,0001,0610");
  device.on_host_bytes(
      std::span(reinterpret_cast<const std::uint8_t*>(start.data()), start.size()));
  ASSERT_FALSE(device.on_sample(vn_sim_sample(0)).empty());
  VnDeviceLink link(&device);
  const auto settings = WireFormatSettings{200.0, nlohmann::json::object(), "x"};
  const UnitIdentity id =
      VectornavConfigurator(parse_options(settings), 200.0, 100ms).configure(link);
  EXPECT_EQ(id.serial, "0100012345");
}

TEST(VectornavDialogue, EmulatorToDecoderReproducesTheSamplesToF32) {
  const auto& format = vectornav_wire_format();
  for (const bool compensated : {false, true}) {
    WireFormatSettings settings{400.0,
                                {{"outputs", compensated ? "compensated" : "uncompensated"}},
                                "imus[0].connection.vectornav"};
    auto device = format.make_emulator(vn_unit());
    VnDeviceLink link(nullptr);
    link.reply_ = [&](const std::string& in) {
      const auto r = device->on_host_bytes(
          std::span(reinterpret_cast<const std::uint8_t*>(in.data()), in.size()));
      return std::string(r.begin(), r.end());
    };
    format.make_configurator(settings)->configure(link);
    auto decoder = format.make_decoder(settings);
    std::vector<core::ImuSample> out;
    for (std::uint64_t n = 0; n < 400; ++n) decoder->feed(device->on_sample(vn_sim_sample(n)), out);
    ASSERT_EQ(out.size(), 200u);
    for (std::size_t k = 0; k < out.size(); ++k) {
      const auto want = vn_sim_sample(2 * k);
      EXPECT_NEAR(out[k].device_time_s, want.device_time_s, 1e-9);
      EXPECT_EQ(out[k].sequence, static_cast<std::uint32_t>(800 + k));  // round(t * 400 Hz)
      for (int i = 0; i < 3; ++i) {
        EXPECT_NEAR(out[k].gyro_dps[i], want.gyro_dps[i], 1e-6 * (1 + std::abs(want.gyro_dps[i])));
        EXPECT_NEAR(out[k].accel_mps2[i], want.accel_mps2[i],
                    1e-6 * (1 + std::abs(want.accel_mps2[i])));
      }
      EXPECT_NEAR(out[k].temperature_c, want.temperature_c, 1e-5);
    }
    EXPECT_EQ(decoder->counters().at("sequence_gaps"), 0u);
    EXPECT_EQ(format.sequence_modulus(settings), std::uint64_t{1} << 32);
  }
}

TEST(VectornavDialogue, AnEmulatorSampledAtAnotherNativeRateKeepsTheOutputRate) {
  EmulatedUnit unit = vn_unit();
  unit.native_rate_hz = 1000.0;
  VectornavEmulator device(unit);
  const std::string start = ascii_message("VNWRG,75,1,5,05,0001,001C");  // 800 / 5 = 160 Hz
  device.on_host_bytes(
      std::span(reinterpret_cast<const std::uint8_t*>(start.data()), start.size()));
  VectornavDecoder decoder(160.0, false);
  std::vector<core::ImuSample> out;
  for (std::uint64_t n = 0; n < 1000; ++n) {
    core::ImuSample s = vn_sim_sample(n);
    s.device_time_s = static_cast<double>(n) / 1000.0;
    decoder.feed(device.on_sample(s), out);
  }
  ASSERT_EQ(out.size(), 160u);
  // Each output is the first native sample at or after its 1/160 s slot.
  for (std::size_t k = 0; k < out.size(); ++k) {
    EXPECT_GE(out[k].device_time_s + 1e-12, static_cast<double>(k) / 160.0);
    EXPECT_LT(out[k].device_time_s, static_cast<double>(k) / 160.0 + 1.0 / 1000.0);
    EXPECT_EQ(out[k].sequence, k);
  }
  EXPECT_EQ(decoder.stats().sequence_gaps, 0u);
}

TEST(VectornavDialogue, ASilentDeviceTimesOutNamingTheRequest) {
  VnDeviceLink link(nullptr);
  VectornavConfigurator configurator(Options{}, 100.0, 30ms);
  try {
    configurator.configure(link);
    ADD_FAILURE();
  } catch (const DeviceConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("no reply to Async Data Output Type (register 6) off"), std::string::npos)
        << what;
    EXPECT_NE(what.find("3 attempts"), std::string::npos) << what;
  }
  // Three attempts of the same request.
  const std::string request = ascii_message("VNWRG,06,0");
  EXPECT_EQ(link.written_, request + request + request);
}

TEST(VectornavDialogue, ADeviceRefusalSurfacesInItsOwnWords) {
  VectornavEmulator device(vn_unit());
  VnDeviceLink link(nullptr);
  link.reply_ = [&](const std::string& in) -> std::string {
    if (in.find("VNWRG,75") != std::string::npos) return ascii_message("VNERR,07");
    const auto r = device.on_host_bytes(
        std::span(reinterpret_cast<const std::uint8_t*>(in.data()), in.size()));
    return std::string(r.begin(), r.end());
  };
  try {
    VectornavConfigurator(Options{}, 100.0, 100ms).configure(link);
    ADD_FAILURE();
  } catch (const DeviceConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("Binary Output Register 1"), std::string::npos) << what;
    EXPECT_NE(what.find("$VNERR,07: Invalid Parameter"), std::string::npos) << what;
  }
}

TEST(VectornavDialogue, ARateTheDivisorCannotMakeIsRefusedBeforeAnyByteIsSent) {
  VnDeviceLink link(nullptr);
  EXPECT_THROW(VectornavConfigurator(Options{}, 300.0, 30ms).configure(link), DeviceConfigError);
  EXPECT_TRUE(link.written_.empty());
}

TEST(VectornavEmulator, AnswersBadCommandsAsTheUnitDoes) {
  VectornavEmulator device(vn_unit());
  const auto ask = [&](const std::string& text) {
    const auto r = device.on_host_bytes(
        std::span(reinterpret_cast<const std::uint8_t*>(text.data()), text.size()));
    return std::string(r.begin(), r.end());
  };
  EXPECT_EQ(ask("$VNRRG,01*00\r\n"), ascii_message("VNERR,03"));
  EXPECT_EQ(ask("$VNRRG,01*XX\r\n"), ascii_message("VNRRG,01,VN-100T-CR"));
  EXPECT_EQ(ask(ascii_message("VNRRG,99")), ascii_message("VNERR,08"));
  EXPECT_EQ(ask(ascii_message("VNFOO,1")), ascii_message("VNERR,04"));
  EXPECT_EQ(ask(ascii_message("VNWRG,75,1,0,05,0001,001C")), ascii_message("VNERR,07"));
  EXPECT_EQ(ask(ascii_message("VNWRG,75,1,8,15,0001,000C,0014")), ascii_message("VNERR,07"));
  EXPECT_EQ(ask(ascii_message("VNWRG,75,1,8,05,0001")), ascii_message("VNERR,05"));
  // A command split across writes is answered once complete.
  EXPECT_EQ(ask("$VNRRG,0"), "");
  EXPECT_EQ(ask("3*XX\r\n"), ascii_message("VNRRG,03,0100012345"));
  // Nothing is streamed before the host asks for the binary output.
  EXPECT_TRUE(device.on_sample(vn_sim_sample(0)).empty());
}

}  // namespace
}  // namespace calstand::drivers::vectornav
