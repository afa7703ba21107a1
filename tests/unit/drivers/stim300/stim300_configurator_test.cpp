#include "drivers/stim300_configurator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <deque>
#include <thread>

#include "drivers/stim300_decoder.hpp"
#include "drivers/stim300_emulator.hpp"

namespace calstand::drivers::stim300 {
namespace {

const EmulatedUnit kUnit{"84167-2500-301", "N25581234", "", 2000.0};

core::ImuSample sample_k(std::uint32_t k) {
  core::ImuSample s;
  s.sequence = k;
  s.device_time_s = k / 2000.0;
  s.gyro_dps = {std::sin(k / 10.0), -0.25, 100.0};
  s.accel_mps2 = {0.1 * std::cos(k / 7.0), 0.0, 9.80665};
  s.temperature_c = 31.5;
  return s;
}

/// The emulated unit on an in-memory line, sampling at its native rate in real time (the unit
/// does not stop streaming for the dialogue) and answering what the host writes.
class EmulatorLink final : public ByteTransport {
 public:
  explicit EmulatorLink(Stim300Emulator& unit, bool answers = true)
      : unit_(unit), answers_(answers), start_(std::chrono::steady_clock::now()) {}
  IoResult read(std::span<std::uint8_t> buffer, std::chrono::milliseconds timeout) override {
    const double elapsed_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    for (const auto due = static_cast<std::uint32_t>(elapsed_s * kUnit.native_rate_hz);
         next_ < due;) {
      const auto b = unit_.on_sample(sample_k(next_++));
      pending_.insert(pending_.end(), b.begin(), b.end());
    }
    if (pending_.empty()) {
      std::this_thread::sleep_for(std::min(timeout, std::chrono::milliseconds(2)));
      return {};
    }
    std::size_t n = 0;
    while (n < buffer.size() && !pending_.empty()) {
      buffer[n++] = pending_.front();
      pending_.pop_front();
    }
    return {n, {}};
  }
  IoResult write(std::span<const std::uint8_t> bytes, std::chrono::milliseconds) override {
    ++writes;
    if (answers_) {
      const auto reply = unit_.on_host_bytes(bytes);
      pending_.insert(pending_.end(), reply.begin(), reply.end());
    }
    return {bytes.size(), {}};
  }
  int writes = 0;

