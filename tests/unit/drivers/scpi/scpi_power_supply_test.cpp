// The SCPI supply driver against its protocol simulator (ScpiServer over the simulated world)
// and against an independent bench supply written here in Python (standard library only).
#include "drivers/scpi_power_supply.hpp"

#include <gtest/gtest.h>

#include <mutex>

#include "../modbus/modbus_test_support.hpp"
#include "core/clock.hpp"
#include "drivers/scpi_server.hpp"
#include "sim/sim_world.hpp"

namespace calstand::drivers {
namespace {

using namespace std::chrono_literals;

core::PowerSupplyConfig supply_config(int port, int timeout_ms = 300) {
  core::PowerSupplyConfig c;
  c.name = "psu0";
  c.backend = "scpi";
  c.imu = "imu0";
  c.voltage_v = 28.0;
  c.current_limit_a = 1.5;
  c.connection = {
      {"transport", "tcp"}, {"host", "127.0.0.1"}, {"port", port}, {"timeout_ms", timeout_ms}};
  return c;
}

bool has_event(const std::vector<DeviceEvent>& events, const std::string& text) {
  for (const auto& e : events) {
    if (e.message.find(text) != std::string::npos) return true;
  }
  return false;
}

class ScpiAgainstSimulator : public ::testing::Test {
 protected:
  ScpiAgainstSimulator() : world_(sim::default_station()), server_(world_, mutex_, 0, 24.0, 1.0) {
    server_.start();
  }
  sim::SimWorld world_;
  std::mutex mutex_;
  ScpiServer server_;
  core::VirtualClock clock_;
};

TEST_F(ScpiAgainstSimulator, ConfiguresSwitchesTheUnitAndMeasures) {
  ScpiPowerSupply psu(supply_config(server_.port()), clock_);
  ASSERT_TRUE(psu.configure()) << "configure";
  ASSERT_TRUE(psu.activate());
  EXPECT_TRUE(has_event(psu.take_events(), "SCPI-SUPPLY-SIM"));
  ASSERT_TRUE(psu.set_output(false));
  EXPECT_FALSE(world_.imu_powered(0));
  auto r = psu.read();
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_FALSE(r.output_on);
  EXPECT_EQ(r.voltage_v, 0.0);
  ASSERT_TRUE(psu.set_output(true));
  EXPECT_TRUE(world_.imu_powered(0));
  r = psu.read();
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_TRUE(r.output_on);
  EXPECT_NEAR(r.voltage_v, 28.0, 1e-4) << "configure() set the station file's voltage";
  EXPECT_NEAR(r.current_a, SimScpiSupply::kLoadPowerW / 28.0, 1e-4);
  for (const auto& [name, count] : psu.fault_counters()) EXPECT_EQ(count, 0u) << name;
}

TEST_F(ScpiAgainstSimulator, AnErrorTheSupplyReportsFailsTheCommandWithItsText) {
  ScpiPowerSupply psu(supply_config(server_.port()), clock_);
  ASSERT_TRUE(psu.configure());
  ASSERT_TRUE(psu.activate());
  const Result r = psu.set_voltage(99.0);
  ASSERT_FALSE(r);
  EXPECT_NE(r.message.find("-222"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("Data out of range"), std::string::npos) << r.message;
  EXPECT_EQ(psu.fault_counters().at("refused_commands"), 1u);
  EXPECT_TRUE(psu.set_voltage(12.0)) << "the error queue was read out";
  EXPECT_NEAR(psu.read().voltage_v, 12.0, 1e-4);
}

TEST_F(ScpiAgainstSimulator, ADroppedConnectionIsRecordedAndReconnected) {
  ScpiPowerSupply psu(supply_config(server_.port()), clock_);
  ASSERT_TRUE(psu.configure());
  ASSERT_TRUE(psu.activate());
  psu.take_events();
  server_.drop_clients();
  std::this_thread::sleep_for(100ms);
  int failures = 0;
  bool back = false;
  for (int i = 0; i < 10 && !back; ++i) {
    const auto r = psu.read();
    if (r.ok)
      back = true;
    else
      ++failures;
    std::this_thread::sleep_for(50ms);
  }
  ASSERT_TRUE(back) << "the driver did not reconnect";
  const auto counters = psu.fault_counters();
  EXPECT_GE(counters.at("link_errors") + counters.at("timeouts"), 1u);
  EXPECT_GE(counters.at("reconnects"), 1u);
  const auto events = psu.take_events();
  EXPECT_TRUE(has_event(events, "link lost"));
  EXPECT_TRUE(has_event(events, "link back"));
}

TEST_F(ScpiAgainstSimulator, AHungSupplyTimesOut) {
  ScpiPowerSupply psu(supply_config(server_.port(), 150), clock_);
  ASSERT_TRUE(psu.configure());
  ASSERT_TRUE(psu.activate());
  server_.set_answering(false);
  const Result r = psu.set_output(false);
  ASSERT_FALSE(r);
  EXPECT_NE(r.message.find("no reply"), std::string::npos) << r.message;
  EXPECT_GE(psu.fault_counters().at("timeouts"), 1u);
  server_.set_answering(true);
  EXPECT_TRUE(psu.set_output(true));
}

TEST(ScpiSafeState, OffSwitchesTheOutputOffEvenUnconfiguredOnLeavesIt) {
  sim::SimWorld world(sim::default_station());
  std::mutex mutex;
  ScpiServer server(world, mutex, 0, 24.0, 1.0);
  server.start();
  core::VirtualClock clock;
  auto config = supply_config(server.port());
  config.safe_state = "on";
  ScpiPowerSupply keep(config, clock);
  EXPECT_TRUE(keep.make_safe());
  EXPECT_TRUE(world.imu_powered(0));
  config.safe_state = "off";
  ScpiPowerSupply off(config, clock);
  EXPECT_TRUE(off.make_safe());
  EXPECT_FALSE(world.imu_powered(0));
}

TEST(ScpiConnection, BadConnectionsAreRefusedNamingTheField) {
  core::VirtualClock clock;
  auto config = supply_config(5025);
  config.connection["model"] = "no-such-supply";
  try {
    ScpiPowerSupply psu(config, clock, "power_supplies[0].connection");
    FAIL() << "accepted";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("power_supplies[0].connection"), std::string::npos)
        << e.what();
  }
  config = supply_config(5025);
  config.connection.erase("host");
  EXPECT_THROW(ScpiPowerSupply(config, clock), std::exception);
}

// ---- against an independent SCPI server --------------------------------------------------------

// A bench supply as a vendor's firmware behaves, written from the SCPI standard with
// socketserver (not our code): long and short headers, NR3 numbers, `+0,"No error"`, an error
// queue, set commands unanswered. `--drop-after N` closes the connection after N lines (a
// broken cable); the next connection is served normally.
constexpr const char* kPythonSupply = R"PY(
import socketserver, sys, re
drop_after = int(sys.argv[1])
state = {"out": False, "volt": 0.0, "curr": 0.1, "errors": [], "lines": 0, "dropped": False}
def hdr(h, *forms):
    return any(re.fullmatch(f, h, re.I) for f in forms)
class Handler(socketserver.StreamRequestHandler):
    def handle(self):
        for raw in self.rfile:
            state["lines"] += 1
            if not state["dropped"] and state["lines"] == drop_after:
                state["dropped"] = True
                return
            parts = raw.decode().strip().split(None, 1)
            if not parts:
                continue
            h, arg = parts[0], (parts[1] if len(parts) > 1 else "")
            reply = None
            if h.upper() == "*IDN?": reply = "ACME,PSU-3005,SN42,2.1"
            elif h.upper() == "*CLS": state["errors"].clear()
            elif hdr(h, r"SYST(em)?:ERR(or)?(:NEXT)?\?"):
                reply = '%d,"%s"' % state["errors"].pop(0) if state["errors"] else '+0,"No error"'
            elif hdr(h, r"OUTP(ut)?(:STAT(e)?)?"):
                if arg.upper() in ("ON", "1"): state["out"] = True
                elif arg.upper() in ("OFF", "0"): state["out"] = False
                else: state["errors"].append((-224, "Illegal parameter value"))
            elif hdr(h, r"OUTP(ut)?(:STAT(e)?)?\?"): reply = "1" if state["out"] else "0"
            elif hdr(h, r"VOLT(age)?"):
                v = float(arg)
                if v > 30: state["errors"].append((-222, "Data out of range"))
                else: state["volt"] = v
            elif hdr(h, r"CURR(ent)?"): state["curr"] = float(arg)
            elif hdr(h, r"MEAS(ure)?:VOLT(age)?\?"): reply = "%+.5E" % (state["volt"] if state["out"] else 0.0)
            elif hdr(h, r"MEAS(ure)?:CURR(ent)?\?"): reply = "%+.5E" % (0.25 if state["out"] else 0.0)
            else: state["errors"].append((-113, "Undefined header"))
            if reply is not None:
                self.wfile.write((reply + "\n").encode()); self.wfile.flush()
class Server(socketserver.ThreadingTCPServer):
    allow_reuse_address = True
    daemon_threads = True
with Server(("127.0.0.1", 0), Handler) as s:
    print("port", s.server_address[1], flush=True)
    s.serve_forever()
)PY";

struct PythonSupply {
  test::ChildProcess process;
  int port = 0;
  explicit PythonSupply(int drop_after)
      : process({test::kPython, "-c", kPythonSupply, std::to_string(drop_after)}) {
    const auto line = process.read_line(10000ms);
    if (line && line->rfind("port ", 0) == 0) port = std::stoi(line->substr(5));
  }
};

TEST(ScpiAgainstPython, SwitchesMeasuresAndReportsTheSuppliesErrors) {
  if (::access(test::kPython, X_OK) != 0) GTEST_SKIP() << "no " << test::kPython;
  PythonSupply py(1000000);
  ASSERT_GT(py.port, 0) << "the Python supply did not start";
  core::VirtualClock clock;
  auto config = supply_config(py.port, 1000);
  ScpiPowerSupply psu(config, clock);
  ASSERT_TRUE(psu.configure());
  ASSERT_TRUE(psu.activate());
  EXPECT_TRUE(has_event(psu.take_events(), "ACME,PSU-3005"));
  ASSERT_TRUE(psu.set_output(true));
  auto r = psu.read();
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_TRUE(r.output_on);
  EXPECT_NEAR(r.voltage_v, 28.0, 1e-3);
  EXPECT_NEAR(r.current_a, 0.25, 1e-6);
  const Result refused = psu.set_voltage(32.0);
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.message.find("-222,\"Data out of range\""), std::string::npos)
      << refused.message;
  ASSERT_TRUE(psu.set_output(false));
  r = psu.read();
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_FALSE(r.output_on);
  EXPECT_EQ(r.voltage_v, 0.0);
}

TEST(ScpiAgainstPython, ADroppedConnectionFailsOneCallAndTheNextReconnects) {
  if (::access(test::kPython, X_OK) != 0) GTEST_SKIP() << "no " << test::kPython;
  // configure() sends 7 lines (*IDN?, *CLS, SYST:ERR?, VOLT, SYST:ERR?, CURR, SYST:ERR?); the
  // first query after it is dropped.
  PythonSupply py(8);
  ASSERT_GT(py.port, 0);
  core::VirtualClock clock;
  ScpiPowerSupply psu(supply_config(py.port, 500), clock);
  ASSERT_TRUE(psu.configure());
  ASSERT_TRUE(psu.activate());
  const auto cut = psu.read();
  EXPECT_FALSE(cut.ok);
  const auto again = psu.read();
  EXPECT_TRUE(again.ok) << again.message;
  EXPECT_EQ(psu.fault_counters().at("reconnects"), 1u);
  const auto events = psu.take_events();
  EXPECT_TRUE(has_event(events, "link lost"));
  EXPECT_TRUE(has_event(events, "link back"));
}

}  // namespace
}  // namespace calstand::drivers
