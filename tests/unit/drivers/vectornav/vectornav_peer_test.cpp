// A SerialImu in format vectornav against an independent Python VN-100 (vectornav_peer.py,
// written from the manual) on a pseudo-terminal.
#include <gtest/gtest.h>

#include <cmath>
#include <thread>

#include "../child_process.hpp"
#include "../schema_error_field.hpp"
#include "core/clock.hpp"
#include "core/error.hpp"
#include "drivers/serial_imu.hpp"

namespace calstand::drivers {
namespace {

using namespace std::chrono_literals;

std::vector<core::ImuSample> vn_collect(Imu& imu, std::size_t count) {
  std::vector<core::ImuSample> out;
  for (int i = 0; i < 300 && out.size() < count; ++i) {
    auto s = imu.poll();
    out.insert(out.end(), s.begin(), s.end());
    if (out.size() < count) std::this_thread::sleep_for(10ms);
  }
  return out;
}

TEST(VectornavPeer, ConfiguresIdentifiesAndDecodesAnIndependentDevice) {
  test::ChildProcess peer(
      {test::kPython, CALSTAND_SOURCE_DIR "/tests/unit/drivers/vectornav/vectornav_peer.py"});
  ASSERT_TRUE(peer.started());
  const auto path = peer.read_line();
  ASSERT_TRUE(path.has_value());

  core::ImuConfig config;
  config.name = "imu0";
  config.backend = "serial";
  config.connection = {{"path", *path},
                       {"baud", 921600},
                       {"format", "vectornav"},
                       {"sample_rate_hz", 100},
                       {"vectornav", {{"outputs", "uncompensated"}, {"port", 2}}}};
  core::SteadyClock clock;
  SerialImu imu(config, clock, "imus[0].connection");
  ASSERT_TRUE(imu.configure());
  const auto id = imu.identity();
  ASSERT_TRUE(id.has_value());
  EXPECT_EQ(id->model, "VN-100T-CR (hardware revision 5)");
  EXPECT_EQ(id->serial, "0100099999");
  EXPECT_EQ(id->firmware, "2.1.0.0");
  EXPECT_EQ(imu.sequence_modulus(), std::uint64_t{1} << 32);

  // What the peer understood of the writes: ASCII output off, then the binary output on
  // port 2 every 8th IMU sample (100 Hz) with TimeStartup and the uncompensated IMU fields.
  const auto writes = peer.json_lines();
  ASSERT_EQ(writes.size(), 2u);
  EXPECT_EQ(writes[0]["write"], 6);
  EXPECT_EQ(writes[0]["values"], nlohmann::json::array({"0"}));
  EXPECT_EQ(writes[1]["write"], 75);
  EXPECT_EQ(writes[1]["values"], nlohmann::json::array({"2", "8", "05", "0001", "001C"}));

  ASSERT_TRUE(imu.activate());
  peer.send_line("stream");
  const auto got = vn_collect(imu, 58);
  ASSERT_EQ(got.size(), 58u);  // 60 sent but one left out and one with a broken CRC
  std::size_t i = 0;
  for (int k = 0; k < 60; ++k) {
    if (k == 20 || k == 30) continue;
    const auto& s = got[i++];
    EXPECT_EQ(s.sequence, static_cast<std::uint32_t>(100 + k)) << k;  // round(t * 100 Hz)
    EXPECT_NEAR(s.device_time_s, 1.0 + 0.01 * k, 1e-9) << k;
    EXPECT_NEAR(s.gyro_dps.x(), 10.0 * std::sin(k / 10.0), 1e-5) << k;
    EXPECT_NEAR(s.gyro_dps.y(), 5.0 * std::cos(k / 10.0), 1e-5) << k;
    EXPECT_NEAR(s.gyro_dps.z(), 0.1 * k, 1e-5) << k;
    EXPECT_NEAR(s.accel_mps2.x(), 0.01 * k, 1e-6) << k;
    EXPECT_NEAR(s.accel_mps2.y(), -9.80665, 1e-5) << k;
    EXPECT_NEAR(s.accel_mps2.z(), std::cos(k / 7.0), 1e-6) << k;
    EXPECT_NEAR(s.temperature_c, 25.0 + 0.01 * k, 1e-5) << k;
  }
  const auto sent = peer.json_lines();
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0]["sent"], 59);
  const auto counters = imu.fault_counters();
  EXPECT_EQ(counters.at("frames"), 58u);
  EXPECT_GE(counters.at("crc_errors"), 1u);
  EXPECT_EQ(counters.at("garbage_bytes"), 44u + 5u);  // the broken message and the garbage
  EXPECT_EQ(counters.at("sequence_gaps"), 2u);
  EXPECT_EQ(counters.at("device_errors"), 1u);
  // What the device reports is said at the next fault summary (deactivate() forces one).
  ASSERT_TRUE(imu.deactivate());
  bool reported = false;
  for (const auto& e : imu.take_events()) {
    if (e.message.find("$VNERR,12: Insufficient Baud Rate") != std::string::npos) reported = true;
  }
  EXPECT_TRUE(reported);
}

TEST(VectornavPeer, TheStationFileOptionsAreCheckedNamingTheField) {
  core::SteadyClock clock;
  for (const auto& [options, field] : std::vector<std::pair<nlohmann::json, std::string>>{
           {{{"port", 3}}, "imus[0].connection.vectornav.port"},
           {{{"outputs", "raw"}}, "imus[0].connection.vectornav.outputs"},
           {{{"imu_rate_hz", 0}}, "imus[0].connection.vectornav.imu_rate_hz"},
           {{{"model", "VN-100"}}, "imus[0].connection.vectornav.model"}}) {
    core::ImuConfig config;
    config.name = "imu0";
    config.backend = "serial";
    config.connection = {{"path", "/dev/null"},
                         {"format", "vectornav"},
                         {"sample_rate_hz", 100},
                         {"vectornav", options}};
    try {
      SerialImu imu(config, clock, "imus[0].connection");
      ADD_FAILURE() << field;
    } catch (const core::InputError& e) {
      EXPECT_EQ(test::error_field(e), field) << e.what();
    }
  }
  // Every key with its default accepted.
  core::ImuConfig config;
  config.name = "imu0";
  config.backend = "serial";
  config.connection = {
      {"path", "/dev/null"},
      {"format", "vectornav"},
      {"sample_rate_hz", 100},
      {"vectornav", {{"outputs", "uncompensated"}, {"port", 1}, {"imu_rate_hz", 800}}}};
  EXPECT_NO_THROW(SerialImu(config, clock, "imus[0].connection"));
}

}  // namespace
}  // namespace calstand::drivers
