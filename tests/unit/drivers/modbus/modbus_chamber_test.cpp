// ModbusChamber against our own protocol simulator (ModbusChamberServer) over TCP and RTU on a
// pseudo-terminal, with a simulated world advancing in a background thread.

#include "drivers/modbus_chamber.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "drivers/modbus_chamber_server.hpp"
#include "modbus_test_support.hpp"

namespace calstand::drivers {
namespace {

using namespace test;
using nlohmann::json;

json tcp_connection(int port, const std::string& map) {
  return {{"transport", "tcp"}, {"host", "127.0.0.1"}, {"port", port},
          {"map", map},         {"timeout_ms", 100},   {"poll_period_ms", 20}};
}

json rtu_connection(const std::string& path, const std::string& map) {
  return {{"transport", "rtu"}, {"path", path},      {"baud", 19200},
          {"map", map},         {"timeout_ms", 100}, {"poll_period_ms", 20}};
}

ModbusChamberOptions options(const core::StationConfig& station, json connection,
                             double stale_after_s) {
  auto c = station.chamber;
  c.backend = "modbus";
  connection["stale_after_s"] = stale_after_s;
  c.connection = std::move(connection);
  return ModbusChamberOptions::from_config(c);
}

bool has_event(const std::vector<DeviceEvent>& events, bool fault, const std::string& text) {
  return std::any_of(events.begin(), events.end(), [&](const DeviceEvent& e) {
    return e.fault == fault && e.message.find(text) != std::string::npos;
  });
}

/// Collects the chamber's events while waiting for `condition`.
bool eventually_collecting(ModbusChamber& chamber, std::vector<DeviceEvent>& events,
                           const std::function<bool()>& condition,
                           std::chrono::milliseconds timeout = 5000ms) {
  return eventually(
      [&] {
        for (auto& e : chamber.take_events()) events.push_back(std::move(e));
        return condition();
      },
      timeout);
}

// The station runs 60x faster than the wall: 60 degC/min of station time is 1 degC per 16 ms.
constexpr double kTimeScale = 60.0;
constexpr double kStaleStationS = 30.0;  // half a second of wall time at kTimeScale

TEST(ModbusChamber, FollowsSetpointOverTcpWithF4tMapAndGoesToStandby) {
  const auto station = quick_chamber_station();
  RunningWorld w(station, kTimeScale);
  SimChamberBackend backend(w.world, w.mutex);
  auto server = ModbusChamberServer::tcp(watlow_f4t_map(), backend);
  server->start();
  ModbusChamber chamber(
      options(station, tcp_connection(server->port(), "watlow-f4t"), kStaleStationS), w.clock);
  EXPECT_EQ(chamber.state(), DeviceState::kUnconfigured);
  ASSERT_TRUE(chamber.configure());
  EXPECT_EQ(chamber.state(), DeviceState::kInactive);
  auto s = chamber.read_state();
  EXPECT_FALSE(s.fault) << s.fault_text;
  EXPECT_NEAR(s.air_temperature_c, 23.0, 0.5);
  EXPECT_EQ(s.mode, core::ChamberMode::kStandby);
  EXPECT_FALSE(chamber.set_temperature(60.0, std::nullopt)) << "inactive devices refuse commands";

  ASSERT_TRUE(chamber.activate());
  ASSERT_TRUE(chamber.set_temperature(60.0, std::nullopt));
  EXPECT_TRUE(eventually([&] {
    s = chamber.read_state();
    return !s.fault && s.mode == core::ChamberMode::kActive &&
           std::abs(s.setpoint_c - 60.0) < 1e-4 && std::abs(s.air_temperature_c - 60.0) < 0.5;
  })) << s.air_temperature_c
      << " degC, setpoint " << s.setpoint_c << ", " << s.fault_text;
  EXPECT_EQ(w.chamber().mode, core::ChamberMode::kActive);
  EXPECT_NEAR(w.chamber().setpoint_c, 60.0, 1e-4);
  // The cache is stamped with the station clock, within a few polls of now.
  EXPECT_NEAR(s.time_s, w.clock.now_s(), 0.1 * kTimeScale);

  ASSERT_TRUE(chamber.deactivate());
  EXPECT_EQ(chamber.state(), DeviceState::kInactive);
  EXPECT_EQ(w.chamber().mode, core::ChamberMode::kStandby);
  EXPECT_TRUE(eventually([&] {
    s = chamber.read_state();
    return s.mode == core::ChamberMode::kStandby && s.air_temperature_c < 50.0;
  })) << "the air drifts back to ambient in standby";
  EXPECT_EQ(chamber.fault_counters().at("link_losses"), 0u);
  EXPECT_EQ(chamber.fault_counters().at("refused_writes"), 0u);
}

TEST(ModbusChamber, FollowsSetpointOverRtuWithF4MapAndStandbyFallsBackToAmbient) {
  const auto station = quick_chamber_station();
  RunningWorld w(station, kTimeScale);
  SimChamberBackend backend(w.world, w.mutex);
  auto server = ModbusChamberServer::rtu(watlow_f4_map(), backend);
  server->start();
  ModbusChamber chamber(
      options(station, rtu_connection(server->slave_path(), "watlow-f4"), kStaleStationS), w.clock);
  ASSERT_TRUE(chamber.configure());
  ASSERT_TRUE(chamber.activate());
  ASSERT_TRUE(chamber.set_temperature(-20.0, std::nullopt));
  core::ChamberState s;
  EXPECT_TRUE(eventually([&] {
    s = chamber.read_state();
    return !s.fault && std::abs(s.setpoint_c + 20.0) < 0.05 &&
           std::abs(s.air_temperature_c + 20.0) < 0.5;
  })) << s.air_temperature_c
      << " degC, setpoint " << s.setpoint_c << ", " << s.fault_text;
  EXPECT_EQ(s.mode, core::ChamberMode::kActive);
  EXPECT_NEAR(w.chamber().setpoint_c, -20.0, 0.05) << "negative tenths on the wire";

  // The F4 map has no mode register: standby writes the ambient setpoint (the controller keeps
  // controlling, to room temperature) and the driver reports standby.
  ASSERT_TRUE(chamber.standby());
  EXPECT_NEAR(w.chamber().setpoint_c, station.chamber.ambient_c, 0.05);
  EXPECT_EQ(w.chamber().mode, core::ChamberMode::kActive);
  EXPECT_TRUE(eventually([&] {
    s = chamber.read_state();
    return s.mode == core::ChamberMode::kStandby && s.air_temperature_c > 20.0;
  }));
}

TEST(ModbusChamber, StepsTheSetpointAtTheRequestedRampInStationTime) {
  const auto station = quick_chamber_station();
  RunningWorld w(station, kTimeScale);
  SimChamberBackend backend(w.world, w.mutex);
  auto server = ModbusChamberServer::tcp(watlow_f4t_map(), backend);
  server->start();
  ModbusChamber chamber(
      options(station, tcp_connection(server->port(), "watlow-f4t"), kStaleStationS), w.clock);
  ASSERT_TRUE(chamber.configure());
  ASSERT_TRUE(chamber.activate());
  const double start_c = chamber.read_state().air_temperature_c;
  const double t0 = w.clock.now_s();
  ASSERT_TRUE(chamber.set_temperature(60.0, 30.0));  // half the chamber's own maximum
  // (station time, setpoint held by the simulated controller)
  std::vector<std::pair<double, double>> samples;
  eventually([&] {
    std::lock_guard lock(w.mutex);
    samples.emplace_back(w.world.now_s(), w.world.chamber_state().setpoint_c);
    return samples.back().second >= 60.0;
  });
  ASSERT_GE(samples.size(), 10u);
  EXPECT_LT(samples.front().second, 30.0) << "the target is not written at once";
  EXPECT_NEAR(samples.back().second, 60.0, 1e-4);
  // Slope over the middle of the ramp, away from the first and last step.
  const auto first =
      std::find_if(samples.begin(), samples.end(), [](const auto& p) { return p.second > 30.0; });
  const auto last =
      std::find_if(samples.begin(), samples.end(), [](const auto& p) { return p.second > 55.0; });
  ASSERT_TRUE(first != samples.end() && last != samples.end() && last > first);
  const double slope_c_per_min =
      (last->second - first->second) / (last->first - first->first) * 60.0;
  EXPECT_NEAR(slope_c_per_min, 30.0, 3.0);
  // End to end: (60 - start) at 30 degC/min, within a couple of polls.
  const double expected_end_s = t0 + (60.0 - start_c) / 30.0 * 60.0;
  EXPECT_NEAR(samples.back().first, expected_end_s, 0.1 * kTimeScale);
}

TEST(ModbusChamber, RefusesSetpointsOutsideTheLimitsWithoutWriting) {
  const auto station = quick_chamber_station();
  RunningWorld w(station, kTimeScale);
  SimChamberBackend backend(w.world, w.mutex);
  auto server = ModbusChamberServer::tcp(watlow_f4t_map(), backend);
  server->start();
  ModbusChamber chamber(
      options(station, tcp_connection(server->port(), "watlow-f4t"), kStaleStationS), w.clock);
  ASSERT_TRUE(chamber.configure());
  ASSERT_TRUE(chamber.activate());
  auto r = chamber.set_temperature(station.chamber.max_c + 1.0, std::nullopt);
  EXPECT_FALSE(r);
  EXPECT_NE(r.message.find("outside the chamber range"), std::string::npos) << r.message;
  EXPECT_FALSE(chamber.set_temperature(station.chamber.min_c - 0.1, std::nullopt));
  EXPECT_FALSE(chamber.set_temperature(std::numeric_limits<double>::quiet_NaN(), std::nullopt));
  r = chamber.set_temperature(50.0, station.chamber.max_ramp_c_per_min * 2);
  EXPECT_FALSE(r);
  EXPECT_NE(r.message.find("ramp"), std::string::npos) << r.message;
  EXPECT_FALSE(chamber.set_temperature(50.0, 0.0));
  EXPECT_EQ(chamber.fault_counters().at("refused_commands"), 5u);
  std::this_thread::sleep_for(100ms);  // several polls: none of them may write
  EXPECT_EQ(w.chamber().mode, core::ChamberMode::kStandby);
  EXPECT_NEAR(w.chamber().setpoint_c, station.chamber.ambient_c, 1e-4);
}

TEST(ModbusChamber, ConfigureFailureNamesTheLink) {
  core::SteadyClock clock;
  const auto station = quick_chamber_station();
  int free_port = 0;
  {
    // A port that was just ours and is closed now: nothing listens there.
    RunningWorld w(station, 1.0);
    SimChamberBackend backend(w.world, w.mutex);
    auto server = ModbusChamberServer::tcp(watlow_f4t_map(), backend);
    server->start();
    free_port = server->port();
  }
  ModbusChamber tcp(options(station, tcp_connection(free_port, "watlow-f4t"), 5.0), clock);
  auto r = tcp.configure();
  EXPECT_FALSE(r);
  EXPECT_NE(r.message.find("127.0.0.1:" + std::to_string(free_port)), std::string::npos)
      << r.message;
  EXPECT_NE(r.message.find("refused"), std::string::npos) << r.message;
  EXPECT_EQ(tcp.state(), DeviceState::kError);
  EXPECT_FALSE(tcp.activate());

  ModbusChamber rtu(options(station, rtu_connection("/dev/calstand-no-such-tty", "watlow-f4"), 5.0),
                    clock);
  r = rtu.configure();
  EXPECT_FALSE(r);
  EXPECT_NE(r.message.find("/dev/calstand-no-such-tty"), std::string::npos) << r.message;
}

TEST(ModbusChamber, TcpServerGoneMidRunFaultsThenReconnects) {
  const auto station = quick_chamber_station();
  RunningWorld w(station, 1.0);
  SimChamberBackend backend(w.world, w.mutex);
  auto server = ModbusChamberServer::tcp(watlow_f4t_map(), backend);
  server->start();
  const double stale_after_s = 1.0;
  ModbusChamber chamber(
      options(station, tcp_connection(server->port(), "watlow-f4t"), stale_after_s), w.clock);
  ASSERT_TRUE(chamber.configure());
  ASSERT_TRUE(chamber.activate());
  // 1 degC at 60 degC/min: the ramp is still running while the server is gone.
  ASSERT_TRUE(chamber.set_temperature(24.0, std::nullopt));
  std::vector<DeviceEvent> events = chamber.take_events();

  server->stop();
  core::ChamberState s;
  EXPECT_TRUE(eventually_collecting(
      chamber, events, [&] { return chamber.read_state().fault; },
      std::chrono::milliseconds(int(stale_after_s * 1000))))
      << "a fault within stale_after_s";
  s = chamber.read_state();
  EXPECT_NE(s.fault_text.find("link down"), std::string::npos) << s.fault_text;
  EXPECT_EQ(chamber.state(), DeviceState::kError);
  EXPECT_GE(chamber.fault_counters().at("link_losses"), 1u);
  EXPECT_FALSE(chamber.set_temperature(40.0, std::nullopt)) << "no write while the link is down";
  EXPECT_TRUE(eventually_collecting(chamber, events, [&] {
    return chamber.read_state().fault_text.find("no valid process value") != std::string::npos;
  })) << "stale once stale_after_s has passed";

  server->start();  // same port
  EXPECT_TRUE(eventually_collecting(chamber, events, [&] {
    return chamber.state() == DeviceState::kActive && !chamber.read_state().fault;
  })) << chamber.read_state().fault_text;
  EXPECT_GE(chamber.fault_counters().at("reconnects"), 1u);
  EXPECT_GE(chamber.fault_counters().at("stale"), 1u);
  EXPECT_TRUE(has_event(events, true, "link lost"));
  EXPECT_TRUE(has_event(events, true, "stale"));
  EXPECT_TRUE(has_event(events, false, "link back"));
  // The last command is written again after the reconnect and stepping continues.
  EXPECT_TRUE(eventually([&] { return std::abs(w.chamber().setpoint_c - 24.0) < 1e-3; }));
  EXPECT_TRUE(chamber.set_temperature(25.0, std::nullopt));
}

TEST(ModbusChamber, RtuServerSilentGoesStaleCountsTimeoutsAndRecovers) {
  const auto station = quick_chamber_station();
  RunningWorld w(station, 1.0);
  SimChamberBackend backend(w.world, w.mutex);
  auto server = ModbusChamberServer::rtu(watlow_f4_map(), backend);
  server->start();
  ModbusChamber chamber(options(station, rtu_connection(server->slave_path(), "watlow-f4"), 0.5),
                        w.clock);
  ASSERT_TRUE(chamber.configure());
  ASSERT_TRUE(chamber.activate());
  std::vector<DeviceEvent> events;
  server->stop();  // the pty stays: requests go unanswered
  EXPECT_TRUE(eventually_collecting(
      chamber, events,
      [&] {
        const auto s = chamber.read_state();
        return s.fault && s.fault_text.find("no valid process value") != std::string::npos;
      },
      2000ms));
  EXPECT_GE(chamber.fault_counters().at("timeouts"), 1u);
  server->start();
  EXPECT_TRUE(eventually_collecting(chamber, events, [&] {
    return chamber.state() == DeviceState::kActive && !chamber.read_state().fault;
  })) << chamber.read_state().fault_text;
  EXPECT_TRUE(has_event(events, true, "stale"));
  EXPECT_TRUE(has_event(events, false, "fresh again"));
}

/// A controller whose readings the test sets.
class FakeBackend final : public ChamberServerBackend {
 public:
  std::atomic<double> pv_c{25.0};
  std::atomic<bool> refuse_setpoints{false};
  core::ChamberState state() override {
    core::ChamberState s;
    s.air_temperature_c = pv_c;
    s.setpoint_c = 25.0;
    return s;
  }
  Result set_setpoint(double) override {
    return refuse_setpoints ? Result::failure("door open") : Result::success();
  }
  Result set_mode(Mode) override { return Result::success(); }
  Result set_ramp(double) override { return Result::success(); }
};

TEST(ModbusChamber, ImplausibleProcessValueIsAFaultNotAValue) {
  core::SteadyClock clock;
  const auto station = quick_chamber_station();
  FakeBackend backend;
  auto server = ModbusChamberServer::tcp(watlow_f4t_map(), backend);
  server->start();
  ModbusChamber chamber(options(station, tcp_connection(server->port(), "watlow-f4t"), 5.0), clock);
  ASSERT_TRUE(chamber.configure());
  std::vector<DeviceEvent> events;
  backend.pv_c = 999.0;
  core::ChamberState s;
  EXPECT_TRUE(eventually_collecting(chamber, events, [&] {
    s = chamber.read_state();
    return s.fault;
  }));
  EXPECT_NE(s.fault_text.find("plausible range"), std::string::npos) << s.fault_text;
  EXPECT_DOUBLE_EQ(s.air_temperature_c, 25.0) << "the last plausible value, never 999";
  EXPECT_GE(chamber.fault_counters().at("out_of_range"), 1u);

  backend.pv_c = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(eventually(
      [&] { return chamber.read_state().fault_text.find("not a number") != std::string::npos; }));
  backend.pv_c = 26.0;
  EXPECT_TRUE(eventually_collecting(chamber, events, [&] {
    s = chamber.read_state();
    return !s.fault && s.air_temperature_c == 26.0;
  }));
  EXPECT_TRUE(has_event(events, true, "plausible range"));
  EXPECT_TRUE(has_event(events, false, "plausible again"));

  // Configuring on an implausible reading fails rather than starting on it.
  backend.pv_c = -300.0;
  const auto r = chamber.configure();
  EXPECT_FALSE(r);
  EXPECT_NE(r.message.find("plausible"), std::string::npos) << r.message;
}

TEST(ModbusChamber, F4SensorFaultSentinelIsAFault) {
  core::SteadyClock clock;
  const auto station = quick_chamber_station();
  FakeBackend backend;
  auto server = ModbusChamberServer::rtu(watlow_f4_map(), backend);
  server->start();
  ModbusChamber chamber(options(station, rtu_connection(server->slave_path(), "watlow-f4"), 5.0),
                        clock);
  ASSERT_TRUE(chamber.configure());
  backend.pv_c = 5000.0;  // beyond int16 tenths: the server shows full scale, 0x7FFF
  core::ChamberState s;
  EXPECT_TRUE(eventually([&] {
    s = chamber.read_state();
    return s.fault;
  }));
  EXPECT_NE(s.fault_text.find("sensor-fault"), std::string::npos) << s.fault_text;
  EXPECT_DOUBLE_EQ(s.air_temperature_c, 25.0);
}

}  // namespace
}  // namespace calstand::drivers

