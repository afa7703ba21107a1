// Every wire format as a whole, the same way: its configuration dialogue against its device
// emulator (the identity the unit reports arrives), then a stream of samples through the
// emulator's frames and the decoder (what comes out is what went in, to the format's
// resolution; sequence and device time advance as the device's counters do). Each format's
// own suite tests it against an independent Python peer; this one holds them to one contract.
#include <gtest/gtest.h>

#include <cmath>

#include "drivers/emulated_device_link.hpp"
#include "drivers/imu_wire_format.hpp"

namespace calstand::drivers {
namespace {

struct FormatCase {
  const char* name;
  double rate_hz;  ///< a rate the device makes
};

std::ostream& operator<<(std::ostream& os, const FormatCase& c) { return os << c.name; }

/// A sample of a unit turning and tilting: rates up to 250 deg/s, 2 g, a slow warm-up.
core::ImuSample moving_sample(std::uint32_t k, double rate_hz) {
  const double t = k / rate_hz;
  core::ImuSample s;
  s.sequence = k;
  s.device_time_s = 12.5 + t;
  s.gyro_dps = {250.0 * std::sin(0.7 * t), -120.0 * std::cos(1.3 * t), 40.0 * std::sin(2.1 * t)};
  s.accel_mps2 = {19.6 * std::sin(0.2 * t), -3.0, 9.80665 * std::cos(0.1 * t)};
  s.temperature_c = 25.0 + 10.0 * std::sin(1e-3 * t);
  return s;
}

class WireFormatRoundTrip : public ::testing::TestWithParam<FormatCase> {};

TEST_P(WireFormatRoundTrip, DialogueThenStreamGiveTheUnitAndItsSamples) {
  const FormatCase c = GetParam();
  const ImuWireFormat& format = imu_wire_format(c.name, "format");
  WireFormatSettings settings;
  settings.sample_rate_hz = c.rate_hz;
  settings.where = std::string("imus[0].connection.") + c.name;
  // The STIM300's dialogue times the unit's stream on the wall clock; this link has none.
  if (std::string(c.name) == "stim300") settings.options = {{"rate_check", false}};
  // Eight digits: a serial every format carries (a u32 in decimal or hex, 8 ASCII characters).
  const EmulatedUnit unit{"unit-model", "20004711", "fw-2.5", c.rate_hz};
  EmulatedDeviceLink link(format.make_emulator(unit));

  // A unit that was streaming when the host came and streams on through the dialogue: the
  // dialogue must find its replies among the frames anyway.
  std::uint32_t k = 0;
  for (; k < 3; ++k) link.sample(moving_sample(k, c.rate_hz));
  link.free_run([&] { return moving_sample(k++, c.rate_hz); });
  auto decoder = format.make_decoder(settings);
  auto configurator = format.make_configurator(settings);
  if (configurator) {
    const UnitIdentity id = configurator->configure(link);
    EXPECT_NE(id.serial.find("4711"), std::string::npos) << id.serial;
    EXPECT_FALSE(id.model.empty());
    decoder->identified(id);  // as SerialImu does after each dialogue
  }

  link.free_run({});
  decoder->restart();  // as the reader does after flushing what the dialogue left
  std::vector<std::uint8_t> leftover(link.pending());
  link.read(leftover, std::chrono::milliseconds(0));

  constexpr std::uint32_t kSamples = 2000;
  std::vector<core::ImuSample> sent, got;
  std::array<std::uint8_t, 97> chunk{};  // an odd read size: frames straddle reads
  for (const std::uint32_t end = k + kSamples; k < end; ++k) {
    sent.push_back(moving_sample(k, c.rate_hz));
    link.sample(sent.back());
    while (link.pending() > 0) {
      const auto r = link.read(chunk, std::chrono::milliseconds(0));
      decoder->feed(std::span(chunk.data(), r.bytes), got);
    }
  }
  const auto counters = decoder->counters();
  ASSERT_EQ(got.size(), sent.size()) << c.name;
  EXPECT_EQ(counters.at("garbage_bytes"), 0u);
  EXPECT_EQ(counters.at("sequence_gaps"), 0u);
  const std::uint64_t modulus = format.sequence_modulus(settings);
  for (std::size_t i = 0; i < got.size(); ++i) {
    SCOPED_TRACE(std::string(c.name) + " sample " + std::to_string(i));
    for (int a = 0; a < 3; ++a) {
      EXPECT_NEAR(got[i].gyro_dps[a], sent[i].gyro_dps[a], 1e-3);
      EXPECT_NEAR(got[i].accel_mps2[a], sent[i].accel_mps2[a], 1e-4);
    }
    EXPECT_NEAR(got[i].temperature_c, sent[i].temperature_c, 0.02);
    if (i > 0) {
      EXPECT_NEAR(got[i].device_time_s - got[i - 1].device_time_s, 1.0 / c.rate_hz, 2e-4);
      EXPECT_EQ(got[i].sequence, (std::uint64_t{got[i - 1].sequence} + 1) % modulus);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Formats, WireFormatRoundTrip,
                         ::testing::Values(FormatCase{"calstand", 200.0},
                                           FormatCase{"xsens", 200.0},
                                           FormatCase{"vectornav", 200.0},
                                           FormatCase{"epson", 200.0},
                                           FormatCase{"stim300", 250.0}),
                         [](const auto& test_info) { return std::string(test_info.param.name); });

}  // namespace
}  // namespace calstand::drivers
