#include "drivers/modbus_chamber_options.hpp"

#include <gtest/gtest.h>

#include "../schema_error_field.hpp"
#include "core/clock.hpp"
#include "core/error.hpp"
#include "drivers/modbus_chamber.hpp"

namespace calstand::drivers {
namespace {

using nlohmann::json;

core::ChamberConfig chamber_with(json connection) {
  core::ChamberConfig c;
  c.backend = "modbus";
  c.connection = std::move(connection);
  return c;
}

std::string options_error_where(const json& connection) {
  try {
    ModbusChamberOptions::from_config(chamber_with(connection));
  } catch (const core::InputError& e) {
    return test::error_field(e);
  }
  return "";
}

TEST(ModbusChamberOptions, TcpWithDefaults) {
  auto c = chamber_with({{"transport", "tcp"}, {"host", "10.0.0.5"}, {"map", "watlow-f4t"}});
  c.min_c = -70;
  c.max_c = 180;
  c.max_ramp_c_per_min = 3;
  c.ambient_c = 21;
  const auto o = ModbusChamberOptions::from_config(c);
  EXPECT_EQ(o.transport, ModbusTransport::kTcp);
  EXPECT_EQ(o.port, 502);
  EXPECT_EQ(o.unit_id, 1);
  EXPECT_EQ(o.timeout_ms, 500);
  EXPECT_EQ(o.poll_period_ms, 250);
  EXPECT_DOUBLE_EQ(o.stale_after_s, 5.0);
  EXPECT_EQ(o.map.name, "watlow-f4t");
  EXPECT_EQ(o.map.setpoint.word_order, WordOrder::kHighFirst);
  EXPECT_DOUBLE_EQ(o.min_c, -70);
  EXPECT_DOUBLE_EQ(o.max_c, 180);
  EXPECT_DOUBLE_EQ(o.max_ramp_c_per_min, 3);
  EXPECT_DOUBLE_EQ(o.ambient_c, 21);
  EXPECT_EQ(o.link_name(), "tcp 10.0.0.5:502");
}

TEST(ModbusChamberOptions, RtuWithEverything) {
  const auto o = ModbusChamberOptions::from_config(chamber_with({{"transport", "rtu"},
                                                                 {"path", "/dev/ttyUSB3"},
                                                                 {"baud", 19200},
                                                                 {"parity", "even"},
                                                                 {"unit_id", 7},
                                                                 {"map", "watlow-f4"},
                                                                 {"timeout_ms", 300},
                                                                 {"poll_period_ms", 100},
                                                                 {"stale_after_s", 2.5},
                                                                 {"word_order", "low_first"}}));
  EXPECT_EQ(o.transport, ModbusTransport::kRtu);
  EXPECT_EQ(o.serial.path, "/dev/ttyUSB3");
  EXPECT_EQ(o.serial.baud_rate, 19200);
  EXPECT_EQ(o.serial.parity, Parity::kEven);
  EXPECT_EQ(o.unit_id, 7);
  EXPECT_EQ(o.map.name, "watlow-f4");
  EXPECT_EQ(o.timeout_ms, 300);
  EXPECT_EQ(o.poll_period_ms, 100);
  EXPECT_DOUBLE_EQ(o.stale_after_s, 2.5);
  EXPECT_EQ(o.link_name(), "rtu /dev/ttyUSB3");
}

TEST(ModbusChamberOptions, ErrorsNameTheConnectionField) {
  const json tcp = {{"transport", "tcp"}, {"host", "h"}, {"map", "watlow-f4t"}};
  const json rtu = {{"transport", "rtu"}, {"path", "/dev/ttyS0"}, {"map", "watlow-f4"}};
  const std::string at = "chamber.connection.";
  auto with = [](json j, const std::string& key, json value) {
    j[key] = std::move(value);
    return j;
  };
  auto without = [](json j, const std::string& key) {
    j.erase(key);
    return j;
  };
  EXPECT_EQ(options_error_where(tcp), "");
  EXPECT_EQ(options_error_where(rtu), "");
  EXPECT_EQ(options_error_where(without(tcp, "transport")), at + "transport");
  EXPECT_EQ(options_error_where(with(tcp, "transport", "udp")), at + "transport");
  EXPECT_EQ(options_error_where(without(tcp, "host")), at + "host");
  EXPECT_EQ(options_error_where(with(tcp, "port", 70000)), at + "port");
  EXPECT_EQ(options_error_where(with(tcp, "port", "502")), at + "port");
  EXPECT_EQ(options_error_where(with(tcp, "unit_id", 256)), at + "unit_id");
  EXPECT_EQ(options_error_where(with(rtu, "unit_id", 0)), at + "unit_id");  // broadcast on a bus
  EXPECT_EQ(options_error_where(without(rtu, "path")), at + "path");
  EXPECT_EQ(options_error_where(with(rtu, "baud", 12345)), at + "baud");
  EXPECT_EQ(options_error_where(with(rtu, "parity", "mark")), at + "parity");
  EXPECT_EQ(options_error_where(with(tcp, "word_order", "middle")), at + "word_order");
  EXPECT_EQ(options_error_where(without(tcp, "map")), at + "map");
  const json half_map = {{"process_value", {{"address", 1}, {"encoding", "int16"}}},
                         {"setpoint", {{"address", 2}}}};
  EXPECT_EQ(options_error_where(with(tcp, "map", half_map)), at + "map.setpoint.encoding");
  EXPECT_EQ(options_error_where(with(tcp, "timeout_ms", 0)), at + "timeout_ms");
  EXPECT_EQ(options_error_where(with(tcp, "poll_period_ms", -5)), at + "poll_period_ms");
  EXPECT_EQ(options_error_where(with(tcp, "stale_after_s", 0)), at + "stale_after_s");
  EXPECT_EQ(options_error_where(with(tcp, "hots", "x")), at + "hots");
  // A field of the other transport: "unknown property" of this one (the schema's words).
  EXPECT_EQ(options_error_where(with(tcp, "path", "/dev/ttyS0")), at + "path");
  EXPECT_EQ(options_error_where(json::array()), "chamber.connection");
}

TEST(ModbusChamberOptions, FactoryParsesWithoutIo) {
  core::SteadyClock clock;
  // Port 1 on a documentation address: a constructor that tried to connect would hang or fail.
  auto chamber = make_modbus_chamber(
      chamber_with(
          {{"transport", "tcp"}, {"host", "192.0.2.1"}, {"port", 1}, {"map", "watlow-f4t"}}),
      clock);
  ASSERT_NE(chamber, nullptr);
  EXPECT_EQ(chamber->state(), DeviceState::kUnconfigured);
  EXPECT_TRUE(chamber->read_state().fault);
  EXPECT_FALSE(chamber->set_temperature(30, std::nullopt));
  EXPECT_THROW(make_modbus_chamber(chamber_with({{"transport", "tcp"}}), clock), core::InputError);
}

}  // namespace
}  // namespace calstand::drivers
