#include "drivers/can_imu.hpp"

#include <gtest/gtest.h>
#include <net/if.h>
#include <sys/socket.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <ostream>
#include <set>
#include <thread>

#include "../schema_error_field.hpp"
#include "can_test_support.hpp"
#include "core/error.hpp"
#include "drivers/socketcan_port.hpp"
#include "drivers/socketpair_can.hpp"

namespace calstand::drivers {
namespace {

using namespace std::chrono_literals;
using nlohmann::json;

const std::string kWhere = "imus[0].connection";

json connection_json() {
  return {{"interface", "can0"},
          {"map_file", can_test::example_map_path()},
          {"sample_rate_hz", 200},
          {"sequence_modulus", 256}};
}

CanImuConnection connection() { return CanImuConnection::from_json(connection_json(), kWhere); }

/// Events of `imu` until one contains `text` or `timeout` passed.
using can_test::collect;

std::vector<DeviceEvent> wait_for_event(Imu& imu, const std::string& text,
                                        std::chrono::milliseconds timeout = 3000ms) {
  std::vector<DeviceEvent> all;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    for (auto& e : imu.take_events()) {
      all.push_back(e);
      if (e.message.find(text) != std::string::npos) return all;
    }
    std::this_thread::sleep_for(5ms);
  }
  return all;
}

bool contains(const std::vector<DeviceEvent>& events, const std::string& text) {
  for (const auto& e : events) {
    if (e.message.find(text) != std::string::npos) return true;
  }
  return false;
}

TEST(CanImuConnectionTest, ParsesTheDocumentedFields) {
  json c = connection_json();
  c["filter_ids"] = false;
  c["kernel_timestamps"] = false;
  const auto conn = CanImuConnection::from_json(c, kWhere);
  EXPECT_EQ(conn.interface, "can0");
  EXPECT_EQ(conn.map.frames.size(), 4u);
  EXPECT_DOUBLE_EQ(conn.sample_rate_hz, 200.0);
  EXPECT_EQ(conn.sequence_modulus, 256u);
  EXPECT_FALSE(conn.filter_ids);
  EXPECT_FALSE(conn.kernel_timestamps);
  c.erase("sequence_modulus");
  EXPECT_EQ(CanImuConnection::from_json(c, kWhere).sequence_modulus, 256u);  // the field's wrap
}

TEST(CanImuConnectionTest, MapFileResolvesAgainstTheStationFolder) {
  const std::filesystem::path example = can_test::example_map_path();
  json c = connection_json();
  c["map_file"] = example.filename().string();
  EXPECT_EQ(
      CanImuConnection::from_json(c, kWhere, example.parent_path().string()).map.frames.size(), 4u);
  EXPECT_THROW(CanImuConnection::from_json(c, kWhere, "/nonexistent-dir"), core::InputError);
}

TEST(CanImuConnectionTest, InlineMapErrorsNameTheFullPath) {
  json c = connection_json();
  c.erase("map_file");
  c["map"] = can_test::float_map_json();
  c["map"]["signals"]["gyro_x"]["length_bits"] = 72;
  try {
    CanImuConnection::from_json(c, kWhere);
    FAIL() << "accepted a 72-bit field";
  } catch (const core::InputError& e) {
    EXPECT_EQ(test::error_field(e), "imus[0].connection.map.signals.gyro_x.length_bits")
        << e.what();
  }
}

struct BadConnection {
  const char* name;
  const char* key;
  json value;  // null: remove the key
  const char* where;
};

// The listing (ctest's names) shows the case's name, not the struct's bytes and pointers.
void PrintTo(const BadConnection& b, std::ostream* os) { *os << b.name; }

class CanImuConnectionErrorTest : public ::testing::TestWithParam<BadConnection> {};

TEST_P(CanImuConnectionErrorTest, NamesTheField) {
  const BadConnection& b = GetParam();
  json c = connection_json();
  if (b.value.is_null()) {
    c.erase(b.key);
  } else {
    c[b.key] = b.value;
  }
  try {
    CanImuConnection::from_json(c, kWhere);
    FAIL() << "accepted " << b.name;
  } catch (const core::InputError& e) {
    EXPECT_EQ(test::error_field(e), kWhere + b.where) << e.what();
  }
}

INSTANTIATE_TEST_SUITE_P(
    Mistakes, CanImuConnectionErrorTest,
    ::testing::Values(
        BadConnection{"no interface", "interface", nullptr, ".interface"},
        BadConnection{"empty interface", "interface", "", ".interface"},
        BadConnection{"no map", "map_file", nullptr, ".map"},
        // A valid map beside the file, so that it is the pair that is refused.
        BadConnection{"map and map_file", "map", can_test::float_map_json(), ".map"},
        BadConnection{"missing map file", "map_file", "/nonexistent/map.json", ".map_file"},
        BadConnection{"no rate", "sample_rate_hz", nullptr, ".sample_rate_hz"},
        BadConnection{"negative rate", "sample_rate_hz", -200, ".sample_rate_hz"},
        BadConnection{"modulus beyond the field", "sequence_modulus", 257, ".sequence_modulus"},
        BadConnection{"modulus 1", "sequence_modulus", 1, ".sequence_modulus"},
        BadConnection{"filter not a bool", "filter_ids", "yes", ".filter_ids"},
        BadConnection{"unknown key", "bitrate", 500000, ".bitrate"}),
    [](const ::testing::TestParamInfo<BadConnection>& param) {
      std::string n = param.param.name;
      for (char& ch : n) ch = std::isalnum(static_cast<unsigned char>(ch)) ? ch : '_';
      return n;
    });

TEST(CanImuTest, FactoryDoesNoIoAndConfigureNamesAMissingInterface) {
  core::SteadyClock clock;
  core::ImuConfig config;
  config.name = "imu-can";
  config.backend = "can";
  config.connection = connection_json();
  config.connection["interface"] = "calcan9";
  auto imu = make_can_imu(config, clock, kWhere);  // no such interface: still constructs
  EXPECT_EQ(imu->name(), "imu-can");
  EXPECT_EQ(imu->state(), DeviceState::kUnconfigured);
  EXPECT_EQ(imu->sequence_modulus(), 256u);
  EXPECT_DOUBLE_EQ(imu->sample_rate_hz(), 200.0);
  EXPECT_FALSE(imu->activate());  // not configured
  const Result r = imu->configure();
  EXPECT_FALSE(r);
  EXPECT_NE(r.message.find("calcan9: no such interface"), std::string::npos) << r.message;
  EXPECT_EQ(imu->state(), DeviceState::kError);
}

/// The driver over a socket pair, with a writer thread playing the IMU.
class CanImuEndToEndTest : public ::testing::Test {
 protected:
  void SetUp() override {
    auto [device_end, driver_end] = SocketPairCan::make_pair();
    bus_ = std::move(device_end);
    imu_ = std::make_unique<CanImu>("imu-can", connection_, std::move(driver_end), clock_);
    ASSERT_TRUE(imu_->configure());
    ASSERT_TRUE(imu_->activate());
    EXPECT_EQ(imu_->state(), DeviceState::kActive);
  }
  void TearDown() override {
    if (writer_.joinable()) writer_.join();
    if (imu_) imu_->deactivate();
  }
  void send(const can_frame& f) { ASSERT_EQ(bus_->write(f, 1000ms), ""); }

