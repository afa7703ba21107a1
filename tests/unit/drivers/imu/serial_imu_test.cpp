#include "drivers/serial_imu.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "../schema_error_field.hpp"
#include "core/error.hpp"
#include "drivers/pseudo_terminal.hpp"

namespace calstand::drivers {
namespace {

using namespace std::chrono_literals;
using nlohmann::json;

core::ImuSample make_serial_sample(std::uint32_t sequence) {
  core::ImuSample s;
  s.sequence = sequence;
  s.device_time_s = 100.0 + 0.01 * sequence;
  s.gyro_dps = {0.5 + sequence, -1.25, 0.015625};
  s.accel_mps2 = {0.0, 0.125, 9.8125};
  s.temperature_c = 25.5;
  return s;
}

core::ImuConfig serial_config(const std::string& path) {
  core::ImuConfig c;
  c.name = "imu0";
  c.backend = "serial";
  c.connection = {{"path", path}, {"baud", 921600}, {"sample_rate_hz", 100}};
  return c;
}

void send(PseudoTerminal& pty, const std::vector<std::uint8_t>& bytes) {
  ASSERT_TRUE(pty.write(bytes, 1000ms).ok());
}

/// Polls until `count` samples arrived or 2 s passed.
std::vector<core::ImuSample> collect(Imu& imu, std::size_t count) {
  std::vector<core::ImuSample> out;
  for (int i = 0; i < 200 && out.size() < count; ++i) {
    auto s = imu.poll();
    out.insert(out.end(), s.begin(), s.end());
    if (out.size() < count) std::this_thread::sleep_for(10ms);
  }
  return out;
}

TEST(SerialImu, DeliversFramesFromTheLineStampedOnTheStationClock) {
  PseudoTerminal pty;
  core::SteadyClock clock;
  SerialImu imu(serial_config(pty.slave_path()), clock, "imus[0].connection");
  ASSERT_TRUE(imu.configure());
  ASSERT_TRUE(imu.activate());
  EXPECT_EQ(imu.state(), DeviceState::kActive);
  const double before = clock.now_s();
  for (std::uint32_t i = 0; i < 50; ++i) send(pty, encode_imu_frame(make_serial_sample(i)));
  const auto got = collect(imu, 50);
  const double after = clock.now_s();
  ASSERT_EQ(got.size(), 50u);
  for (std::uint32_t i = 0; i < 50; ++i) {
    const auto want = make_serial_sample(i);
    EXPECT_EQ(got[i].sequence, i);
    EXPECT_DOUBLE_EQ(got[i].device_time_s, want.device_time_s);
    EXPECT_DOUBLE_EQ(got[i].gyro_dps.x(), want.gyro_dps.x());  // exact in f32
    EXPECT_DOUBLE_EQ(got[i].accel_mps2.z(), want.accel_mps2.z());
    EXPECT_DOUBLE_EQ(got[i].temperature_c, 25.5);
    EXPECT_GE(got[i].receive_time_s, before);
    EXPECT_LE(got[i].receive_time_s, after);
    if (i > 0) {
      EXPECT_GE(got[i].receive_time_s, got[i - 1].receive_time_s);
    }
  }
  EXPECT_EQ(imu.fault_counters().at("frames"), 50u);
  EXPECT_EQ(imu.fault_counters().at("crc_errors"), 0u);
  ASSERT_TRUE(imu.deactivate());
}

TEST(SerialImu, CountsCorruptFramesAsEventsAndInventsNothing) {
  PseudoTerminal pty;
  core::SteadyClock clock;
  SerialImu imu(serial_config(pty.slave_path()), clock, "imus[0].connection");
  ASSERT_TRUE(imu.configure());
  ASSERT_TRUE(imu.activate());
  send(pty, encode_imu_frame(make_serial_sample(0)));
  send(pty, {0x00, 0x13, 0x37, 0xA5});  // garbage
  auto corrupt = encode_imu_frame(make_serial_sample(1));
  corrupt[20] ^= 0x40;  // CRC error
  send(pty, corrupt);
  send(pty, encode_imu_frame(make_serial_sample(3)));  // sample 2 never sent: a gap
  const auto got = collect(imu, 2);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].sequence, 0u);
  EXPECT_EQ(got[1].sequence, 3u);
  std::this_thread::sleep_for(100ms);
  EXPECT_TRUE(imu.poll().empty());
  ASSERT_TRUE(imu.deactivate());  // the reader reports what it saw on the way out
  const auto counters = imu.fault_counters();
  EXPECT_EQ(counters.at("crc_errors"), 1u);
  EXPECT_EQ(counters.at("sequence_gaps"), 1u);
  EXPECT_GE(counters.at("garbage_bytes"), 4u);
  const auto events = imu.take_events();
  ASSERT_FALSE(events.empty());
  EXPECT_TRUE(events.back().fault);
  EXPECT_NE(events.back().message.find("1 CRC"), std::string::npos) << events.back().message;
}

