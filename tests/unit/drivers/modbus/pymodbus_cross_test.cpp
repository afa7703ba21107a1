// Cross-tests against an independent Modbus implementation (pymodbus 3.0, system Python):
// our driver against a pymodbus F4T stand-in, and a pymodbus client against our server.
// Skipped, saying why, where /usr/bin/python3 or pymodbus is missing.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

#include "drivers/modbus_chamber.hpp"
#include "drivers/modbus_chamber_server.hpp"
#include "modbus_test_support.hpp"

namespace calstand::drivers {
namespace {

using namespace test;
using nlohmann::json;

/// The last of `writes` (the script's echo lines) to register `address`.
std::optional<json> last_write_to(const std::vector<json>& writes, int address) {
  for (auto it = writes.rbegin(); it != writes.rend(); ++it) {
    if ((*it)["write"] == address) return *it;
  }
  return std::nullopt;
}

#define SKIP_WITHOUT_PYMODBUS()                                           \
  do {                                                                    \
    static const std::string missing = pymodbus_missing();                \
    if (!missing.empty() && std::getenv("CALSTAND_REQUIRE_PYMODBUS")) {   \
      FAIL() << missing                                                   \
             << " (CALSTAND_REQUIRE_PYMODBUS is set: the test command "   \
                "installs python3-pymodbus, so its absence is an error)"; \
    }                                                                     \
    if (!missing.empty()) GTEST_SKIP() << missing;                        \
  } while (false)

/// The pymodbus F4T started on an ephemeral port; port() is 0 when it did not come up.
struct PymodbusF4t {
  ChildProcess process;
  int port = 0;
  explicit PymodbusF4t(const std::string& word_order, double pv_c = 23.5)
      : process({kPython, script_path("f4t_pymodbus_server.py"), "--word-order", word_order, "--pv",
                 std::to_string(pv_c)}) {
    const auto line = process.read_line(10000ms);
    if (line && line->rfind("port ", 0) == 0) port = std::stoi(line->substr(5));
  }
};

ModbusChamberOptions f4t_options(int port, const std::string& word_order) {
  auto config = quick_chamber_station().chamber;
  config.backend = "modbus";
  config.connection = {{"transport", "tcp"},   {"host", "127.0.0.1"},      {"port", port},
                       {"map", "watlow-f4t"},  {"word_order", word_order}, {"timeout_ms", 300},
                       {"poll_period_ms", 20}, {"stale_after_s", 60.0}};
  return ModbusChamberOptions::from_config(config);
}

class DriverAgainstPymodbus : public ::testing::TestWithParam<std::string> {};

TEST_P(DriverAgainstPymodbus, ReadsAndWritesTheF4tRegisters) {
  SKIP_WITHOUT_PYMODBUS();
  const std::string order = GetParam();
  PymodbusF4t f4t(order, 23.5);
  ASSERT_GT(f4t.port, 0) << "the pymodbus server did not start";
  // 60x: the 60 degC/min ramp from 23.5 to 40 takes about a quarter of a second of wall time.
  core::SteadyClock clock(60.0);
  ModbusChamber chamber(f4t_options(f4t.port, order), clock);
  ASSERT_TRUE(chamber.configure());
  auto s = chamber.read_state();
  EXPECT_NEAR(s.air_temperature_c, 23.5, 1e-6);
  EXPECT_EQ(s.mode, core::ChamberMode::kStandby);  // the script starts with mode 62 (off)

  ASSERT_TRUE(chamber.activate());
  ASSERT_TRUE(chamber.set_temperature(40.0, std::nullopt));
  EXPECT_TRUE(eventually([&] { return std::abs(chamber.read_state().setpoint_c - 40.0) < 1e-6; }));
  auto writes = f4t.process.json_lines();
  ASSERT_FALSE(writes.empty());
  auto echo = std::optional<json>(writes.back());
  // Decoded by the script with Python's struct module, not by our codec.
  EXPECT_DOUBLE_EQ((*echo)["setpoint_c"].get<double>(), 40.0);
  EXPECT_EQ((*echo)["mode"], 10);
  EXPECT_EQ(chamber.read_state().mode, core::ChamberMode::kActive);

  // The last setpoint write, word for word: 40.0f is 0x42200000.
  ASSERT_TRUE(chamber.set_temperature(40.0, std::nullopt));
  echo = last_write_to(f4t.process.json_lines(), 2782);
  ASSERT_TRUE(echo);
  const json expected = order == "high_first" ? json{0x4220, 0x0000} : json{0x0000, 0x4220};
  EXPECT_EQ((*echo)["values"], expected);

  ASSERT_TRUE(chamber.standby());
  echo = last_write_to(f4t.process.json_lines(), 2730);
  ASSERT_TRUE(echo);
  EXPECT_EQ((*echo)["mode"], 62);
  EXPECT_TRUE(eventually([&] { return chamber.read_state().mode == core::ChamberMode::kStandby; }));
}

INSTANTIATE_TEST_SUITE_P(WordOrders, DriverAgainstPymodbus,
                         ::testing::Values("high_first", "low_first"));

TEST(PymodbusCross, OutOfRangeAndNanProcessValuesAreFaults) {
  SKIP_WITHOUT_PYMODBUS();
  PymodbusF4t f4t("low_first", 25.0);
  ASSERT_GT(f4t.port, 0);
  core::SteadyClock clock;
  ModbusChamber chamber(f4t_options(f4t.port, "low_first"), clock);
  ASSERT_TRUE(chamber.configure());
  f4t.process.send_line("pv 999");
  core::ChamberState s;
  EXPECT_TRUE(eventually([&] {
    s = chamber.read_state();
    return s.fault;
  }));
  EXPECT_NE(s.fault_text.find("plausible range"), std::string::npos) << s.fault_text;
  EXPECT_DOUBLE_EQ(s.air_temperature_c, 25.0);
  f4t.process.send_line("pv nan");
  EXPECT_TRUE(eventually(
      [&] { return chamber.read_state().fault_text.find("not a number") != std::string::npos; }));
  f4t.process.send_line("pv -30.25");
  EXPECT_TRUE(eventually([&] {
    s = chamber.read_state();
    return !s.fault && s.air_temperature_c == -30.25;
  })) << s.fault_text;
  EXPECT_GE(chamber.fault_counters().at("out_of_range"), 2u);
}

TEST(PymodbusCross, PymodbusClientReadsAndWritesOurServer) {
  SKIP_WITHOUT_PYMODBUS();
  for (const std::string order : {"high_first", "low_first"}) {
    SCOPED_TRACE(order);
    const auto station = quick_chamber_station();
    std::mutex mutex;
    sim::SimWorld world(station);
    SimChamberBackend backend(world, mutex);
    auto server =
        ModbusChamberServer::tcp(watlow_f4t_map(word_order_from_json(order, "")), backend);
    server->start();
    ChildProcess client({kPython, script_path("f4t_pymodbus_client.py"), "--port",
                         std::to_string(server->port()), "--word-order", order, "--setpoint",
                         "41.5", "--mode", "10"});
    const auto line = client.read_line(10000ms);
    ASSERT_TRUE(line) << "no output from the pymodbus client";
    const auto out = json::parse(*line);
    ASSERT_FALSE(out.contains("error")) << out.dump();
    EXPECT_NEAR(out["before"]["pv"].get<double>(), station.chamber.ambient_c, 0.2);
    EXPECT_NEAR(out["before"]["sp"].get<double>(), station.chamber.ambient_c, 1e-4);
    EXPECT_EQ(out["before"]["mode"], 62);
    EXPECT_TRUE(out["setpoint_write_error"].is_null()) << out.dump();
    EXPECT_TRUE(out["mode_write_error"].is_null()) << out.dump();
    EXPECT_NEAR(out["after"]["sp"].get<double>(), 41.5, 1e-4);
    EXPECT_EQ(out["after"]["mode"], 10);
    EXPECT_EQ(out["out_of_range_write_error"], 3) << "illegal data value";
    EXPECT_EQ(out["process_value_write_error"], 2) << "illegal data address";
    EXPECT_EQ(out["unmapped_read_error"], 2);
    std::lock_guard lock(mutex);
    EXPECT_EQ(world.chamber_state().mode, core::ChamberMode::kActive);
    EXPECT_NEAR(world.chamber_state().setpoint_c, 41.5, 1e-4);
  }
}

}  // namespace
}  // namespace calstand::drivers
