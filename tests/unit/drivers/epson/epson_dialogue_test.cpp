#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <deque>
#include <functional>
#include <thread>

#include "core/error.hpp"
#include "drivers/epson_wire.hpp"

namespace calstand::drivers::epson {
namespace {

using namespace std::chrono_literals;
using Bytes = std::vector<std::uint8_t>;

/// The emulator behind an in-memory link. While it samples, every read lets 10 native samples
/// of the test signal pass, as a device streaming at 2 kHz would between two reads.
class EmulatorLink final : public ByteTransport {
 public:
  explicit EmulatorLink(Emulator& emulator) : emulator_(emulator) {}
  /// Sees every command written; returns false to drop it (a device that ignores it).
  std::function<bool(const Bytes&)> accept = [](const Bytes&) { return true; };

  IoResult read(std::span<std::uint8_t> buffer, std::chrono::milliseconds timeout) override {
    for (int i = 0; i < 10; ++i) {
      const auto b = emulator_.on_sample(next_sample());
      rx_.insert(rx_.end(), b.begin(), b.end());
    }
    if (rx_.empty()) {
      std::this_thread::sleep_for(std::min<std::chrono::milliseconds>(timeout, 2ms));
      return {};
    }
    const std::size_t n = std::min(buffer.size(), rx_.size());
    std::copy_n(rx_.begin(), n, buffer.begin());
    rx_.erase(rx_.begin(), rx_.begin() + static_cast<std::ptrdiff_t>(n));
    return {n, {}};
  }
  IoResult write(std::span<const std::uint8_t> bytes, std::chrono::milliseconds) override {
    for (std::size_t i = 0; i + 3 <= bytes.size(); i += 3) {
      const Bytes command(bytes.begin() + static_cast<std::ptrdiff_t>(i),
                          bytes.begin() + static_cast<std::ptrdiff_t>(i + 3));
      if (!accept(command)) continue;
      const auto reply = emulator_.on_host_bytes(command);
      rx_.insert(rx_.end(), reply.begin(), reply.end());
    }
    return {bytes.size(), {}};
  }

  std::uint64_t native_index = 0;
  static core::ImuSample signal(std::uint64_t n) {
    core::ImuSample s;
    const double k = static_cast<double>(n);
    s.sequence = static_cast<std::uint32_t>(n);
    s.device_time_s = k / 2000.0;
    s.gyro_dps = {10.0 * std::sin(k / 100.0), -3.0, 0.5 * std::cos(k / 50.0)};
    s.accel_mps2 = {0.1, -0.2 * std::sin(k / 70.0), 9.80665};
    s.temperature_c = 30.0 + 0.001 * k;
    return s;
  }