TEST(SerialImu, ALostLineIsAnErrorStateAndAnEvent) {
  auto pty = std::make_unique<PseudoTerminal>();
  core::SteadyClock clock;
  SerialImu imu(serial_config(pty->slave_path()), clock, "imus[0].connection");
  ASSERT_TRUE(imu.configure());
  ASSERT_TRUE(imu.activate());
  pty.reset();  // the device end hangs up (cable pulled)
  for (int i = 0; i < 200 && imu.state() != DeviceState::kError; ++i)
    std::this_thread::sleep_for(10ms);
  EXPECT_EQ(imu.state(), DeviceState::kError);
  const auto events = imu.take_events();
  ASSERT_FALSE(events.empty());
  EXPECT_NE(events.front().message.find("link lost"), std::string::npos) << events.front().message;
  EXPECT_GE(imu.fault_counters().at("read_errors"), 1u);
  ASSERT_TRUE(imu.deactivate());
}

TEST(SerialImu, InactiveDeviceDropsWhatArrivedBeforeActivation) {
  PseudoTerminal pty;
  core::SteadyClock clock;
  SerialImu imu(serial_config(pty.slave_path()), clock, "imus[0].connection");
  ASSERT_TRUE(imu.configure());
  send(pty, encode_imu_frame(make_serial_sample(0)));
  std::this_thread::sleep_for(50ms);
  EXPECT_TRUE(imu.poll().empty());
  ASSERT_TRUE(imu.activate());
  send(pty, encode_imu_frame(make_serial_sample(1)));
  const auto got = collect(imu, 1);
  ASSERT_FALSE(got.empty());
  EXPECT_EQ(got.back().sequence, 1u);
}

TEST(SerialImu, ConfigureNamesAMissingDevice) {
  core::SteadyClock clock;
  SerialImu imu(serial_config("/dev/nonexistent-imu"), clock, "imus[0].connection");
  const auto r = imu.configure();
  EXPECT_FALSE(r);
  EXPECT_NE(r.message.find("/dev/nonexistent-imu"), std::string::npos) << r.message;
  EXPECT_EQ(imu.state(), DeviceState::kError);
}