  core::SteadyClock clock_;
  CanImuConnection connection_ = connection();
  std::unique_ptr<SocketPairCan> bus_;
  std::unique_ptr<CanImu> imu_;
  std::thread writer_;
};

TEST_F(CanImuEndToEndTest, EverySampleArrivesIntactAndGapsAreCounted) {
  const CanSignalMap map = connection_.map;
  // 1000 samples (5 s of device time at 200 Hz), sent as fast as the pair takes them; samples
  // 300..302 and 700 are never sent (lost on the bus).
  const std::set<std::uint32_t> lost{300, 301, 302, 700};
  writer_ = std::thread([&] {
    for (std::uint32_t i = 0; i < 1000; ++i) {
      if (lost.count(i)) continue;
      for (const auto& f : encode_sample(map, can_test::sample(i % 256, 3.0 + 0.005 * i))) {
        if (!bus_->write(f, 1000ms).empty()) return;
      }
    }
  });
  const auto got = collect(*imu_, 1000 - lost.size());
  writer_.join();
  ASSERT_EQ(got.size(), 1000 - lost.size());
  std::uint32_t i = 0;
  double last_receive_s = -1.0;
  for (const auto& s : got) {
    while (lost.count(i)) ++i;
    const core::ImuSample sent = can_test::sample(i % 256, 3.0 + 0.005 * i);
    ASSERT_EQ(s.sequence, sent.sequence) << "sample " << i;
    ASSERT_LE((s.gyro_dps - sent.gyro_dps).cwiseAbs().maxCoeff(), 1e-5) << "sample " << i;
    ASSERT_LE((s.accel_mps2 - sent.accel_mps2).cwiseAbs().maxCoeff(), 1e-5) << "sample " << i;
    ASSERT_NEAR(s.temperature_c, sent.temperature_c, 0.005 + 1e-9);
    ASSERT_NEAR(s.device_time_s, sent.device_time_s, 1e-6);
    ASSERT_GE(s.receive_time_s, last_receive_s);  // SampleClock never goes back
    ASSERT_LE(s.receive_time_s, clock_.now_s());
    last_receive_s = s.receive_time_s;
    ++i;
  }
  const auto counters = imu_->fault_counters();
  EXPECT_EQ(counters.at("samples"), 1000 - lost.size());
  EXPECT_EQ(counters.at("sequence_gaps"), 2u);
  EXPECT_EQ(counters.at("incomplete_samples"), 0u);
  EXPECT_EQ(counters.at("read_errors"), 0u);
  // Gaps are summarised in an event (at the latest when the reader stops).
  imu_->deactivate();
  EXPECT_TRUE(contains(imu_->take_events(), "2 sequence_gaps")) << "no gap event";
}

TEST_F(CanImuEndToEndTest, GarbageIsCountedAndSummarisedNeverDelivered) {
  // Frames failing the map: short frames, a remote frame, and a message of the wrong size.
  const auto good = encode_sample(connection_.map, can_test::sample(1, 1.0));
  can_frame short_frame = good[0];
  short_frame.len = 3;
  can_frame remote = good[1];
  remote.can_id |= CAN_RTR_FLAG;  // filtered out like the kernel would
  for (int k = 0; k < 100; ++k) send(short_frame);
  send(remote);
  const char junk[3] = {1, 2, 3};
  ASSERT_EQ(::send(bus_->fd(), junk, sizeof junk, 0), 3);
  for (const auto& f : good) send(f);
  const auto got = collect(*imu_, 1);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].sequence, 1u);
  EXPECT_TRUE(collect(*imu_, 1, 50ms).empty());  // nothing invented
  const auto counters = imu_->fault_counters();
  EXPECT_EQ(counters.at("bad_dlc"), 100u);
  EXPECT_EQ(counters.at("malformed_messages"), 1u);
  EXPECT_EQ(counters.at("bad_frames"), 0u);  // the remote frame never reached the driver

  // A flood is summarised, not logged frame by frame: within a second, one event at most,
  // plus the final summary when the reader stops.
  imu_->deactivate();
  std::vector<DeviceEvent> summaries;
  for (auto& e : imu_->take_events()) {
    if (e.message.find("CAN faults") != std::string::npos) summaries.push_back(e);
  }
  ASSERT_FALSE(summaries.empty());
  EXPECT_LE(summaries.size(), 2u);
  EXPECT_NE(summaries.back().message.find("bad_dlc (total 100)"), std::string::npos)
      << summaries.back().message;
  EXPECT_TRUE(contains(summaries, "malformed_messages"));
}

