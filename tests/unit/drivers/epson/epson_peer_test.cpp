// The Epson format against an independent device: tests/unit/drivers/epson/epson_peer.py,
// written from the data sheets in Python, on a pseudo-terminal.
#include <gtest/gtest.h>

#include <cmath>
#include <thread>

#include "../child_process.hpp"
#include "../schema_error_field.hpp"
#include "drivers/serial_imu.hpp"

namespace calstand::drivers {
namespace {

using namespace std::chrono_literals;

core::ImuConfig epson_peer_config(const std::string& path, nlohmann::json epson) {
  core::ImuConfig c;
  c.name = "imu0";
  c.backend = "serial";
  c.connection = {{"path", path},
                  {"baud", 460800},
                  {"format", "epson"},
                  {"sample_rate_hz", 100},
                  {"epson", std::move(epson)}};
  return c;
}

std::vector<core::ImuSample> epson_collect(Imu& imu, std::size_t count) {
  std::vector<core::ImuSample> out;
  for (int i = 0; i < 400 && out.size() < count; ++i) {
    auto s = imu.poll();
    out.insert(out.end(), s.begin(), s.end());
    if (out.size() < count) std::this_thread::sleep_for(10ms);
  }
  return out;
}

TEST(EpsonPeer, ConfiguresIdentifiesAndDecodesThePythonDevice) {
  test::ChildProcess peer(
      {test::kPython, std::string(CALSTAND_SOURCE_DIR) + "/tests/unit/drivers/epson/epson_peer.py",
       "--faults"});
  ASSERT_TRUE(peer.started());
  const auto path = peer.read_line();
  ASSERT_TRUE(path) << "the peer printed no pty path";

  core::SteadyClock clock;
  SerialImu imu(epson_peer_config(*path, {{"width_bits", 32}}), clock, "imus[0].connection");
  ASSERT_TRUE(imu.configure());
  const auto id = imu.identity();
  ASSERT_TRUE(id);
  EXPECT_EQ(id->model, "G366PDG0");
  EXPECT_EQ(id->serial, "PEER0042");
  EXPECT_EQ(id->firmware, "VERSION 0x0209");
  ASSERT_TRUE(imu.activate());
  const auto got = epson_collect(imu, 100);
  ASSERT_GE(got.size(), 100u);

  for (std::size_t i = 0; i < got.size(); ++i) {
    const auto& s = got[i];
    // COUNT = 64336 + 20 k at 2000 counts/s, unwrapped past 65535.
    const double k = std::round((s.device_time_s * 2000.0 - 64336.0) / 20.0);
    ASSERT_NEAR(s.device_time_s, (64336.0 + 20.0 * k) / 2000.0, 1e-9);
    const double q = 1.0 / 65536;  // 32-bit resolution, in 16-bit LSBs
    EXPECT_NEAR(s.gyro_dps.x(), 10 * std::sin(k / 10), q / 66);
    EXPECT_NEAR(s.gyro_dps.y(), -2.5, q / 66);
    EXPECT_NEAR(s.gyro_dps.z(), 0.01 * k, q / 66);
    EXPECT_NEAR(s.accel_mps2.x(), 0.5 * std::cos(k / 10), q * 0.25e-3 * 9.80665);
    EXPECT_NEAR(s.accel_mps2.y(), 0.0, q * 0.25e-3 * 9.80665);
    EXPECT_NEAR(s.accel_mps2.z(), 9.80665, q * 0.25e-3 * 9.80665);
    EXPECT_NEAR(s.temperature_c, 30 + 0.01 * k, q * 0.00390625);
    if (i > 0) {
      EXPECT_EQ(s.sequence, got[i - 1].sequence + 1);
      EXPECT_NEAR(s.device_time_s - got[i - 1].device_time_s, 0.01, 1e-9);
    }
  }
  // The wrap of COUNT (64336 + 20 k passes 65535 at k = 60) is inside the 100 frames.
  EXPECT_GT(got.back().device_time_s, 65536.0 / 2000.0);

  const auto counters = imu.fault_counters();
  EXPECT_EQ(counters.at("crc_errors"), 1u);  // the bad copy of frame 50
  EXPECT_GE(counters.at("garbage_bytes"), 36u + 5u);
  EXPECT_EQ(counters.at("sequence_gaps"), 0u);
  ASSERT_TRUE(imu.deactivate());
}

TEST(EpsonPeer, AModelOtherThanPRODIDIsRefused) {
  test::ChildProcess peer({test::kPython, std::string(CALSTAND_SOURCE_DIR) +
                                              "/tests/unit/drivers/epson/epson_peer.py"});
  const auto path = peer.read_line();
  ASSERT_TRUE(path);
  core::SteadyClock clock;
  SerialImu imu(epson_peer_config(*path, {{"model", "G370PDF1"}}), clock, "imus[0].connection");
  const Result r = imu.configure();
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.message.find("PROD_ID is G366PDG0, not the model G370PDF1"), std::string::npos)
      << r.message;
}

}  // namespace
}  // namespace calstand::drivers

namespace calstand::drivers {
namespace {

TEST(EpsonOptionsSchema, TheStationSchemaChecksEveryKey) {
  auto error_of = [](const nlohmann::json& epson) -> std::string {
    try {
      SerialImuConnection::from_json(
          {{"path", "/dev/x"}, {"sample_rate_hz", 100}, {"format", "epson"}, {"epson", epson}},
          "imus[1].connection");
    } catch (const core::InputError& e) {
      return test::error_field(e);
    }
    return "accepted";
  };
  EXPECT_EQ(error_of({{"width_bits", 24}}), "imus[1].connection.epson.width_bits");
  EXPECT_EQ(error_of({{"model", "G999PDX0"}}), "imus[1].connection.epson.model");
  EXPECT_EQ(error_of({{"filter", "moving_average_3"}}), "imus[1].connection.epson.filter");
  EXPECT_EQ(error_of({{"count_step", "tick"}}), "imus[1].connection.epson.count_step");
  EXPECT_EQ(error_of({{"baud", 9600}}), "imus[1].connection.epson.baud");
  EXPECT_EQ(error_of({{"model", "G365PDF1"},
                      {"width_bits", 16},
                      {"filter", "kaiser_128_fc50"},
                      {"count_step", "output"}}),
            "accepted");
}

}  // namespace
}  // namespace calstand::drivers