namespace calstand::drivers {
namespace {

TEST(ModbusChamber, WritesTheControllerRefusesAreCountedAndReportedOnce) {
  core::SteadyClock clock;
  const auto station = quick_chamber_station();
  FakeBackend backend;
  backend.refuse_setpoints = true;
  auto server = ModbusChamberServer::tcp(watlow_f4t_map(), backend);
  server->start();
  ModbusChamber chamber(options(station, tcp_connection(server->port(), "watlow-f4t"), 5.0), clock);
  ASSERT_TRUE(chamber.configure());
  ASSERT_TRUE(chamber.activate());
  const auto r = chamber.set_temperature(30.0, std::nullopt);
  EXPECT_FALSE(r);
  EXPECT_NE(r.message.find("setpoint not written"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("Illegal data value"), std::string::npos) << r.message;
  std::this_thread::sleep_for(150ms);  // the poll thread retries several times meanwhile
  const auto events = chamber.take_events();
  EXPECT_EQ(std::count_if(events.begin(), events.end(),
                          [](const DeviceEvent& e) {
                            return e.fault && e.message.find("refused") != std::string::npos;
                          }),
            1);
  EXPECT_GE(chamber.fault_counters().at("refused_writes"), 2u);
  EXPECT_EQ(chamber.state(), DeviceState::kActive) << "a refusal is not a lost link";
  EXPECT_FALSE(chamber.read_state().fault);
  backend.refuse_setpoints = false;
  EXPECT_TRUE(chamber.set_temperature(30.0, std::nullopt));
}

}  // namespace
}  // namespace calstand::drivers

namespace calstand::drivers {
namespace {

TEST(ModbusChamber, GenericMapWithARampRegisterLetsTheControllerRamp) {
  const json map = json::parse(R"({
    "name": "ramping",
    "process_value": {"address": 1, "kind": "input", "encoding": "int16", "scale": 0.1},
    "setpoint": {"address": 2, "encoding": "float32"},
    "mode": {"address": 10, "control": 1, "standby": 0},
    "ramp_rate": {"address": 20, "encoding": "uint16", "scale": 0.1}
  })");
  const auto station = quick_chamber_station();
  RunningWorld w(station, kTimeScale);
  SimChamberBackend backend(w.world, w.mutex);
  auto server =
      ModbusChamberServer::tcp(register_map_from_json(map, "map", WordOrder::kLowFirst), backend);
  server->start();
  auto connection = tcp_connection(server->port(), "");
  connection["map"] = map;
  connection["word_order"] = "low_first";
  ModbusChamber chamber(options(station, connection, kStaleStationS), w.clock);
  ASSERT_TRUE(chamber.configure());
  ASSERT_TRUE(chamber.activate());
  const double t0 = w.clock.now_s();
  const double start_c = chamber.read_state().air_temperature_c;
  ASSERT_TRUE(chamber.set_temperature(60.0, 30.0));
  // No stepping: the target goes out at once and the simulated controller ramps at 30 degC/min.
  EXPECT_NEAR(w.chamber().setpoint_c, 60.0, 1e-4);
  EXPECT_EQ(w.chamber().mode, core::ChamberMode::kActive);
  core::ChamberState s;
  ASSERT_TRUE(eventually([&] {
    s = chamber.read_state();
    return s.air_temperature_c >= start_c + 12.0;
  }));
  // 12 degC at 30 degC/min is 24 s, plus the air's 2 s lag and a few polls.
  EXPECT_NEAR(s.time_s - t0, 26.0, 8.0);
  EXPECT_NEAR(s.setpoint_c, 60.0, 1e-4);
  EXPECT_EQ(s.mode, core::ChamberMode::kActive);
}

}  // namespace
}  // namespace calstand::drivers