TEST_F(CanImuEndToEndTest, UnfilteredUnknownIdsAreCounted) {
  imu_->deactivate();
  auto [device_end, driver_end] = SocketPairCan::make_pair();
  bus_ = std::move(device_end);
  CanImuConnection open_bus = connection_;
  open_bus.filter_ids = false;
  imu_ = std::make_unique<CanImu>("imu-can", open_bus, std::move(driver_end), clock_);
  ASSERT_TRUE(imu_->configure());
  ASSERT_TRUE(imu_->activate());
  can_frame other{};
  other.can_id = 0x7DF;
  other.len = 8;
  for (int k = 0; k < 5; ++k) send(other);
  for (const auto& f : encode_sample(open_bus.map, can_test::sample(2, 1.0))) send(f);
  ASSERT_EQ(collect(*imu_, 1).size(), 1u);
  EXPECT_EQ(imu_->fault_counters().at("unknown_ids"), 5u);
}

TEST_F(CanImuEndToEndTest, ALostLinkIsAnErrorAndAnEvent) {
  for (const auto& f : encode_sample(connection_.map, can_test::sample(0, 1.0))) send(f);
  ASSERT_EQ(collect(*imu_, 1).size(), 1u);
  bus_.reset();  // the IMU end goes away
  const auto events = wait_for_event(*imu_, "link lost");
  EXPECT_TRUE(contains(events, "link lost")) << "no event for the lost link";
  EXPECT_EQ(imu_->state(), DeviceState::kError);
  EXPECT_GE(imu_->fault_counters().at("read_errors"), 1u);
  EXPECT_TRUE(imu_->poll().empty());
  EXPECT_FALSE(imu_->activate());   // an error is left by configure(), not activate()
  EXPECT_TRUE(imu_->deactivate());  // stops the retrying reader promptly
  EXPECT_EQ(imu_->state(), DeviceState::kError);
  // A socket pair cannot be reopened: configure() says so and the device stays in error.
  const Result r = imu_->configure();
  EXPECT_FALSE(r);
  EXPECT_NE(r.message.find("cannot be reopened"), std::string::npos) << r.message;
  EXPECT_EQ(imu_->state(), DeviceState::kError);
}