 private:
  core::ImuSample next_sample() { return signal(native_index++); }
  Emulator& emulator_;
  std::deque<std::uint8_t> rx_;
};

/// A device that never answers.
class SilentLink final : public ByteTransport {
 public:
  IoResult read(std::span<std::uint8_t>, std::chrono::milliseconds timeout) override {
    std::this_thread::sleep_for(timeout);
    return {};
  }
  IoResult write(std::span<const std::uint8_t> bytes, std::chrono::milliseconds) override {
    return {bytes.size(), {}};
  }
};

EmulatedUnit unit(const std::string& model = "G366PDG0") {
  return {model, "E0001234", "0x0105", 2000.0};
}

WireFormatSettings settings(double rate_hz, nlohmann::json options, const std::string& where) {
  WireFormatSettings s;
  s.sample_rate_hz = rate_hz;
  s.options = std::move(options);
  s.where = where;
  return s;
}

std::string configure_error(ByteTransport& link, const WireFormatSettings& s) {
  Configurator c(s);
  try {
    c.configure(link);
  } catch (const DeviceConfigError& e) {
    return e.what();
  }
  return "configured";
}

void start_streaming(Emulator& emulator) {
  for (const Bytes& command : {write_command(0x7E, 1), write_command(0x08, kUartAuto),
                               write_command(0x7E, 0), write_command(0x03, kModeCmdSampling)}) {
    emulator.on_host_bytes(command);
  }
}

TEST(EpsonDialogue, ConfiguresAStreamingDeviceAndReadsItsIdentity) {
  Emulator emulator(unit());
  start_streaming(emulator);
  EmulatorLink link(emulator);
  ASSERT_FALSE(emulator.on_sample(EmulatorLink::signal(0)).empty());  // it is streaming

  const auto s = settings(200, {{"width_bits", 32}}, "dialogue.streaming");
  Configurator c(s);
  const UnitIdentity id = c.configure(link);
  EXPECT_EQ(id.model, "G366PDG0");
  EXPECT_EQ(id.serial, "E0001234");
  EXPECT_EQ(id.firmware, "VERSION 0x0105");
  EXPECT_TRUE(emulator.sampling());

  // What it streams now decodes, with the model the dialogue read, to the simulated signal.
  Decoder decoder(Options::from_settings(s));
  decoder.identified(id);
  std::vector<core::ImuSample> got;
  std::array<std::uint8_t, 4096> chunk{};
  for (int i = 0; i < 50; ++i) {
    const auto r = link.read(chunk, 10ms);
    decoder.feed(std::span(chunk.data(), r.bytes), got);
  }
  ASSERT_GE(got.size(), 20u);
  EXPECT_EQ(decoder.counters().at("sequence_gaps"), 0u);
  EXPECT_EQ(decoder.counters().at("crc_errors"), 0u);
  for (const auto& g : got) {
    const auto n = static_cast<std::uint64_t>(std::llround(g.device_time_s * 2000.0));
    EXPECT_EQ(n % 10, 0u);  // 200 Hz out of 2000: every tenth native sample
    const auto want = EmulatorLink::signal(n);
    EXPECT_NEAR(g.gyro_dps.x(), want.gyro_dps.x(), 1.0 / 66 / 65536);
    EXPECT_NEAR(g.gyro_dps.z(), want.gyro_dps.z(), 1.0 / 66 / 65536);
    EXPECT_NEAR(g.accel_mps2.y(), want.accel_mps2.y(), 0.25e-3 * 9.80665 / 65536);
    EXPECT_NEAR(g.temperature_c, want.temperature_c, 0.00390625 / 65536);
  }
  for (std::size_t i = 1; i < got.size(); ++i) {
    EXPECT_EQ(got[i].sequence, got[i - 1].sequence + 1);
    EXPECT_NEAR(got[i].device_time_s - got[i - 1].device_time_s, 0.005, 1e-12);
  }
}

TEST(EpsonDialogue, SixteenBitOutputKeepsTheSixteenBitResolution) {
  Emulator emulator(unit("G370PDF1"));
  EmulatorLink link(emulator);
  const auto s = settings(2000, {{"width_bits", 16}, {"model", "G370PDF1"}}, "dialogue.16");
  Configurator c(s);
  EXPECT_EQ(c.configure(link).model, "G370PDF1");
  Decoder decoder(Options::from_settings(s));
  std::vector<core::ImuSample> got;
  std::array<std::uint8_t, 4096> chunk{};
  for (int i = 0; i < 5; ++i) {
    const auto r = link.read(chunk, 10ms);
    decoder.feed(std::span(chunk.data(), r.bytes), got);
  }
  ASSERT_GE(got.size(), 40u);
  for (const auto& g : got) {
    const auto want =
        EmulatorLink::signal(static_cast<std::uint64_t>(std::llround(g.device_time_s * 2000.0)));
    EXPECT_NEAR(g.gyro_dps.x(), want.gyro_dps.x(), 0.5 / 66 + 1e-12);
    EXPECT_NEAR(g.accel_mps2.y(), want.accel_mps2.y(), 0.5 * 0.4e-3 * 9.80665 + 1e-12);
  }
}

TEST(EpsonDialogue, AReplyThatNeverComesNamesTheRequest) {
  SilentLink link;
  const auto t0 = std::chrono::steady_clock::now();
  const std::string what = configure_error(link, settings(100, nlohmann::json::object(), "s"));
  EXPECT_NE(what.find("no reply to MODE_CTRL read within 500 ms (3 attempts)"), std::string::npos)
      << what;
  EXPECT_GE(std::chrono::steady_clock::now() - t0, 1500ms);
}

TEST(EpsonDialogue, ADifferentModelIsRefusedByName) {
  Emulator emulator(unit("G366PDG0"));
  EmulatorLink link(emulator);
  const std::string what =
      configure_error(link, settings(100, {{"model", "G370PDF1"}}, "imus[0].connection.epson"));
  EXPECT_NE(
      what.find("PROD_ID is G366PDG0, not the model G370PDF1 of imus[0].connection.epson.model"),
      std::string::npos)
      << what;
}

TEST(EpsonDialogue, ARegisterTheDeviceKeepsIsItsRefusal) {
  Emulator emulator(unit());
  EmulatorLink link(emulator);
  link.accept = [](const Bytes& command) { return command[0] != (0x05 | kWriteBit); };
  const std::string what = configure_error(link, settings(100, nlohmann::json::object(), "r"));
  EXPECT_NE(what.find("the device kept SMPL_CTRL at 0x0100 after 0x0A00 was written"),
            std::string::npos)
      << what;
}

TEST(EpsonDialogue, ADiagnosedErrorIsRefusedWithItsRegister) {
  Emulator emulator(unit());
  emulator.set_diag_stat(0x0002);
  EmulatorLink link(emulator);
  const std::string what = configure_error(link, settings(100, nlohmann::json::object(), "d"));
  EXPECT_NE(what.find("DIAG_STAT 0x0002"), std::string::npos) << what;
}

TEST(EpsonDialogue, ARateDoutRateCannotMakeIsRefusedWithTheRatesItCan) {
  Emulator emulator(unit());
  EmulatorLink link(emulator);
  const std::string what = configure_error(link, settings(300, nlohmann::json::object(), "q"));
  EXPECT_NE(what.find("300 Hz"), std::string::npos) << what;
  EXPECT_NE(what.find("2000, 1000, 500, 250, 125, 62.5, 31.25, 15.625, 400, 200, 100, 80, 50, "
                      "40, 25, 20 Hz"),
            std::string::npos)
      << what;
}

TEST(EpsonEmulator, IsSilentInConfigurationModeAndAnswersReads) {
  Emulator emulator(unit());
  EXPECT_TRUE(emulator.on_sample(EmulatorLink::signal(0)).empty());
  emulator.on_host_bytes(write_command(0x7E, 1));
  // Split across calls, as a UART delivers it.
  EXPECT_TRUE(emulator.on_host_bytes(Bytes{0x6A}).empty());
  const auto reply = emulator.on_host_bytes(Bytes{0x00, 0x0D});
  EXPECT_EQ(reply, (Bytes{0x6A, '3', 'G', 0x0D}));  // PROD_ID1 "G3": first character low
}

}  // namespace
}  // namespace calstand::drivers::epson

