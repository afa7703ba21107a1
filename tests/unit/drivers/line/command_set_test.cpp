#include "drivers/command_set.hpp"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "core/error.hpp"
#include "drivers/command_set_backends.hpp"

namespace calstand::drivers::line {
namespace {

using nlohmann::json;

json minimal_chamber() {
  return json::parse(R"({
    "format": "calstand-command-set/1", "name": "test-chamber", "device": "chamber",
    "source": "a test",
    "errors": [{"pattern": "^NA:(.*)$", "text_group": 1}],
    "operations": {
      "read_air": {"command": "TEMP?", "reply": "^([-0-9.]+),([-0-9.]+)$",
                   "fields": {"air_c": 1, "setpoint_c": 2}},
      "set_setpoint": {"command": "TEMP,S{setpoint_c:.1f}", "reply": "^OK:.*$"},
      "standby": {"command": "MODE,STANDBY", "reply": "^OK:.*$"}
    }})");
}

std::string error_of(const json& doc) {
  try {
    parse_command_set(doc, "set.json");
  } catch (const core::InputError& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(CommandSet, EveryBuiltInSetParsesAndIsListedUnderItsDevice) {
  const auto tables = builtin_command_set_names(DeviceKind::kTable);
  ASSERT_FALSE(tables.empty());
  for (const auto& name : tables) {
    const auto set = builtin_command_set(name);
    ASSERT_TRUE(set.has_value()) << name;
    EXPECT_EQ(set->device, DeviceKind::kTable);
    EXPECT_FALSE(set->source.empty()) << name;
  }
  for (const auto& name : builtin_command_set_names(DeviceKind::kChamber)) {
    EXPECT_EQ(builtin_command_set(name)->device, DeviceKind::kChamber) << name;
  }
}

TEST(CommandSet, AMissingRequiredOperationIsNamed) {
  json doc = minimal_chamber();
  EXPECT_EQ(error_of(doc), "(accepted)");
  doc["operations"].erase("standby");
  EXPECT_NE(error_of(doc).find("needs \"standby\""), std::string::npos) << error_of(doc);
}

TEST(CommandSet, AFieldBeyondThePatternsGroupsIsNamedWithItsPath) {
  json doc = minimal_chamber();
  doc["operations"]["read_air"]["fields"]["air_c"] = 3;
  const std::string e = error_of(doc);
  EXPECT_NE(e.find("operations.read_air.fields.air_c"), std::string::npos) << e;
  EXPECT_NE(e.find("2 groups"), std::string::npos) << e;
}

TEST(CommandSet, ABadPatternAnUnknownArgumentAndATableOperationOnAChamberAreRefused) {
  json bad_regex = minimal_chamber();
  bad_regex["operations"]["read_air"]["reply"] = "^([0-9]+$";
  EXPECT_NE(error_of(bad_regex).find("operations.read_air.reply: not a regular expression"),
            std::string::npos)
      << error_of(bad_regex);
  json typo = minimal_chamber();
  typo["operations"]["set_setpoint"]["command"] = "TEMP,S{setpoint:.1f}";
  EXPECT_NE(error_of(typo).find("operations.set_setpoint.command"), std::string::npos)
      << error_of(typo);
  json table_op = minimal_chamber();
  table_op["operations"]["position"] = {{"command", "P"}};
  EXPECT_NE(error_of(table_op).find("not an operation of a chamber"), std::string::npos)
      << error_of(table_op);
  json schema = minimal_chamber();
  schema["line"] = {{"timeout_ms", "soon"}};
  EXPECT_NE(error_of(schema).find("line"), std::string::npos) << error_of(schema);
}

TEST(CommandSet, StringsAreLatin1Bytes) {
  EXPECT_EQ(latin1_of("1\u00b611004", "x"), std::string("1\xb6"
                                                        "11004"));
  EXPECT_THROW(latin1_of("\u2013", "x"), core::InputError);
}

TEST(CommandSet, RendersTemplatesWithNamedNumbersAndTexts) {
  Arguments a;
  a.numbers["angle_deg"] = -12.5;
  a.texts["axis"] = "2";
  EXPECT_EQ(render(":D:P {axis},{angle_deg:.4f}", a, "op"), ":D:P 2,-12.5000");
  EXPECT_THROW(render("{rate_dps}", a, "op"), core::InputError);
}

TEST(CommandSet, ReadsNumbersBitsMapsAndOptionalGroupsFromAReply) {
  const auto set = builtin_command_set("acutrol-style");
  ASSERT_TRUE(set);
  const Step& status = set->find("read_status")->steps.at(0);
  auto r = parse_reply(status, "FAULT,0,OPEN,interlock open: door");
  ASSERT_TRUE(r.error.empty()) << r.error;
  EXPECT_EQ(r.fields["mode"].text, "fault");
  EXPECT_EQ(r.fields["in_position"].truth, false);
  EXPECT_EQ(r.fields["fault"].truth, true);
  EXPECT_EQ(r.fields["fault_text"].text, "interlock open: door");
  r = parse_reply(status, "RATE,1,CLOSED");
  ASSERT_TRUE(r.error.empty()) << r.error;
  EXPECT_EQ(r.fields["fault"].truth, false);
  EXPECT_EQ(r.fields["in_position"].truth, true);
  EXPECT_FALSE(parse_reply(status, "SPIN,1,CLOSED").error.empty());
  const Step& pos = set->find("read_position")->steps.at(0);
  r = parse_reply(pos, "-90.250000");
  EXPECT_DOUBLE_EQ(*r.fields["angle_deg"].number, -90.25);
  EXPECT_NE(parse_reply(pos, "n/a").error.find("is not"), std::string::npos);
}

TEST(CommandSet, ErrorRepliesGiveTheControllersWords) {
  const CommandSet set = parse_command_set(minimal_chamber(), "set.json");
  EXPECT_EQ(match_error(set, "NA:DATA OUT OF RANGE"), "DATA OUT OF RANGE");
  EXPECT_FALSE(match_error(set, "OK:TEMP,S25.0"));
}

TEST(CommandSet, AnUnknownBuiltInNameListsTheKnownOnes) {
  try {
    load_command_set("nosuch", "", DeviceKind::kTable, "table.command_set");
    FAIL() << "accepted";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("acutrol-style"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("table.command_set"), std::string::npos) << e.what();
  }
  EXPECT_THROW(load_command_set("acutrol-style", "", DeviceKind::kChamber, "chamber.command_set"),
               core::InputError);
}

}  // namespace
}  // namespace calstand::drivers::line

namespace calstand::drivers::line {
namespace {

TEST(CommandSetBackends, AStationNamesASetByItsBackendOrByCommandSet) {
  EXPECT_EQ(station_naming("espec", DeviceKind::kChamber).backend, "espec");
  EXPECT_EQ(station_naming("espec", DeviceKind::kChamber).command_set, "");
  EXPECT_EQ(station_naming("acutrol3000", DeviceKind::kTable).backend, "acutrol");
  EXPECT_EQ(station_naming("acutrol3000", DeviceKind::kTable).command_set, "acutrol3000");
  EXPECT_EQ(station_naming("/lab/our-table.json", DeviceKind::kTable).backend, "line");
  core::TableConfig table;
  table.backend = "acutrol";
  EXPECT_FALSE(station_command_set(table).has_value());  // today's ACUTROL-style driver
  table.command_set = "acutrol-style";
  ASSERT_TRUE(station_command_set(table).has_value());
  EXPECT_EQ(station_command_set(table)->name, "acutrol-style");
  core::ChamberConfig chamber;
  chamber.backend = "modbus";
  EXPECT_FALSE(station_command_set(chamber).has_value());
  chamber.backend = "line";
  chamber.command_set = "acutrol-style";  // a table's set for a chamber
  EXPECT_THROW(station_command_set(chamber), core::InputError);
}

}  // namespace
}  // namespace calstand::drivers::line
