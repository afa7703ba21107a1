#include "core/station_config.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "core/error.hpp"
#include "core/json_schema.hpp"

namespace calstand::core {
namespace {

using nlohmann::json;

json minimal_station() {
  return json::parse(R"({
    "format": "calstand-station/1",
    "name": "lab-3",
    "site": {"latitude_deg": 45.0, "height_m": 100.0},
    "table": {"backend": "sim", "outer_axis": [0, 1, 0], "inner_axis": [0, 0, 1],
              "outer": {"max_rate_dps": 200, "max_accel_dps2": 100},
              "inner": {"max_rate_dps": 500, "max_accel_dps2": 300}},
    "chamber": {"backend": "sim", "min_c": -40, "max_c": 85, "max_ramp_c_per_min": 3},
    "imus": [{"name": "dut", "backend": "sim", "model": "ln200"}]
  })");
}

TEST(StationConfig, ReadsAMinimalStationWithDefaults) {
  const StationConfig c = StationConfig::from_json(minimal_station(), "lab-3.json");
  EXPECT_EQ(c.name, "lab-3");
  EXPECT_DOUBLE_EQ(c.site.latitude_deg, 45.0);
  EXPECT_FALSE(c.site.gravity_mps2.has_value());
  EXPECT_DOUBLE_EQ(c.table.outer.max_rate_dps, 200.0);
  EXPECT_DOUBLE_EQ(c.table.inner.encoder_resolution_deg, 1e-4);  // default
  EXPECT_DOUBLE_EQ(c.chamber.max_ramp_c_per_min, 3.0);
  ASSERT_EQ(c.imus.size(), 1u);
  EXPECT_EQ(c.imus[0].model, "ln200");
  EXPECT_EQ(c.seed, 1u);
}

TEST(StationConfig, RoundTripsThroughJson) {
  json doc = minimal_station();
  doc["site"]["gravity_mps2"] = 9.80123;
  doc["imus"][0]["mount_rpy_deg"] = {0, 0, 90};
  const StationConfig a = StationConfig::from_json(doc, "a.json");
  const StationConfig b = StationConfig::from_json(a.to_json(), "b.json");
  EXPECT_EQ(a.to_json(), b.to_json());
  EXPECT_DOUBLE_EQ(*b.site.gravity_mps2, 9.80123);
  EXPECT_EQ(b.imus[0].mount_rpy_deg, Eigen::Vector3d(0, 0, 90));
}

json with_supply(json doc, json supply) {
  doc["power_supplies"] = json::array({std::move(supply)});
  return doc;
}

json sim_supply() {
  return {{"name", "psu0"},  {"backend", "sim"},       {"imu", "dut"},
          {"voltage_v", 28}, {"current_limit_a", 1.5}, {"safe_state", "on"}};
}

TEST(StationConfig, PowerSuppliesRoundTrip) {
  const StationConfig a =
      StationConfig::from_json(with_supply(minimal_station(), sim_supply()), "a.json");
  ASSERT_EQ(a.power_supplies.size(), 1u);
  EXPECT_EQ(a.power_supplies[0].imu, "dut");
  EXPECT_DOUBLE_EQ(a.power_supplies[0].voltage_v, 28.0);
  EXPECT_EQ(a.power_supplies[0].safe_state, "on");
  EXPECT_EQ(a.supply_of("dut"), &a.power_supplies[0]);
  EXPECT_EQ(a.supply_of("other"), nullptr);
  const StationConfig b = StationConfig::from_json(a.to_json(), "b.json");
  EXPECT_EQ(a.to_json(), b.to_json());
  // Defaults: safe state off, 10 s for the unit to start streaming.
  json plain = sim_supply();
  plain.erase("safe_state");
  const StationConfig c = StationConfig::from_json(with_supply(minimal_station(), plain), "c.json");
  EXPECT_EQ(c.power_supplies[0].safe_state, "off");
  EXPECT_DOUBLE_EQ(c.power_supplies[0].start_timeout_s, 10.0);
  json slow = sim_supply();
  slow["start_timeout_s"] = 180;
  EXPECT_DOUBLE_EQ(StationConfig::from_json(with_supply(minimal_station(), slow), "d.json")
                       .power_supplies[0]
                       .start_timeout_s,
                   180.0);
}

// Each bad supply is refused naming its field.
TEST(StationConfig, BadPowerSuppliesNameTheField) {
  const auto error_of = [](const json& supply) {
    try {
      StationConfig::from_json(with_supply(minimal_station(), supply), "s.json");
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  json s = sim_supply();
  s["imu"] = "nobody";
  EXPECT_NE(error_of(s).find("power_supplies[0].imu"), std::string::npos) << error_of(s);
  s = sim_supply();
  s["voltage_v"] = -5;
  EXPECT_NE(error_of(s).find("power_supplies[0].voltage_v"), std::string::npos) << error_of(s);
  s = sim_supply();
  s["start_timeout_s"] = 0;
  EXPECT_NE(error_of(s).find("start_timeout_s"), std::string::npos) << error_of(s);
  s = sim_supply();
  s["safe_state"] = "maybe";
  EXPECT_NE(error_of(s).find("safe_state"), std::string::npos) << error_of(s);
  s = sim_supply();
  s["backend"] = "scpi";
  s["connection"] = {{"transport", "tcp"}, {"host", "127.0.0.1"}, {"port", 5025}};
  EXPECT_NE(error_of(s).find("power_supplies[0].backend"), std::string::npos) << error_of(s);
  s = sim_supply();
  s.erase("current_limit_a");
  EXPECT_NE(error_of(s).find("current_limit_a"), std::string::npos) << error_of(s);
  json doc = minimal_station();
  doc["power_supplies"] = json::array({sim_supply(), sim_supply()});
  doc["power_supplies"][1]["name"] = "psu1";
  try {
    StationConfig::from_json(doc, "s.json");
    ADD_FAILURE() << "two supplies for one IMU accepted";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("power_supplies[1].imu"), std::string::npos) << e.what();
  }
}

TEST(StationConfig, TableTiltIsOptionalAndRoundTrips) {
  EXPECT_EQ(StationConfig::from_json(minimal_station(), "s.json").table.tilt_rad,
            Eigen::Vector2d::Zero());
  json doc = minimal_station();
  doc["table"]["tilt_rad"] = {{"east", 2e-4}, {"north", -3e-4}};
  const StationConfig a = StationConfig::from_json(doc, "a.json");
  EXPECT_EQ(a.table.tilt_rad, Eigen::Vector2d(2e-4, -3e-4));
  const StationConfig b = StationConfig::from_json(a.to_json(), "b.json");
  EXPECT_EQ(b.table.tilt_rad, a.table.tilt_rad);
  doc["table"]["tilt_rad"] = {{"east", 0.5}};  // not a small angle
  EXPECT_THROW(StationConfig::from_json(doc, "s.json"), SchemaError);
}

TEST(StationConfig, AxesTypedWithFewDecimalsAreAcceptedAndNormalised) {
  json doc = minimal_station();
  doc["table"]["inner_axis"] = {0.7071, 0, 0.7071};  // norm 0.99999 (off by 1e-5)
  const StationConfig c = StationConfig::from_json(doc, "s.json");
  EXPECT_NEAR(c.table.inner_axis.norm(), 1.0, 1e-15);
  EXPECT_NEAR(c.table.inner_axis.x(), std::sqrt(0.5), 1e-15);
  doc["table"]["inner_axis"] = {0, 0, 0.998};  // off by 2e-3: not meant as a unit vector
  try {
    StationConfig::from_json(doc, "s.json");
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("s.json: table.inner_axis"), std::string::npos)
        << e.what();
  }
}

TEST(StationConfig, ListsEverySchemaViolationWithItsPath) {
  json doc = minimal_station();
  doc["site"]["latitude_deg"] = 95.0;             // above the maximum 90
  doc["table"]["outer"].erase("max_accel_dps2");  // required
  doc["imus"][0]["backend"] = "telepathy";        // not an allowed backend
  doc["chamber"]["max_ramp"] = 2;                 // unknown key
  try {
    StationConfig::from_json(doc, "bad.json");
    FAIL() << "expected a SchemaError";
  } catch (const SchemaError& e) {
    const std::string text = e.what();
    EXPECT_GE(e.violations().size(), 4u) << text;
    EXPECT_NE(text.find("site.latitude_deg"), std::string::npos) << text;
    EXPECT_NE(text.find("table.outer"), std::string::npos) << text;
    EXPECT_NE(text.find("max_accel_dps2"), std::string::npos) << text;
    EXPECT_NE(text.find("imus[0].backend"), std::string::npos) << text;
    EXPECT_NE(text.find("max_ramp"), std::string::npos) << text;
    EXPECT_NE(text.find("bad.json"), std::string::npos) << text;
  }
}

TEST(StationConfig, RejectsRulesTheSchemaCannotState) {
  json doc = minimal_station();
  doc["chamber"]["min_c"] = 90;
  EXPECT_THROW(
      {
        try {
          StationConfig::from_json(doc, "s.json");
        } catch (const InputError& e) {
          EXPECT_NE(std::string(e.what()).find("chamber.min_c"), std::string::npos) << e.what();
          throw;
        }
      },
      InputError);

  doc = minimal_station();
  doc["table"]["inner_axis"] = {0, 1, 0};  // parallel to the outer axis
  EXPECT_THROW(StationConfig::from_json(doc, "s.json"), InputError);

  doc = minimal_station();
  doc["table"]["outer_axis"] = {0, 0.5, 0};  // not a unit vector
  EXPECT_THROW(StationConfig::from_json(doc, "s.json"), InputError);

  doc = minimal_station();
  doc["imus"].push_back(doc["imus"][0]);  // duplicate name
  EXPECT_THROW(StationConfig::from_json(doc, "s.json"), InputError);

  doc = minimal_station();
  doc["imus"][0]["truth_file"] = "x.json";  // two truth sources: oneOf fails
  EXPECT_THROW(StationConfig::from_json(doc, "s.json"), SchemaError);
}

TEST(StationConfig, ResolvesPathsAgainstTheStationFile) {
  const auto dir = std::filesystem::temp_directory_path() / "calstand_station_config_test";
  std::filesystem::create_directories(dir);
  json doc = minimal_station();
  doc["imus"][0].erase("model");
  doc["imus"][0]["truth_file"] = "truths/dut.json";
  const auto path = dir / "station.json";
  std::ofstream(path) << doc.dump();
  const StationConfig c = StationConfig::load(path.string());
  EXPECT_EQ(c.imus[0].truth_file, (dir / "truths/dut.json").lexically_normal().string());
  std::filesystem::remove_all(dir);
}

TEST(StationConfig, GeometryCarriesTheMount) {
  json doc = minimal_station();
  doc["imus"][0]["mount_rpy_deg"] = {180, 0, 0};
  const StationConfig c = StationConfig::from_json(doc, "s.json");
  const Eigen::Matrix3d C_LB = c.geometry(0).body_to_level(0.0, 0.0);
  EXPECT_NEAR(C_LB(2, 2), -1.0, 1e-12);  // body z points down
}

}  // namespace
}  // namespace calstand::core