namespace calstand::drivers {
namespace {

TEST(EpsonWireFormat, ADecoderScalesWithTheModelItsOwnUnitReported) {
  const ImuWireFormat& format = epson_wire_format();
  WireFormatSettings s;
  s.sample_rate_hz = 2000;
  s.where = "imus[0].connection.epson";
  // Two stations of a fleet, each with an imus[0], made one after the other.
  auto decoder_a = format.make_decoder(s);
  auto configurator_a = format.make_configurator(s);
  auto decoder_b = format.make_decoder(s);
  auto configurator_b = format.make_configurator(s);
  epson::Emulator device_a({"G370PDS0", "A", "0x0100", 2000.0});
  epson::Emulator device_b({"G366PDG0", "B", "0x0100", 2000.0});
  epson::EmulatorLink link_a(device_a);
  epson::EmulatorLink link_b(device_b);
  const UnitIdentity id_a = configurator_a->configure(link_a);
  const UnitIdentity id_b = configurator_b->configure(link_b);
  EXPECT_EQ(id_a.model, "G370PDS0");
  EXPECT_EQ(id_b.model, "G366PDG0");
  // As SerialImu does after each dialogue.
  decoder_a->identified(id_a);
  decoder_b->identified(id_b);
  // The same raw gyro (150 x 65536) is 1 deg/s on a G370PDS0 and 150/66 deg/s on a G366PDG0.
  epson::BurstFields f;
  f.gyro[0] = 150 * 65536;
  const auto frame = epson::encode_burst(f, 32);
  std::vector<core::ImuSample> a, b;
  decoder_a->feed(frame, a);
  decoder_b->feed(frame, b);
  ASSERT_EQ(a.size(), 1u);
  ASSERT_EQ(b.size(), 1u);
  EXPECT_NEAR(a[0].gyro_dps.x(), 1.0, 1e-12);
  EXPECT_NEAR(b[0].gyro_dps.x(), 150.0 / 66, 1e-12);
}

TEST(EpsonWireFormat, IsTheFormatNamedEpson) {
  const ImuWireFormat& format = imu_wire_format("epson", "connection.format");
  EXPECT_EQ(format.name(), "epson");
  WireFormatSettings s;
  s.sample_rate_hz = 125;
  s.where = "imus[1].connection.epson";
  EXPECT_EQ(format.sequence_modulus(s), std::uint64_t{1} << 32);
  EXPECT_NE(format.make_decoder(s), nullptr);
  EXPECT_NE(format.make_configurator(s), nullptr);
  EXPECT_NE(format.make_emulator({"G330PDG0", "1", "0x0100", 2000.0}), nullptr);
  s.sample_rate_hz = 300;
  try {
    format.make_decoder(s);
    ADD_FAILURE() << "300 Hz accepted";
  } catch (const core::InputError& e) {
    EXPECT_EQ(e.where(), "imus[1].connection.epson.sample_rate_hz");
  }
}

}  // namespace
}  // namespace calstand::drivers
