// The csz-ezt570 map against an independent Modbus TCP peer written from the CSZ EZT-570i/S
// User Communication Reference Manual (csz_ezt570_peer.py: plain sockets, no Modbus library):
// read, set, standby, an alarm word, a dropped connection ridden out. Skipped, saying why,
// where /usr/bin/python3 is missing.

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "drivers/modbus_chamber.hpp"
#include "drivers/ride_out.hpp"
#include "modbus_test_support.hpp"

namespace calstand::drivers {
namespace {

using namespace test;
using nlohmann::json;

/// The peer started on an ephemeral port; port is 0 when it did not come up.
struct CszPeer {
  ChildProcess process{{kPython, script_path("csz_ezt570_peer.py")}};
  int port = 0;
  CszPeer() {
    const auto line = process.read_line(10000ms);
    if (line && line->rfind("port ", 0) == 0) port = std::stoi(line->substr(5));
  }
};

ModbusChamberOptions csz_options(int port) {
  auto config = quick_chamber_station().chamber;
  config.backend = "modbus";
  config.connection = {{"transport", "tcp"},   {"host", "127.0.0.1"}, {"port", port},
                       {"map", "csz-ezt570"},  {"timeout_ms", 300},   {"poll_period_ms", 20},
                       {"stale_after_s", 60.0}};
  return ModbusChamberOptions::from_config(config);
}

/// The values of the last of the peer's write echoes to `address`.
std::optional<json> last_values_written_to(const std::vector<json>& writes, int address) {
  for (auto it = writes.rbegin(); it != writes.rend(); ++it) {
    if ((*it)["write"] == address) return (*it)["values"];
  }
  return std::nullopt;
}

#define SKIP_WITHOUT_PYTHON()                                                  \
  do {                                                                         \
    if (::access(kPython, X_OK) != 0) GTEST_SKIP() << kPython << " not found"; \
  } while (false)

TEST(CszEzt570, ReadsSetsAndStandsByAsTheManualSays) {
  SKIP_WITHOUT_PYTHON();
  CszPeer peer;
  ASSERT_GT(peer.port, 0) << "the peer did not start";
  core::SteadyClock clock(60.0);  // the driver's 60 degC/min ramp to -10 takes 0.6 s of wall time
  ModbusChamber chamber(csz_options(peer.port), clock);
  ASSERT_TRUE(chamber.configure());
  auto s = chamber.read_state();
  EXPECT_NEAR(s.air_temperature_c, 23.5, 1e-9);  // 235 in tenths
  EXPECT_NEAR(s.setpoint_c, 25.0, 1e-9);
  EXPECT_EQ(s.mode, core::ChamberMode::kStandby) << "the peer starts with the chamber off";
  EXPECT_FALSE(s.fault) << s.fault_text;

  ASSERT_TRUE(chamber.activate());
  ASSERT_TRUE(chamber.set_temperature(-10.0, std::nullopt));
  EXPECT_TRUE(eventually([&] { return std::abs(chamber.read_state().setpoint_c + 10.0) < 1e-9; }));
  auto writes = peer.process.json_lines();
  const auto setpoint = last_values_written_to(writes, 60);
  ASSERT_TRUE(setpoint.has_value());
  EXPECT_EQ((*setpoint)[0], 65436) << "-10.0 degC is -100 tenths, two's complement";
  const auto on = last_values_written_to(writes, 22);
  ASSERT_TRUE(on.has_value());
  EXPECT_EQ((*on)[0], 1) << "chamber on: event bit 0";
  EXPECT_TRUE(eventually([&] { return chamber.read_state().mode == core::ChamberMode::kActive; }));
  peer.process.send_line("pv -9.5");
  EXPECT_TRUE(
      eventually([&] { return std::abs(chamber.read_state().air_temperature_c + 9.5) < 1e-9; }));

  ASSERT_TRUE(chamber.standby());
  const auto off = last_values_written_to(peer.process.json_lines(), 22);
  ASSERT_TRUE(off.has_value());
  EXPECT_EQ((*off)[0], 0);
  EXPECT_TRUE(eventually([&] { return chamber.read_state().mode == core::ChamberMode::kStandby; }));
}

TEST(CszEzt570, AnAlarmWordIsAFaultInTheControllersWordsAndAnEvent) {
  SKIP_WITHOUT_PYTHON();
  CszPeer peer;
  ASSERT_GT(peer.port, 0) << "the peer did not start";
  core::SteadyClock clock(60.0);
  ModbusChamber chamber(csz_options(peer.port), clock);
  ASSERT_TRUE(chamber.configure());
  chamber.take_events();
  peer.process.send_line("alarm 57 4");
  EXPECT_TRUE(eventually([&] { return chamber.read_state().fault; }));
  const auto s = chamber.read_state();
  EXPECT_NE(s.fault_text.find("chamber alarms (register 57) reads 0x0004"), std::string::npos)
      << s.fault_text;
  EXPECT_FALSE(s.link_lost) << "an alarm is the controller's word, not a lost link";
  std::string events;
  for (const auto& e : chamber.take_events()) events += e.message + "\n";
  EXPECT_NE(events.find("chamber alarms"), std::string::npos) << events;
  peer.process.send_line("alarm 57 0");
  EXPECT_TRUE(eventually([&] { return !chamber.read_state().fault; }));
}

TEST(CszEzt570, ADroppedConnectionIsRiddenOut) {
  SKIP_WITHOUT_PYTHON();
  CszPeer peer;
  ASSERT_GT(peer.port, 0) << "the peer did not start";
  core::SteadyClock clock(1.0);
  ModbusChamber chamber(csz_options(peer.port), clock);
  ASSERT_TRUE(chamber.configure());
  peer.process.send_line("drop");
  // The driver sees the connection go on its next poll and reconnects with backoff; a read
  // riding the outage out answers with a live state.
  RideOutPolicy policy;
  policy.limit_s = 30.0;
  EXPECT_TRUE(eventually([&] { return chamber.fault_counters().at("link_losses") > 0; }));
  const auto read = read_riding_out(chamber, clock, policy);
  EXPECT_TRUE(read.result) << read.result.message;
  EXPECT_FALSE(read.state.link_lost);
  EXPECT_NEAR(read.state.air_temperature_c, 23.5, 1e-9);
  EXPECT_GE(chamber.fault_counters().at("reconnects"), 1u);
}

}  // namespace
}  // namespace calstand::drivers