TEST_F(CanImuEndToEndTest, ConfiguringAgainKeepsAHealthyLink) {
  ASSERT_TRUE(imu_->deactivate());
  EXPECT_EQ(imu_->state(), DeviceState::kInactive);
  ASSERT_TRUE(imu_->configure());
  ASSERT_TRUE(imu_->activate());
  for (const auto& f : encode_sample(connection_.map, can_test::sample(4, 1.0))) send(f);
  const auto got = collect(*imu_, 1);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].sequence, 4u);
}

TEST(CanImuVcanTest, SamplesOverVcan0) {
  if (::if_nametoindex("vcan0") == 0) {
    GTEST_SKIP() << "no vcan0 on this machine: modprobe vcan; ip link add dev vcan0 type vcan; "
                    "ip link set up vcan0";
  }
  core::SteadyClock clock;
  core::ImuConfig config;
  config.name = "imu-vcan";
  config.connection = connection_json();
  config.connection["interface"] = "vcan0";
  auto imu = make_can_imu(config, clock, kWhere);
  if (auto r = imu->configure(); !r) GTEST_SKIP() << "vcan0 cannot be opened here: " << r.message;
  ASSERT_TRUE(imu->activate());
  SocketCanPort bus("vcan0");
  bus.open();
  const CanSignalMap map = CanImuConnection::from_json(config.connection, kWhere).map;
  for (std::uint32_t i = 0; i < 50; ++i) {
    for (const auto& f : encode_sample(map, can_test::sample(i, 1.0 + 0.005 * i))) {
      ASSERT_EQ(bus.write(f, 1000ms), "");
    }
  }
  const auto got = collect(*imu, 50);
  ASSERT_EQ(got.size(), 50u);
  for (std::uint32_t i = 0; i < 50; ++i) EXPECT_EQ(got[i].sequence, i);
  EXPECT_EQ(imu->fault_counters().at("sequence_gaps"), 0u);
  imu->deactivate();
}

}  // namespace
}  // namespace calstand::drivers
