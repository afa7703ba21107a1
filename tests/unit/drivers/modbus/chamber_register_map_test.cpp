#include "drivers/chamber_register_map.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "../schema_error_field.hpp"
#include "core/error.hpp"

namespace calstand::drivers {
namespace {

using nlohmann::json;

RegisterField tenths() { return {100, RegisterKind::kHolding, RegisterEncoding::kInt16, 0.1, {}}; }

TEST(ChamberRegisterMap, Int16TenthsRoundTripIncludingNegativeTemperatures) {
  const auto f = tenths();
  const auto hot = encode_value(f, 60.0);
  ASSERT_TRUE(hot);
  EXPECT_EQ(hot->count, 1);
  EXPECT_EQ(hot->words[0], 600);
  const auto cold = encode_value(f, -40.5);
  ASSERT_TRUE(cold);
  EXPECT_EQ(cold->words[0], 0xFE6B);  // -405 in two's complement
  EXPECT_DOUBLE_EQ(decode_value(f, cold->span()), -40.5);
  // Rounded to the nearest tenth, not truncated.
  EXPECT_EQ(encode_value(f, 23.46)->words[0], 235);
  EXPECT_EQ(encode_value(f, -0.04)->words[0], 0);
}

TEST(ChamberRegisterMap, IntegerEncodingsRefuseWhatTheyCannotHold) {
  auto f = tenths();
  EXPECT_FALSE(encode_value(f, 3276.8));
  EXPECT_FALSE(encode_value(f, -3276.9));
  EXPECT_TRUE(encode_value(f, 3276.7));
  EXPECT_FALSE(encode_value(f, std::nan("")));
  f.encoding = RegisterEncoding::kUint16;
  EXPECT_FALSE(encode_value(f, -0.1));
  EXPECT_EQ(encode_value(f, 6553.5)->words[0], 65535);
  EXPECT_DOUBLE_EQ(decode_value(f, std::array<std::uint16_t, 1>{65535}), 6553.5);
}

TEST(ChamberRegisterMap, Float32WordOrders) {
  RegisterField f{2782, RegisterKind::kHolding, RegisterEncoding::kFloat32, 1.0,
                  WordOrder::kHighFirst};
  // 60.0f is 0x42700000; -40.25f is 0xC2210000.
  auto w = encode_value(f, 60.0);
  ASSERT_TRUE(w);
  EXPECT_EQ(w->count, 2);
  EXPECT_EQ(w->words[0], 0x4270);
  EXPECT_EQ(w->words[1], 0x0000);
  EXPECT_DOUBLE_EQ(decode_value(f, w->span()), 60.0);
  f.word_order = WordOrder::kLowFirst;
  w = encode_value(f, -40.25);
  EXPECT_EQ(w->words[0], 0x0000);
  EXPECT_EQ(w->words[1], 0xC221);
  EXPECT_DOUBLE_EQ(decode_value(f, w->span()), -40.25);
  // The same words read with the other order are a different number: the order matters.
  f.word_order = WordOrder::kHighFirst;
  EXPECT_NE(decode_value(f, w->span()), -40.25);
  EXPECT_TRUE(std::isnan(decode_value(f, std::array<std::uint16_t, 2>{0x7FC0, 0x0000})));
  EXPECT_TRUE(std::isnan(decode_value(f, std::array<std::uint16_t, 1>{0x4270})));  // too short
}

TEST(ChamberRegisterMap, BuiltInMaps) {
  const auto f4 = watlow_f4_map();
  EXPECT_EQ(f4.process_value.address, 100);
  EXPECT_EQ(f4.setpoint.address, 300);
  EXPECT_EQ(f4.process_value.encoding, RegisterEncoding::kInt16);
  EXPECT_DOUBLE_EQ(f4.setpoint.scale, 0.1);
  EXPECT_FALSE(f4.mode);
  EXPECT_FALSE(f4.ramp_rate);
  EXPECT_NO_THROW(f4.validate("map"));

  const auto f4t = watlow_f4t_map(WordOrder::kLowFirst);
  EXPECT_EQ(f4t.process_value.address, 2820);
  EXPECT_EQ(f4t.setpoint.address, 2782);
  ASSERT_TRUE(f4t.mode);
  EXPECT_EQ(f4t.mode->address, 2730);
  EXPECT_EQ(f4t.mode->control, 10);
  EXPECT_EQ(f4t.mode->standby, 62);
  EXPECT_EQ(f4t.setpoint.word_order, WordOrder::kLowFirst);
  EXPECT_FALSE(f4t.ramp_rate);
  EXPECT_NO_THROW(f4t.validate("map"));

  EXPECT_EQ(
      register_map_from_json("watlow-f4t", "m", WordOrder::kLowFirst).process_value.word_order,
      WordOrder::kLowFirst);
}

// CSZ EZT-570i/S loop 1 as its User Communication Reference Manual (section 2.4) lists it.
TEST(ChamberRegisterMap, CszEzt570BuiltInMap) {
  const auto csz = register_map_from_json("csz-ezt570", "m", WordOrder::kHighFirst);
  EXPECT_EQ(csz.name, "csz-ezt570");
  EXPECT_EQ(csz.setpoint.address, 60);
  EXPECT_EQ(csz.process_value.address, 61);
  EXPECT_EQ(csz.process_value.encoding, RegisterEncoding::kInt16);
  EXPECT_DOUBLE_EQ(csz.process_value.scale, 0.1);
  ASSERT_TRUE(csz.mode);
  EXPECT_EQ(csz.mode->address, 22);
  EXPECT_EQ(csz.mode->control, 1);
  EXPECT_EQ(csz.mode->standby, 0);
  EXPECT_FALSE(csz.ramp_rate) << "constant mode has no ramp register: the driver steps";
  ASSERT_EQ(csz.alarms.size(), 4u);
  EXPECT_EQ(csz.alarms[2].address, 57);
  EXPECT_NO_THROW(csz.validate("map"));
  EXPECT_NEAR(decode_value(csz.process_value, std::vector<std::uint16_t>{0xFF9C}), -10.0, 1e-12);
}

TEST(ChamberRegisterMap, UnknownBuiltInMapIsRefusedWithTheNames) {
  try {
    register_map_from_json("csz-ezt999", "chamber.connection.map", WordOrder::kHighFirst);
    FAIL() << "accepted an unknown map";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("chamber.connection.map"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(builtin_map("csz-ezt999"));
  EXPECT_NE(builtin_map_names().find("csz-ezt570"), std::string::npos);
}

json generic_map() {
  return json::parse(R"({
    "name": "eurotherm-ish",
    "process_value": {"address": 1, "kind": "input", "encoding": "int16", "scale": 0.1},
    "setpoint": {"address": 2, "encoding": "float32"},
    "mode": {"address": 10, "control": 1, "standby": 0},
    "ramp_rate": {"address": 20, "encoding": "uint16", "scale": 0.01},
    "sensor_fault_raw": [-32768, 32767]
  })");
}

TEST(ChamberRegisterMap, GenericMapFromJson) {
  const auto m =
      register_map_from_json(generic_map(), "chamber.connection.map", WordOrder::kLowFirst);
  EXPECT_EQ(m.name, "eurotherm-ish");
  EXPECT_EQ(m.process_value.kind, RegisterKind::kInput);
  EXPECT_EQ(m.setpoint.encoding, RegisterEncoding::kFloat32);
  EXPECT_EQ(m.setpoint.word_order, WordOrder::kLowFirst);
  ASSERT_TRUE(m.ramp_rate);
  EXPECT_DOUBLE_EQ(m.ramp_rate->scale, 0.01);
  ASSERT_TRUE(m.mode);
  EXPECT_EQ(m.mode->standby, 0);
  EXPECT_EQ(m.sensor_fault_raw, (std::vector<std::uint16_t>{0x8000, 0x7FFF}));
  EXPECT_TRUE(m.alarms.empty());

  auto with_alarms = generic_map();
  with_alarms["alarms"] = json::parse(R"([{"address": 30, "name": "chamber"}, {"address": 31}])");
  const auto a = register_map_from_json(with_alarms, "m", WordOrder::kHighFirst);
  ASSERT_EQ(a.alarms.size(), 2u);
  EXPECT_EQ(a.alarms[0].name, "chamber");
  EXPECT_EQ(a.alarms[1].address, 31);
  // An alarm word on the mode register would read the mode as an alarm.
  with_alarms["alarms"] = json::parse(R"([{"address": 10}])");
  EXPECT_THROW(register_map_from_json(with_alarms, "m", WordOrder::kHighFirst), core::InputError);
}

/// The InputError's `where` for `doc`, or "" when it parses.
std::string error_where(const json& doc) {
  try {
    register_map_from_json(doc, "chamber.connection.map", WordOrder::kHighFirst);
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("chamber.connection.map"), std::string::npos) << e.what();
    return test::error_field(e);
  }
  return "";
}

TEST(ChamberRegisterMap, GenericMapErrorsNameTheField) {
  const std::string at = "chamber.connection.map";
  auto doc = generic_map();
  doc["setpoint"]["address"] = 70000;
  EXPECT_EQ(error_where(doc), at + ".setpoint.address");
  doc = generic_map();
  doc["setpoint"]["address"] = "2";
  EXPECT_EQ(error_where(doc), at + ".setpoint.address");
  doc = generic_map();
  doc["setpoint"].erase("address");
  EXPECT_EQ(error_where(doc), at + ".setpoint.address");
  doc = generic_map();
  doc["setpoint"]["kind"] = "input";  // the driver writes it
  EXPECT_EQ(error_where(doc), at + ".setpoint.kind");
  doc = generic_map();
  doc["process_value"]["encoding"] = "int32";
  EXPECT_EQ(error_where(doc), at + ".process_value.encoding");
  doc = generic_map();
  doc["process_value"]["scale"] = 0;
  EXPECT_EQ(error_where(doc), at + ".process_value.scale");
  doc = generic_map();
  doc["setpoint"]["scale"] = 0.1;  // float32 has no scale
  EXPECT_EQ(error_where(doc), at + ".setpoint.scale");
  doc = generic_map();
  doc["mode"]["standby"] = 1;  // same as control
  EXPECT_EQ(error_where(doc), at + ".mode.standby");
  doc = generic_map();
  doc["mode"].erase("control");
  EXPECT_EQ(error_where(doc), at + ".mode.control");
  doc = generic_map();
  doc["setpoint"]["adress"] = 2;  // misspelt
  EXPECT_EQ(error_where(doc), at + ".setpoint.adress");
  doc = generic_map();
  doc.erase("process_value");
  EXPECT_EQ(error_where(doc), at + ".process_value");
  doc = generic_map();
  doc["sensor_fault_raw"][1] = 70000;
  EXPECT_EQ(error_where(doc), at + ".sensor_fault_raw[1]");
  // Beyond INT64_MAX: once read as a wrapped negative (2^64 - 1 taken for -1, i.e. 0xFFFF).
  doc = generic_map();
  doc["sensor_fault_raw"][1] = json::parse("18446744073709551615");
  EXPECT_EQ(error_where(doc), at + ".sensor_fault_raw[1]");
  doc = generic_map();
  doc["sensor_fault_raw"][0] = json::parse("18446744073709518848");  // 2^64 - 32768
  EXPECT_EQ(error_where(doc), at + ".sensor_fault_raw[0]");
  doc = generic_map();
  doc["sensor_fault_raw"][0] = json::parse("65535");
  EXPECT_EQ(error_where(doc), "");
  doc = generic_map();
  doc["ramp_rate"]["address"] = 2;  // inside the setpoint's two registers
  EXPECT_EQ(error_where(doc), at + ".ramp_rate.address");
  EXPECT_EQ(error_where("watlow-f5"), at);
  EXPECT_EQ(error_where(42), at);
}

TEST(ChamberRegisterMap, WordOrderParse) {
  EXPECT_EQ(word_order_from_json("low_first", "w"), WordOrder::kLowFirst);
  EXPECT_EQ(word_order_from_json("high_first", "w"), WordOrder::kHighFirst);
  EXPECT_THROW(word_order_from_json("big", "w"), core::InputError);
}

}  // namespace
}  // namespace calstand::drivers