TEST(SerialImuConnection, EveryMistakeNamesItsField) {
  auto error_of = [](const json& c) -> std::string {
    try {
      SerialImuConnection::from_json(c, "imus[1].connection");
    } catch (const core::InputError& e) {
      return test::error_field(e) + ": " + e.what();
    }
    return "";
  };
  EXPECT_NE(error_of({{"baud", 9600}, {"sample_rate_hz", 100}}).find("imus[1].connection.path"),
            std::string::npos);
  EXPECT_NE(error_of({{"path", "/dev/x"}, {"baud", 12345}, {"sample_rate_hz", 100}}).find("baud"),
            std::string::npos);
  EXPECT_NE(error_of({{"path", "/dev/x"}, {"parity", "mark"}, {"sample_rate_hz", 100}})
                .find("imus[1].connection.parity"),
            std::string::npos);
  EXPECT_NE(error_of({{"path", "/dev/x"}}).find("sample_rate_hz"), std::string::npos);
  EXPECT_NE(error_of({{"path", "/dev/x"}, {"sample_rate_hz", "fast"}}).find("sample_rate_hz"),
            std::string::npos);
  EXPECT_NE(error_of({{"path", "/dev/x"}, {"sample_rate_hz", 100}, {"format", "nmea"}})
                .find("imus[1].connection.format"),
            std::string::npos);
  // A format's options sit under its own name, and only the calstand frame has a modulus.
  EXPECT_NE(error_of({{"path", "/dev/x"}, {"sample_rate_hz", 100}, {"xsens", {{"nope", 1}}}})
                .find("imus[1].connection.xsens"),
            std::string::npos);
  EXPECT_NE(error_of({{"path", "/dev/x"},
                      {"sample_rate_hz", 100},
                      {"format", "epson"},
                      {"sequence_modulus", 65536}})
                .find("imus[1].connection.sequence_modulus"),
            std::string::npos);
  EXPECT_NE(error_of({{"path", "/dev/x"}, {"sample_rate_hz", 100}, {"sequence_modulus", 1}})
                .find("sequence_modulus"),
            std::string::npos);
  const auto ok = SerialImuConnection::from_json(
      {{"path", "/dev/ttyUSB0"}, {"baud", 921600}, {"parity", "even"}, {"sample_rate_hz", 400}},
      "imus[1].connection");
  EXPECT_EQ(ok.serial.parity, Parity::kEven);
  EXPECT_EQ(ok.sequence_modulus, std::uint64_t{1} << 32);
}

}  // namespace
}  // namespace calstand::drivers

namespace calstand::drivers {
namespace {

TEST(SerialImu, ATailCutByTheStartFlushIsNotGarbageButLaterGarbageIs) {
  // The reader's start flushes the line's input, which may cut a frame in two: its tail is
  // the first thing the decoder sees. That is no fault of the line (it was the "33 garbage
  // bytes" event at every start); garbage after the first good frame still is one.
  PseudoTerminal pty;
  core::SteadyClock clock;
  SerialImu imu(serial_config(pty.slave_path()), clock, "imus[0].connection");
  ASSERT_TRUE(imu.configure());
  ASSERT_TRUE(imu.activate());
  const auto cut = encode_imu_frame(make_serial_sample(0));
  send(pty, std::vector<std::uint8_t>(cut.begin() + 12, cut.end()));
  for (std::uint32_t i = 1; i <= 5; ++i) send(pty, encode_imu_frame(make_serial_sample(i)));
  ASSERT_EQ(collect(imu, 5).size(), 5u);
  send(pty, {0x01, 0x02, 0x03});
  send(pty, encode_imu_frame(make_serial_sample(6)));
  ASSERT_EQ(collect(imu, 1).size(), 1u);
  const auto counters = imu.fault_counters();
  EXPECT_EQ(counters.at("start_bytes"), cut.size() - 12);
  EXPECT_EQ(counters.at("garbage_bytes"), 3u);
  EXPECT_EQ(counters.at("resyncs"), 1u);
  EXPECT_EQ(counters.at("sequence_gaps"), 0u);
  ASSERT_TRUE(imu.deactivate());
}

}  // namespace
}  // namespace calstand::drivers

namespace calstand::drivers {
namespace {

/// A device's dialogue as a test scripts it: the identity it reports, or its refusal.
class ScriptedConfigurator final : public ImuConfigurator {
 public:
  explicit ScriptedConfigurator(std::string refusal) : refusal_(std::move(refusal)) {}
  UnitIdentity configure(ByteTransport& /*link*/) override {
    ++calls;
    if (!refusal_.empty()) throw DeviceConfigError(refusal_);
    return {"MTi-630", "03881234", "1.2.3"};
  }
  int calls = 0;