namespace calstand::core {
namespace {

TEST(StationConfig, FaultPolicyDefaultsAndRoundTrips) {
  json doc = minimal_station();
  StationConfig c = StationConfig::from_json(doc, "p.json");
  EXPECT_EQ(c.policy.on_sequence_gap, "record");
  EXPECT_EQ(c.policy.on_stale_stream, "repeat_capture");
  doc["policy"] = {
      {"on_sequence_gap", "abort"}, {"stale_after_s", 0.5}, {"max_capture_attempts", 5}};
  c = StationConfig::from_json(doc, "p.json");
  EXPECT_EQ(c.policy.on_sequence_gap, "abort");
  EXPECT_DOUBLE_EQ(c.policy.stale_after_s, 0.5);
  EXPECT_EQ(c.policy.max_capture_attempts, 5);
  EXPECT_EQ(StationConfig::from_json(c.to_json(), "q.json").to_json(), c.to_json());
  doc["policy"]["on_sequence_gap"] = "ignore";
  EXPECT_THROW(StationConfig::from_json(doc, "p.json"), SchemaError);
}

}  // namespace
}  // namespace calstand::core

namespace calstand::core {
namespace {

/// minimal_station() on real backends (acutrol over TCP, an F4T over Modbus TCP, a serial IMU).
json real_station() {
  json doc = minimal_station();
  doc["table"]["backend"] = "acutrol";
  doc["table"]["connection"] = {{"transport", "tcp"}, {"host", "10.0.0.5"}, {"port", 5025}};
  doc["chamber"]["backend"] = "modbus";
  doc["chamber"]["connection"] = {
      {"transport", "tcp"}, {"host", "10.0.0.6"}, {"map", "watlow-f4t"}};
  doc["imus"][0] = {{"name", "dut"},
                    {"backend", "serial"},
                    {"connection", {{"path", "/dev/ttyUSB0"}, {"sample_rate_hz", 400}}}};
  return doc;
}

/// The schema error's lines ("s.json: PATH: MESSAGE"), or "" when the station loads.
std::string station_error(const json& doc) {
  try {
    StationConfig::from_json(doc, "s.json");
  } catch (const SchemaError& e) {
    return e.what();
  }
  return "";
}

TEST(StationConfig, ConnectionsAreCheckedByTheSchemaNamingFileAndPath) {
  EXPECT_EQ(station_error(real_station()), "");

  json doc = real_station();
  doc["table"]["connection"]["port"] = 70000;
  EXPECT_NE(station_error(doc).find("s.json: table.connection.port: 70000 is greater than the "
                                    "maximum 65535"),
            std::string::npos)
      << station_error(doc);

  doc = real_station();
  doc["table"]["connection"]["transport"] = "udp";
  EXPECT_NE(station_error(doc).find("table.connection.transport: \"udp\" is not one of \"tcp\", "
                                    "\"serial\""),
            std::string::npos)
      << station_error(doc);

  doc = real_station();
  doc["chamber"]["connection"]["baud"] = 9600;  // a field of transport rtu
  EXPECT_NE(station_error(doc).find("chamber.connection: unknown property \"baud\""),
            std::string::npos)
      << station_error(doc);

  doc = real_station();
  doc["chamber"]["connection"]["map"] = {{"process_value", {{"address", 1}, {"encoding", "int16"}}},
                                         {"setpoint", {{"address", 70000}, {"encoding", "int16"}}}};
  EXPECT_NE(station_error(doc).find("chamber.connection.map.setpoint.address: 70000 is greater "
                                    "than the maximum 65535"),
            std::string::npos)
      << station_error(doc);

  doc = real_station();
  doc["imus"][0]["connection"]["baud"] = 12345;
  EXPECT_NE(station_error(doc).find("imus[0].connection.baud: 12345 is not one of"),
            std::string::npos)
      << station_error(doc);

  doc = real_station();
  doc["imus"][0]["backend"] = "socketcan";
  doc["imus"][0]["connection"] = {
      {"interface", "can0"}, {"sample_rate_hz", 200}, {"map", json::object()}};
  EXPECT_NE(station_error(doc).find("imus[0].connection.map: missing required property "
                                    "\"signals\""),
            std::string::npos)
      << station_error(doc);

  // A simulated device runs in process: a connection there is a mistake, not ignored.
  doc = minimal_station();
  doc["chamber"]["connection"] = {{"transport", "tcp"}};
  EXPECT_NE(station_error(doc).find("s.json: chamber.connection: matches a form that is not "
                                    "allowed"),
            std::string::npos)
      << station_error(doc);
}

}  // namespace
}  // namespace calstand::core