 private:
  Stim300Emulator& unit_;
  bool answers_;
  std::chrono::steady_clock::time_point start_;
  std::deque<std::uint8_t> pending_;
  std::uint32_t next_ = 0;
};

WireFormatSettings settings(double rate_hz, nlohmann::json options = nlohmann::json::object()) {
  WireFormatSettings s;
  s.sample_rate_hz = rate_hz;
  s.options = std::move(options);
  s.where = "imus[0].connection.stim300";
  return s;
}

std::string configure_error(Stim300Emulator& unit, const WireFormatSettings& s,
                            int* writes = nullptr) {
  EmulatorLink link(unit);
  Stim300Configurator configurator(s, parse_stim300_options(s));
  try {
    configurator.configure(link);
  } catch (const DeviceConfigError& e) {
    if (writes) *writes = link.writes;
    return e.what();
  }
  return "(accepted)";
}

TEST(Stim300Configurator, ReadsTheIdentityAndChecksWhatTheUnitStreams) {
  Stim300Emulator unit(kUnit, Stim300EmulatorSettings{});
  EmulatorLink link(unit);
  const auto s = settings(2000.0, {{"datagram", "0xA7"}, {"termination", true}});
  Stim300Configurator configurator(s, parse_stim300_options(s));
  const auto id = configurator.configure(link);
  EXPECT_EQ(id.model, "STIM300 841672500301");
  EXPECT_EQ(id.serial, "25581234");
  EXPECT_EQ(id.firmware, "");
  EXPECT_EQ(link.writes, 3);  // N, I, C: one each
}

TEST(Stim300Configurator, ARateTheUnitDoesNotStreamIsRefusedWithWhatItStreams) {
  Stim300Emulator unit(kUnit, Stim300EmulatorSettings{});
  const auto what = configure_error(unit, settings(500.0));
  EXPECT_NE(what.find("STIM300 841672500301 (serial 25581234) streams datagram 0xA7 "
                      "(rate_acc_incl_temp) with CR LF at about "),
            std::string::npos)
      << what;
  EXPECT_NE(what.find("asks sample_rate_hz 500 "), std::string::npos) << what;
}

TEST(Stim300Configurator, ADatagramOrTerminationTheUnitDoesNotStreamIsRefused) {
  Stim300EmulatorSettings es;
  es.datagram_id = kRateAccIncl;
  es.sample_rate_hz = 500.0;
  es.termination = false;
  Stim300Emulator unit(kUnit, es);
  const auto what =
      configure_error(unit, settings(500.0, {{"datagram", "rate_acc"}, {"termination", true}}));
  const std::string said = "streams datagram 0x93 (rate_acc_incl) without CR LF at about ";
  const auto at = what.find(said);
  ASSERT_NE(at, std::string::npos) << what;
  EXPECT_NEAR(std::stod(what.substr(at + said.size())), 500.0, 50.0) << what;
  EXPECT_NE(what.find("asks datagram 0x91 (rate_acc), termination true"), std::string::npos)
      << what;
  Stim300Emulator same(kUnit, es);
  EXPECT_EQ(configure_error(same, settings(500.0, {{"datagram", "0x93"}})), "(accepted)");
}

TEST(Stim300Configurator, WithoutTheRateCheckOnlyTheDatagramIsChecked) {
  Stim300Emulator unit(kUnit, Stim300EmulatorSettings{});  // 2000 Hz
  EXPECT_EQ(configure_error(unit, settings(500.0, {{"rate_check", false}})), "(accepted)");
  Stim300Emulator again(kUnit, Stim300EmulatorSettings{});
  const auto what =
      configure_error(again, settings(500.0, {{"rate_check", false}, {"datagram", "0x93"}}));
  EXPECT_NE(what.find("asks datagram 0x93 (rate_acc_incl) (the unit"), std::string::npos) << what;
}

TEST(Stim300Configurator, ARateNoStim300MakesIsRefusedBeforeAsking) {
  Stim300Emulator unit(kUnit, Stim300EmulatorSettings{});
  int writes = -1;
  const auto what = configure_error(unit, settings(400.0), &writes);
  EXPECT_EQ(what, "STIM300 samples at 125, 250, 500, 1000 or 2000 Hz, not 400 Hz");
  EXPECT_EQ(writes, 0);
}

TEST(Stim300Configurator, AReplyThatNeverComesNamesTheRequest) {
  Stim300Emulator unit(kUnit, Stim300EmulatorSettings{});
  unit.on_sample(sample_k(0));  // powered long ago: its start-up datagrams are gone
  EmulatorLink link(unit, false);
  const auto s = settings(2000.0);
  Stim300Configurator configurator(s, parse_stim300_options(s));
  try {
    configurator.configure(link);
    FAIL() << "no error";
  } catch (const DeviceConfigError& e) {
    EXPECT_STREQ(e.what(), "no reply to N (part number) within 500 ms (3 attempts)");
  }
  EXPECT_EQ(link.writes, 3);
}

TEST(Stim300Emulator, RoundTripReproducesTheSamplesToTheDatagramsResolution) {
  Stim300EmulatorSettings es;
  es.sample_rate_hz = 500.0;  // every fourth native sample
  es.latency_us = 300;
  Stim300Emulator unit(kUnit, es);
  Stim300Options o;
  o.termination = true;
  Stim300Decoder decoder(o, 500.0);
  std::vector<core::ImuSample> out;
  for (std::uint32_t k = 0; k < 400; ++k) decoder.feed(unit.on_sample(sample_k(k)), out);
  ASSERT_EQ(out.size(), 100u);
  for (std::size_t i = 0; i < out.size(); ++i) {
    const auto want = sample_k(static_cast<std::uint32_t>(4 * i));
    EXPECT_NEAR(out[i].gyro_dps.x(), want.gyro_dps.x(), 0.5 / 16384.0);
    EXPECT_NEAR(out[i].gyro_dps.z(), 100.0, 0.5 / 16384.0);
    EXPECT_NEAR(out[i].accel_mps2.x(), want.accel_mps2.x(), 0.5 * 9.80665 / 524288.0);
    EXPECT_NEAR(out[i].accel_mps2.z(), 9.80665, 0.5 * 9.80665 / 524288.0);
    EXPECT_DOUBLE_EQ(out[i].temperature_c, 31.5);
    EXPECT_EQ(out[i].sequence, i);
    EXPECT_NEAR(out[i].device_time_s, want.device_time_s - 300e-6, 1e-9);
  }
  EXPECT_EQ(decoder.stats().sequence_gaps, 0u);
  EXPECT_EQ(decoder.stats().startup_datagrams, 3u);  // power-on
  EXPECT_EQ(decoder.stats().garbage_bytes, 0u);
}

TEST(Stim300Emulator, ResetStartsTheCounterAgainAfterTheStartUpDatagrams) {
  Stim300Emulator unit(kUnit, Stim300EmulatorSettings{});
  Stim300Options o;
  o.termination = true;
  Stim300Decoder decoder(o, 2000.0);
  std::vector<core::ImuSample> out;
  for (std::uint32_t k = 0; k < 50; ++k) decoder.feed(unit.on_sample(sample_k(k)), out);
  decoder.take_device_reports();
  const std::string reset = "R\r";
  decoder.feed(unit.on_host_bytes(std::vector<std::uint8_t>(reset.begin(), reset.end())), out);
  for (std::uint32_t k = 50; k < 60; ++k) decoder.feed(unit.on_sample(sample_k(k)), out);
  ASSERT_EQ(out.size(), 60u);
  EXPECT_EQ(out[50].sequence, 0u);
  EXPECT_LT(out[50].device_time_s, out[49].device_time_s);
  const auto reports = decoder.take_device_reports();
  ASSERT_FALSE(reports.empty());
  EXPECT_EQ(reports[0], "restart: the unit sent its part number datagram (841672500301)");
}

TEST(Stim300WireFormat, MakesItsPartsFromTheOptions) {
  const auto& format = stim300_wire_format();
  EXPECT_EQ(format.name(), "stim300");
  EXPECT_EQ(format.sequence_modulus(settings(2000.0)), std::uint64_t{1} << 32);
  EXPECT_NE(format.make_decoder(settings(2000.0, {{"gyro_output", "increment"}})), nullptr);
  EXPECT_NE(format.make_configurator(settings(2000.0)), nullptr);
  EXPECT_THROW(format.make_decoder(settings(2000.0, {{"datagram", "0x98"}})), std::exception);
  auto emulator = format.make_emulator(kUnit);
  ASSERT_NE(emulator, nullptr);
  auto decoder = format.make_decoder(settings(2000.0));
  std::vector<core::ImuSample> out;
  for (std::uint32_t k = 0; k < 5; ++k) decoder->feed(emulator->on_sample(sample_k(k)), out);
  EXPECT_EQ(out.size(), 5u);
}

}  // namespace
}  // namespace calstand::drivers::stim300
