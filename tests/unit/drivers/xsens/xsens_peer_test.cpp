// SerialImu with format xsens against an independent Python device peer (xsens_peer.py,
// written from MT0101P) on a pseudo-terminal: the dialogue, the identity, the samples of the
// peer's known signal, and its checksum error, garbage and Error message.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <map>
#include <thread>

#include "../child_process.hpp"
#include "core/clock.hpp"
#include "drivers/serial_imu.hpp"

namespace calstand::drivers {
namespace {

using namespace std::chrono_literals;

constexpr int kPeerCount = 60;  // packets the peer streams
constexpr int kPeerBad = 20;    // the one sent with a broken checksum

core::ImuConfig xsens_peer_config(const std::string& path) {
  core::ImuConfig c;
  c.name = "imu0";
  c.backend = "serial";
  c.connection = {
      {"path", path},
      {"baud", 115200},
      {"format", "xsens"},
      {"sample_rate_hz", 100},
      {"xsens", {{"float_format", "fp1632"}, {"coordinates", "ned"}, {"temperature_rate_hz", 25}}}};
  return c;
}

TEST(XsensPeer, ConfiguresTheIndependentPeerAndDecodesItsSignal) {
  test::ChildProcess peer({test::kPython,
                           CALSTAND_SOURCE_DIR "/tests/unit/drivers/xsens/xsens_peer.py",
                           std::to_string(kPeerCount), std::to_string(kPeerBad)});
  ASSERT_TRUE(peer.started());
  const auto path = peer.read_line();
  ASSERT_TRUE(path.has_value()) << "the peer printed no pty path";

  core::SteadyClock clock;
  SerialImu imu(xsens_peer_config(*path), clock, "imus[0].connection");
  ASSERT_TRUE(imu.configure());
  ASSERT_TRUE(imu.activate());
  const auto id = imu.identity();
  ASSERT_TRUE(id.has_value());
  EXPECT_EQ(id->model, "MTi-670-2A8G4");
  EXPECT_EQ(id->serial, "037001A5");
  EXPECT_EQ(id->firmware, "1.8.2 build 55 rev 12345");
  EXPECT_EQ(imu.sequence_modulus(), 65536u);

  std::vector<core::ImuSample> got;
  for (int i = 0; i < 300 && (got.empty() || got.back().sequence < kPeerCount - 1); ++i) {
    const auto s = imu.poll();
    got.insert(got.end(), s.begin(), s.end());
    std::this_thread::sleep_for(10ms);
  }
  ASSERT_GE(got.size(), 20u);
  EXPECT_EQ(got.back().sequence, static_cast<std::uint32_t>(kPeerCount - 1));

  std::map<std::uint32_t, int> seen;
  for (const auto& s : got) {
    const double k = s.sequence;
    ++seen[s.sequence];
    EXPECT_NE(s.sequence, static_cast<std::uint32_t>(kPeerBad)) << "a bad checksum got through";
    // The unit outputs NED: its body axes are the sensor frame turned about x (x, -y, -z).
    const double tol = 1e-7;  // fp16.32 in rad/s, as deg/s
    EXPECT_NEAR(s.gyro_dps.x(), std::sin(k / 10), tol) << k;
    EXPECT_NEAR(s.gyro_dps.y(), -std::cos(k / 10), tol) << k;
    EXPECT_NEAR(s.gyro_dps.z(), -(0.5 + k / 100), tol) << k;
    EXPECT_NEAR(s.accel_mps2.x(), 0.01 * k, 1e-9) << k;
    EXPECT_NEAR(s.accel_mps2.y(), 0.5, 1e-9) << k;
    EXPECT_NEAR(s.accel_mps2.z(), -9.81, 1e-9) << k;
    EXPECT_NEAR(s.device_time_s, 5.0 + k / 100.0, 1e-9) << k;
    // Temperature comes every 4th packet (25 of 100 Hz); each sample has the latest.
    // The packet with the bad checksum was lost with its temperature.
    double carrier = k - std::fmod(k, 4.0);
    if (carrier == kPeerBad) carrier -= 4.0;
    const double latest = 25.0 + 0.01 * carrier;
    EXPECT_NEAR(s.temperature_c, latest, 1e-9) << k;
  }
  for (const auto& [sequence, count] : seen) EXPECT_EQ(count, 1) << sequence;

  const auto counters = imu.fault_counters();
  EXPECT_GE(counters.at("crc_errors"), 1u);
  EXPECT_GE(counters.at("garbage_bytes"), 7u);
  EXPECT_GE(counters.at("sequence_gaps"), 1u);  // the packet with the bad checksum
  EXPECT_EQ(counters.at("device_errors"), 1u);
  ASSERT_TRUE(imu.deactivate());
  bool reported = false;
  for (const auto& e : imu.take_events()) {
    if (e.message.find("Error 0x29: data overflow") != std::string::npos) reported = true;
  }
  EXPECT_TRUE(reported) << "the peer's Error message was not reported";
}

}  // namespace
}  // namespace calstand::drivers
