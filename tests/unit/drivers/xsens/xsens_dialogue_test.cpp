// The configuration dialogue against the emulated unit over an in-memory link, and the round
// trip emulator -> decoder.
#include <gtest/gtest.h>

#include <cmath>
#include <deque>
#include <numbers>

#include "drivers/xsens_configurator.hpp"
#include "drivers/xsens_decoder.hpp"
#include "drivers/xsens_emulator.hpp"

namespace calstand::drivers::xsens {
namespace {

using namespace std::chrono_literals;
using Bytes = std::vector<std::uint8_t>;

core::ImuSample xsens_test_sample(std::uint32_t k, double rate_hz) {
  core::ImuSample s;
  s.sequence = k;
  s.device_time_s = 3.0 + k / rate_hz;
  const double t = k * 0.01;
  s.gyro_dps = {10.0 * std::sin(t), -5.0 + std::cos(t), 0.25 * k};
  s.accel_mps2 = {0.1 * std::cos(t), -0.2, 9.80665 + 0.01 * std::sin(t)};
  s.temperature_c = 20.0 + 0.001 * k;
  return s;
}

/// The host's end of a link to an emulated unit that keeps measuring (a sample every read while
/// it measures), so replies come among streamed packets; reads hand out 3 bytes at most.
class EmulatorLink final : public ByteTransport {
 public:
  EmulatorLink(XsensEmulator& unit, double rate_hz) : unit_(unit), rate_hz_(rate_hz) {}
  IoResult read(std::span<std::uint8_t> buffer, std::chrono::milliseconds) override {
    for (int i = 0; i < 2; ++i) push(unit_.on_sample(xsens_test_sample(k_++, rate_hz_)));
    std::size_t n = 0;
    while (n < buffer.size() && n < 3 && !pending_.empty()) {
      buffer[n++] = pending_.front();
      pending_.pop_front();
    }
    return {n, {}};
  }
  IoResult write(std::span<const std::uint8_t> bytes, std::chrono::milliseconds) override {
    ++writes;
    if (!mute) push(unit_.on_host_bytes(bytes));
    return {bytes.size(), {}};
  }
  bool mute = false;
  int writes = 0;

