// SerialImu with format stim300 against an independent Python STIM300 on a pseudo-terminal
// (stim300_peer.py, written from the datasheet): the dialogue, the decoded signal, the counter
// and device time, and the faults the peer puts on the line.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <numbers>
#include <thread>

#include "../child_process.hpp"
#include "core/clock.hpp"
#include "drivers/serial_imu.hpp"

namespace calstand::drivers {
namespace {

using namespace std::chrono_literals;

std::string stim300_peer_script() {
  return std::string(CALSTAND_SOURCE_DIR) + "/tests/unit/drivers/stim300/stim300_peer.py";
}

core::ImuConfig stim300_config(const std::string& path, double rate_hz) {
  core::ImuConfig c;
  c.name = "stim";
  c.backend = "serial";
  c.connection = {
      {"path", path},
      {"baud", 921600},
      {"format", "stim300"},
      {"sample_rate_hz", rate_hz},
      {"stim300", {{"datagram", "0xA7"}, {"accel_range_g", 10}, {"termination", true}}}};
  return c;
}

TEST(Stim300Peer, ConfiguresAndDecodesAnIndependentUnitOnAPty) {
  test::ChildProcess peer({test::kPython, stim300_peer_script(), "500"});
  ASSERT_TRUE(peer.started());
  const auto path = peer.read_line(10000ms);
  ASSERT_TRUE(path && path->rfind("/dev/", 0) == 0) << path.value_or("(no path)");
  core::SteadyClock clock;
  SerialImu imu(stim300_config(*path, 500.0), clock, "imus[0].connection");
  const auto configured = imu.configure();
  ASSERT_TRUE(configured) << configured.message;
  ASSERT_TRUE(imu.activate());
  const auto id = imu.identity();
  ASSERT_TRUE(id);
  EXPECT_EQ(id->model, "STIM300 841672500301");
  EXPECT_EQ(id->serial, "25581234");
  EXPECT_EQ(imu.sequence_modulus(), std::uint64_t{1} << 32);

  // Two seconds: the peer's faults come one second after the configuration reply.
  std::vector<core::ImuSample> got;
  std::vector<DeviceEvent> events;
  for (int i = 0; i < 250; ++i) {
    auto s = imu.poll();
    got.insert(got.end(), s.begin(), s.end());
    auto e = imu.take_events();
    events.insert(events.end(), e.begin(), e.end());
    std::this_thread::sleep_for(10ms);
  }
  ASSERT_GT(got.size(), 600u);
  std::size_t steps_of_one = 0;
  for (std::size_t i = 0; i < got.size(); ++i) {
    const auto& s = got[i];
    const double phase = 2 * std::numbers::pi * (s.sequence % 256) / 256.0;
    EXPECT_NEAR(s.gyro_dps.x(), std::sin(3 * phase), 0.5 / 16384 + 1e-12) << i;
    EXPECT_NEAR(s.gyro_dps.y(), std::cos(3 * phase), 0.5 / 16384 + 1e-12) << i;
    EXPECT_DOUBLE_EQ(s.gyro_dps.z(), 0.5);
    EXPECT_NEAR(s.accel_mps2.x(), 0.1 * std::sin(phase) * 9.80665, 0.5 * 9.80665 / 524288) << i;
    EXPECT_NEAR(s.accel_mps2.y(), -0.2 * 9.80665, 0.5 * 9.80665 / 524288);
    EXPECT_DOUBLE_EQ(s.accel_mps2.z(), 9.80665);
    EXPECT_DOUBLE_EQ(s.temperature_c, 30 + 0.25 * (s.sequence % 4));
    EXPECT_NEAR(s.device_time_s, s.sequence / 500.0 - 400e-6, 1e-9);
    if (i > 0 && s.sequence == got[i - 1].sequence + 1) ++steps_of_one;
  }
  EXPECT_GE(steps_of_one + 2, got.size() - 1);  // one datagram lost to the broken CRC

  const auto counters = imu.fault_counters();
  EXPECT_EQ(counters.at("crc_errors"), 1u);
  EXPECT_GE(counters.at("garbage_bytes"), 3u);
  EXPECT_EQ(counters.at("sequence_gaps"), 1u);
  EXPECT_EQ(counters.at("length_errors"), 0u);
  bool status_reported = false;
  for (const auto& e : events) {
    if (e.message.find("gyro x: outside operating conditions") != std::string::npos) {
      status_reported = true;
    }
  }
  EXPECT_TRUE(status_reported);
  ASSERT_TRUE(imu.deactivate());
}

TEST(Stim300Peer, ARateTheUnitIsNotSetToFailsConfigureInTheUnitsWords) {
  test::ChildProcess peer({test::kPython, stim300_peer_script(), "500"});
  const auto path = peer.read_line(10000ms);
  ASSERT_TRUE(path);
  core::SteadyClock clock;
  SerialImu imu(stim300_config(*path, 1000.0), clock, "imus[0].connection");
  const auto configured = imu.configure();
  EXPECT_FALSE(configured);
  EXPECT_NE(configured.message.find("STIM300 841672500301 (serial 25581234) streams datagram 0xA7 "
                                    "(rate_acc_incl_temp) with CR LF at about "),
            std::string::npos)
      << configured.message;
  EXPECT_NE(configured.message.find("asks sample_rate_hz 1000"), std::string::npos)
      << configured.message;
}

}  // namespace
}  // namespace calstand::drivers