 private:
  std::string refusal_;
};

TEST(SerialImu, ConfigureRunsTheDialogueAndKeepsTheIdentityTheDeviceReported) {
  core::SteadyClock clock;
  auto pty = std::make_unique<PseudoTerminal>();
  auto configurator = std::make_unique<ScriptedConfigurator>("");
  auto* dialogue = configurator.get();
  SerialImu imu("imu0", std::move(pty), std::make_unique<CalstandFrameDecoder>(), 100.0,
                std::uint64_t{1} << 32, clock, std::move(configurator));
  EXPECT_FALSE(imu.identity().has_value());  // nothing said before the dialogue
  ASSERT_TRUE(imu.configure());
  EXPECT_EQ(dialogue->calls, 1);
  ASSERT_TRUE(imu.identity().has_value());
  EXPECT_EQ(imu.identity()->serial, "03881234");
  EXPECT_EQ(imu.identity()->model, "MTi-630");
  EXPECT_EQ(imu.identity()->firmware, "1.2.3");
}

TEST(SerialImu, ARefusedConfigurationFailsConfigureWithTheDevicesWords) {
  core::SteadyClock clock;
  SerialImu imu("imu0", std::make_unique<PseudoTerminal>(),
                std::make_unique<CalstandFrameDecoder>(), 100.0, std::uint64_t{1} << 32, clock,
                std::make_unique<ScriptedConfigurator>("SetOutputConfiguration: Error 0x04 "
                                                       "(invalid period)"));
  const Result r = imu.configure();
  ASSERT_FALSE(r);
  EXPECT_NE(r.message.find("Error 0x04 (invalid period)"), std::string::npos) << r.message;
  EXPECT_EQ(imu.state(), DeviceState::kError);
  EXPECT_FALSE(imu.identity().has_value());
}

}  // namespace
}  // namespace calstand::drivers

namespace calstand::drivers {
namespace {

/// Calstand frames from a unit whose status word flags the same fault in every frame.
class FaultFlaggingDecoder final : public FrameDecoder {
 public:
  std::size_t feed(std::span<const std::uint8_t> bytes,
                   std::vector<core::ImuSample>& out) override {
    const std::size_t n = frames_.feed(bytes, out);
    for (std::size_t i = 0; i < n; ++i) reports_.push_back("gyro x: outside operating conditions");
    return n;
  }
  std::map<std::string, std::uint64_t> counters() const override { return frames_.counters(); }
  void restart() override { frames_.restart(); }
  std::vector<std::string> take_device_reports() override { return std::exchange(reports_, {}); }

 private:
  CalstandFrameDecoder frames_;
  std::vector<std::string> reports_;
};

TEST(SerialImu, AFaultTheDeviceFlagsInEveryFrameIsOneEventInItsWordsWithACount) {
  core::SteadyClock clock;
  auto pty = std::make_unique<PseudoTerminal>();
  auto* line = pty.get();
  SerialImu imu("imu0", std::move(pty), std::make_unique<FaultFlaggingDecoder>(), 100.0,
                std::uint64_t{1} << 32, clock);
  ASSERT_TRUE(imu.configure());
  ASSERT_TRUE(imu.activate());
  // The device's end of an injected pseudo-terminal is its slave: open it as the unit would.
  SerialPort unit({line->slave_path(), 115200, Parity::kNone});
  unit.open();
  for (std::uint32_t i = 0; i < 40; ++i) {
    const auto frame = encode_imu_frame(make_serial_sample(i));
    ASSERT_TRUE(unit.write(frame, 1000ms).ok());
  }
  ASSERT_EQ(collect(imu, 40).size(), 40u);
  ASSERT_TRUE(imu.deactivate());
  std::vector<std::string> reports;
  for (const auto& e : imu.take_events()) {
    if (e.message.find("the device reports") != std::string::npos) {
      EXPECT_TRUE(e.fault);
      reports.push_back(e.message);
    }
  }
  ASSERT_FALSE(reports.empty());
  EXPECT_LE(reports.size(), 3u);  // once per summary, not once per frame
  EXPECT_NE(reports.front().find("gyro x: outside operating conditions"), std::string::npos);
}

}  // namespace
}  // namespace calstand::drivers