 private:
  void push(const Bytes& b) { pending_.insert(pending_.end(), b.begin(), b.end()); }
  XsensEmulator& unit_;
  double rate_hz_;
  std::uint32_t k_ = 0;
  std::deque<std::uint8_t> pending_;
};

EmulatedUnit mti630() { return {"MTi-630", "0123ABCD", "1.12.0", 2000.0}; }

WireFormatSettings xsens_test_settings(double rate,
                                       nlohmann::json options = nlohmann::json::object()) {
  WireFormatSettings s;
  s.sample_rate_hz = rate;
  s.options = std::move(options);
  s.where = "imus[0].connection.xsens";
  return s;
}

TEST(XsensDialogue, ConfiguresAStreamingUnitAndReadsItsIdentity) {
  XsensEmulator unit(mti630());
  EmulatorLink link(unit, 2000.0);
  XsensConfigurator configurator(xsens_test_settings(400, {{"float_format", "fp1220"}}), 50ms, 3);
  const UnitIdentity id = configurator.configure(link);
  EXPECT_EQ(id.model, "MTi-630");
  EXPECT_EQ(id.serial, "0123ABCD");
  EXPECT_EQ(id.firmware, "1.12.0");
  EXPECT_TRUE(unit.measuring());
  const auto& config = unit.output_configuration();
  ASSERT_EQ(config.size(), 5u);
  EXPECT_EQ(config[2], (OutputItem{0x4021, 400}));
  EXPECT_EQ(config[3], (OutputItem{0x8021, 400}));
  EXPECT_EQ(config[4], (OutputItem{0x0811, 400}));
  EXPECT_EQ(link.writes, 6);  // one of each request: none needed a retry
}

TEST(XsensDialogue, AReplyThatNeverComesNamesTheRequest) {
  XsensEmulator unit(mti630());
  EmulatorLink link(unit, 2000.0);
  link.mute = true;
  XsensConfigurator configurator(xsens_test_settings(100), 20ms, 3);
  try {
    configurator.configure(link);
    FAIL() << "no reply expected";
  } catch (const DeviceConfigError& e) {
    EXPECT_STREQ(e.what(), "no reply to GoToConfig within 20 ms (3 attempts)");
  }
  EXPECT_EQ(link.writes, 3);
}

TEST(XsensDialogue, ARateTheUnitCannotMakeFailsWithTheDevicesError) {
  XsensEmulator unit(mti630());
  EmulatorLink link(unit, 2000.0);
  XsensConfigurator configurator(xsens_test_settings(300), 50ms, 3);  // 2000/300: no
  try {
    configurator.configure(link);
    FAIL() << "refusal expected";
  } catch (const DeviceConfigError& e) {
    EXPECT_STREQ(e.what(),
                 "SetOutputConfiguration refused by the device: Error 0x21: invalid parameter "
                 "(not valid or out of range)");
  }
  EXPECT_FALSE(unit.measuring());  // left in config state, as the device is
}

TEST(XsensDialogue, ARateTheFrequencyFieldCannotCarryIsRefusedBeforeAsking) {
  XsensEmulator unit(mti630());
  EmulatorLink link(unit, 2000.0);
  XsensConfigurator configurator(xsens_test_settings(100.5), 20ms, 1);
  EXPECT_THROW(configurator.configure(link), DeviceConfigError);
  EXPECT_EQ(link.writes, 0);
}

TEST(XsensEmulatorTest, RefusesConfigurationWhileMeasuringAndUnknownMessages) {
  XsensEmulator unit(mti630());
  const Bytes set =
      encode_message(mid::kSetOutputConfiguration, encode_output_configuration({{0x8020, 100}}));
  auto reply = messages_in(unit.on_host_bytes(set));
  ASSERT_EQ(reply.size(), 1u);
  EXPECT_EQ(reply[0].mid, mid::kError);
  EXPECT_EQ(reply[0].data, Bytes{0x04});
  reply = messages_in(unit.on_host_bytes(encode_message(0x77)));
  ASSERT_EQ(reply.size(), 1u);
  EXPECT_EQ(reply[0].mid, mid::kError);
}

TEST(XsensEmulatorTest, SaysWakeUpAtPowerOnAndStopsStreamingInConfig) {
  XsensEmulator unit({"MTi-1", "00000001", "1.0.0", 100.0});
  auto first = messages_in(unit.on_sample(xsens_test_sample(0, 100)));
  ASSERT_EQ(first.size(), 2u);
  EXPECT_EQ(first[0].mid, mid::kWakeUp);
  EXPECT_EQ(first[1].mid, mid::kMtData2);
  const auto ack = messages_in(unit.on_host_bytes(encode_message(mid::kGoToConfig)));
  ASSERT_EQ(ack.size(), 1u);
  EXPECT_EQ(ack[0].mid, mid::kGoToConfigAck);
  EXPECT_TRUE(unit.on_sample(xsens_test_sample(1, 100)).empty());
}

TEST(XsensEmulatorTest, SaysNoWakeUpOnceTheHostHasSpoken) {
  XsensEmulator unit({"MTi-1", "00000001", "1.0.0", 100.0});
  unit.on_host_bytes(encode_message(mid::kGoToMeasurement));
  const auto first = messages_in(unit.on_sample(xsens_test_sample(0, 100)));
  ASSERT_EQ(first.size(), 1u);
  EXPECT_EQ(first[0].mid, mid::kMtData2);
}

// Configures an emulated unit directly (as the configurator would) and decodes its output.
std::vector<core::ImuSample> round_trip(const WireFormatSettings& settings, int samples,
                                        XsensDecoder& decoder) {
  XsensEmulator unit(mti630());
  unit.on_host_bytes(encode_message(mid::kGoToConfig));
  const Options o = parse_options(settings);
  unit.on_host_bytes(encode_message(mid::kSetOutputConfiguration,
                                    encode_output_configuration(output_configuration(
                                        o, static_cast<std::uint16_t>(settings.sample_rate_hz)))));
  unit.on_host_bytes(encode_message(mid::kGoToMeasurement));
  std::vector<core::ImuSample> out;
  for (int k = 0; k < samples; ++k) {
    decoder.feed(unit.on_sample(xsens_test_sample(static_cast<std::uint32_t>(k), 2000.0)), out);
  }
  return out;
}

TEST(XsensDialogue, RoundTripReproducesTheSamplesToTheFormatsResolution) {
  // The format's resolution: float32 and float64 relative (half an ulp), fixed point absolute
  // (half a step), gyro in rad/s on the wire.
  struct Case {
    const char* format;
    double relative;
    double absolute;
  };
  constexpr double kDegPerRad = 180.0 / std::numbers::pi;
  for (const Case& c :
       {Case{"float32", std::ldexp(1.0, -24), 0.0}, Case{"fp1220", 0.0, std::ldexp(1.0, -21)},
        Case{"fp1632", 0.0, std::ldexp(1.0, -33)}, Case{"float64", 1e-15, 0.0}}) {
    auto tolerance = [&](double want, double scale) {
      return (c.relative * std::abs(want) + c.absolute * scale) * 1.0001 + 1e-12;
    };
    XsensDecoder decoder;
    const auto got =
        round_trip(xsens_test_settings(400, {{"float_format", c.format}}), 2000, decoder);
    ASSERT_EQ(got.size(), 400u) << c.format;  // 2000 Hz decimated by 5
    for (std::size_t i = 0; i < got.size(); ++i) {
      const auto want = xsens_test_sample(static_cast<std::uint32_t>(5 * i), 2000.0);
      ASSERT_EQ(got[i].sequence, i);
      EXPECT_NEAR(got[i].device_time_s, want.device_time_s, 0.5e-4);  // 10 kHz ticks
      for (int a = 0; a < 3; ++a) {
        EXPECT_NEAR(got[i].gyro_dps[a], want.gyro_dps[a], tolerance(want.gyro_dps[a], kDegPerRad))
            << c.format << " " << i;
        EXPECT_NEAR(got[i].accel_mps2[a], want.accel_mps2[a], tolerance(want.accel_mps2[a], 1.0))
            << c.format;
      }
      EXPECT_NEAR(got[i].temperature_c, want.temperature_c, 1e-5);
    }
    EXPECT_EQ(decoder.stats().sequence_gaps, 0u);
    EXPECT_EQ(decoder.stats().crc_errors, 0u);
  }
}

TEST(XsensDialogue, NedOutputIsTheSensorFrameTurnedAboutX) {
  XsensDecoder decoder;
  const auto got = round_trip(xsens_test_settings(2000, {{"coordinates", "ned"}}), 10, decoder);
  ASSERT_EQ(got.size(), 10u);
  for (std::size_t i = 0; i < got.size(); ++i) {
    const auto want = xsens_test_sample(static_cast<std::uint32_t>(i), 2000.0);
    EXPECT_NEAR(got[i].gyro_dps.x(), want.gyro_dps.x(), 1e-4);
    EXPECT_NEAR(got[i].gyro_dps.y(), -want.gyro_dps.y(), 1e-4);
    EXPECT_NEAR(got[i].accel_mps2.z(), -want.accel_mps2.z(), 1e-5);
  }
}

TEST(XsensDialogue, TemperatureAtALowerRateIsCarriedByEverySample) {
  XsensDecoder decoder;
  // 2000 Hz samples, temperature by default at 400 Hz: every 5th packet carries it.
  const auto got = round_trip(xsens_test_settings(2000), 20, decoder);
  ASSERT_EQ(got.size(), 20u);
  for (std::size_t i = 0; i < got.size(); ++i) {
    const auto measured = xsens_test_sample(static_cast<std::uint32_t>(i - i % 5), 2000.0);
    EXPECT_NEAR(got[i].temperature_c, measured.temperature_c, 1e-5) << i;
  }
  EXPECT_NE(got[1].temperature_c, xsens_test_sample(1, 2000.0).temperature_c);
}

}  // namespace
}  // namespace calstand::drivers::xsens
