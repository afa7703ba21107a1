// The DBC parser (drivers/dbc_file.hpp), DBC + station names -> CanSignalMap, the two shipped
// examples end to end through the assembler, and an independent peer (dbc_peer.py) that packs
// frames from the DBC convention.
#include "drivers/dbc_file.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <thread>

#include "../child_process.hpp"
#include "core/error.hpp"
#include "core/station_config.hpp"
#include "drivers/can_imu.hpp"
#include "drivers/can_sample_assembler.hpp"
#include "drivers/can_signal_map.hpp"
#include "drivers/socketpair_can.hpp"

namespace calstand::drivers {
namespace {

using nlohmann::json;

std::string dbc_test_source(const std::string& rel) {
  return std::string(CALSTAND_SOURCE_DIR) + "/" + rel;
}

/// The error message of `f`, or "" when it does not throw core::InputError.
template <typename F>
std::string dbc_test_error(F&& f) {
  try {
    f();
  } catch (const core::InputError& e) {
    return e.what();
  }
  return "";
}

/// A file in the test's temporary folder, removed at the end.
/// A file in the temporary folder, named per process: ctest runs each test as a process of its
/// own, two at a time, and two tests writing one path would read each other's files.
struct DbcTestFile {
  explicit DbcTestFile(const std::string& name, const std::string& text)
      : path((std::filesystem::temp_directory_path() / (std::to_string(::getpid()) + "-" + name))
                 .string()) {
    std::ofstream(path) << text;
  }
  ~DbcTestFile() { std::remove(path.c_str()); }
  std::string path;
};

constexpr const char* kDbcEveryConstruct = R"(VERSION "1.2"

NS_ :
	NS_DESC_
	CM_
	BA_DEF_
	BA_
	VAL_
	BS_
	SIG_VALTYPE_

BS_: 500 : 12,34
BU_: IMU Station Logger

VAL_TABLE_ OnOff 1 "on" 0 "off" ;

BO_ 256 RATES: 8 IMU
 SG_ RateX : 0|16@1- (0.01,0) [-327.68|327.67] "deg/s" Station,Logger
 SG_ RateY : 23|16@0- (0.01,0) [-327.68|327.67] "deg/s" Station
 SG_ Temp : 32|8@1+ (1,-40) [-40|215] "degC"  Station
 SG_ Float : 39|32@0- (1,0) [0|0] "m/s^2" Station

BO_ 2566844926 EXT: 8 IMU
 SG_ Mode M : 0|8@1+ (1,0) [0|255] "" Station
 SG_ A m0 : 8|16@1- (1,0) [0|0] "" Station
 SG_ B m1 : 8|16@1- (1e-3,0.5) [0|0] "g" Station

BO_TX_BU_ 256 : IMU,Logger;
CM_ "network comment";
CM_ BU_ IMU "the IMU";
CM_ BO_ 256 "rates
over two lines";
CM_ SG_ 256 RateX "x rate";
BA_DEF_ BO_ "GenMsgCycleTime" INT 0 65535;
BA_DEF_ SG_ "GenSigStartValue" FLOAT -1e9 1e9;
BA_DEF_DEF_ "GenMsgCycleTime" 10;
BA_ "GenMsgCycleTime" BO_ 256 10;
VAL_ 256 Temp 255 "sensor missing" 254 "sensor fault" ;
VAL_ 2566844926 Mode 0 "A" 1 "B";
SIG_VALTYPE_ 256 Float : 1;
)";

TEST(DbcFileTest, ParsesEveryConstruct) {
  const DbcFile f = DbcFile::parse(kDbcEveryConstruct, "t.dbc");
  EXPECT_EQ(f.version, "1.2");
  EXPECT_EQ(f.nodes, (std::vector<std::string>{"IMU", "Station", "Logger"}));
  ASSERT_EQ(f.messages.size(), 2u);
  const DbcMessage& rates = f.messages[0];
  EXPECT_EQ(rates.id, 256u);
  EXPECT_EQ(rates.name, "RATES");
  EXPECT_EQ(rates.dlc, 8u);
  EXPECT_EQ(rates.sender, "IMU");
  EXPECT_EQ(rates.comment, "rates\nover two lines");
  EXPECT_EQ(rates.line, 17u);
  ASSERT_EQ(rates.signals.size(), 4u);
  const DbcSignal& x = rates.signals[0];
  EXPECT_EQ(x.name, "RateX");
  EXPECT_TRUE(x.little_endian);
  EXPECT_TRUE(x.is_signed);
  EXPECT_EQ(x.start_bit, 0u);
  EXPECT_EQ(x.length_bits, 16u);
  EXPECT_DOUBLE_EQ(x.factor, 0.01);
  EXPECT_DOUBLE_EQ(x.minimum, -327.68);
  EXPECT_DOUBLE_EQ(x.maximum, 327.67);
  EXPECT_EQ(x.unit, "deg/s");
  EXPECT_EQ(x.receivers, (std::vector<std::string>{"Station", "Logger"}));
  EXPECT_EQ(x.comment, "x rate");
  EXPECT_EQ(x.line, 18u);
  EXPECT_FALSE(rates.signals[1].little_endian);
  const DbcSignal& temp = *rates.signal("Temp");
  EXPECT_FALSE(temp.is_signed);
  EXPECT_DOUBLE_EQ(temp.offset, -40.0);
  EXPECT_EQ(temp.values.at(254), "sensor fault");
  EXPECT_EQ(rates.signal("Float")->value_type, DbcSignal::ValueType::kFloat32);
  EXPECT_EQ(rates.signal("Float")->field().type, FieldType::kFloat);

  const DbcMessage& ext = f.messages[1];
  EXPECT_EQ(ext.id, (2566844926u & CAN_EFF_MASK) | CAN_EFF_FLAG);  // bit 31: extended
  ASSERT_NE(ext.multiplexer(), nullptr);
  EXPECT_EQ(ext.multiplexer()->name, "Mode");
  EXPECT_EQ(ext.signal("B")->mux, DbcSignal::Mux::kMultiplexed);
  EXPECT_EQ(ext.signal("B")->mux_value, 1u);
  EXPECT_DOUBLE_EQ(ext.signal("B")->factor, 1e-3);
  EXPECT_EQ(f.message("EXT"), &ext);
  EXPECT_EQ(f.message("NONE"), nullptr);
}

TEST(DbcFileTest, IndependentSignalsAndByteOrderMarksAreTolerated) {
  const DbcFile f = DbcFile::parse(
      "\xEF\xBB\xBF"
      R"(BU_: A
BO_ 1 M: 8 A
 SG_ S : 0|8@1+ (1,0) [0|0] "" A
BO_ 3221225472 VECTOR__INDEPENDENT_SIG_MSG: 0 Vector__XXX
 SG_ Loose : 40|16@1+ (1,0) [0|0] "" Vector__XXX
CM_ SG_ 3221225472 Loose "belongs to no message";
VAL_ 3221225472 Loose 0 "zero" ;
)",
      "i.dbc");
  ASSERT_EQ(f.messages.size(), 1u);
  EXPECT_EQ(f.messages[0].name, "M");
}

// The DBC's Motorola convention: the start bit is the most significant bit, numbered
// sawtooth (bit k of byte b is 8b + k). "7|16@0+" is bytes 0..1 big-endian; "3|12@0+" is the
// low nibble of byte 0 (most significant) followed by all of byte 1.
TEST(DbcFileTest, MotorolaStartBitsFollowTheSawtooth) {
  const DbcFile f = DbcFile::parse(R"(BU_: A
BO_ 1 M: 8 A
 SG_ Word : 7|16@0+ (1,0) [0|0] "" A
 SG_ Nibbles : 19|12@0+ (1,0) [0|0] "" A
 SG_ Signed : 47|16@0- (1,0) [0|0] "" A
)",
                                   "m.dbc");
  const DbcMessage& m = f.messages[0];
  EXPECT_EQ(m.signal("Word")->field().start_bit, 0u);      // stream position of byte 0 bit 7
  EXPECT_EQ(m.signal("Nibbles")->field().start_bit, 20u);  // byte 2 bit 3 -> 16 + 4
  const std::array<std::uint8_t, 8> data{0x12, 0x34, 0xA5, 0x6B, 0x00, 0xFF, 0xFE, 0x00};
  const std::span<const std::uint8_t, 8> payload(data);
  EXPECT_EQ(m.signal("Word")->field().extract_raw(payload), 0x1234u);
  EXPECT_EQ(m.signal("Nibbles")->field().extract_raw(payload), 0x56Bu);  // 0xA5 & 0x0F, 0x6B
  EXPECT_EQ(m.signal("Signed")->field().decode(payload), -2.0);          // 0xFFFE
}

TEST(DbcFileTest, RefusesByNameWithFileAndLine) {
  const std::string head = "BU_: A\nBO_ 1 M: 8 A\n SG_ S : 0|8@1+ (1,0) [0|0] \"\" A\n";
  auto err = [&](const std::string& tail) {
    return dbc_test_error([&] { DbcFile::parse(head + tail, "x.dbc"); });
  };
  EXPECT_EQ(err("SG_MUL_VAL_ 1 S M 0-1;\n"),
            "x.dbc:4: extended multiplexing (SG_MUL_VAL_) is not supported: only one `M` switch "
            "per message with `mN` signals");
  EXPECT_EQ(err("BO_ 2 FD: 64 A\n"),
            "x.dbc:4: message FD: length 64 bytes is CAN FD (more than 8 bytes), which is not "
            "supported: classic CAN frames only");
  EXPECT_EQ(err("BO_ 2 N: 8 A\n SG_ T m1M : 0|8@1+ (1,0) [0|0] \"\" A\n"),
            "x.dbc:5: signal T: extended multiplexing (m1M: a multiplexed multiplexer) is not "
            "supported");
  EXPECT_EQ(err("FOO_ 1;\n"), "x.dbc:4: unknown keyword FOO_");
  EXPECT_EQ(err("BO_ 2 N: 2 A\n SG_ T : 8|16@1+ (1,0) [0|0] \"\" A\n"),
            "x.dbc:5: signal T: needs 3 bytes but message N has 2");
  EXPECT_EQ(err("BO_ 2 N: 8 A\n SG_ T : 0|8@1* (1,0) [0|0] \"\" A\n"),
            "x.dbc:5: expected the sign '+' or '-', found '*'");
  EXPECT_EQ(err("BO_ 2 N: 8 A\n SG_ T : 60|8@1+ (1,0) [0|0] \"\" A\n"),
            "x.dbc:5: signal T: 8 bits from start bit 60 (Intel) run beyond the 64 bits of a "
            "classic CAN frame");
  EXPECT_EQ(err("BO_ 2 N: 8 A\n SG_ T : 0|8@1+ (1,0) [0|0] \"deg/s A\n"),
            "x.dbc:5: unterminated string");
  EXPECT_EQ(err("BO_ 3000 N: 8 A\n"),
            "x.dbc:4: message id 3000 is beyond the 11-bit standard ids (an extended id has bit "
            "31 set: id + 2147483648)");
  EXPECT_EQ(err("VAL_ 1 Q 1 \"x\";\n"), "x.dbc:4: message M has no signal Q");
  EXPECT_EQ(err("BA_DEF_ BO_ \"VFrameFormat\" ENUM \"StandardCAN\",\"ExtendedCAN\",\"r\",\"r\","
                "\"r\",\"r\",\"r\",\"r\",\"r\",\"r\",\"r\",\"r\",\"r\",\"r\",\"StandardCAN_FD\";\n"
                "BA_ \"VFrameFormat\" BO_ 1 14;\n"),
            "x.dbc:5: message M: frame format StandardCAN_FD is CAN FD, which is not supported: "
            "classic CAN frames only");
  EXPECT_EQ(err("SIG_VALTYPE_ 1 S : 1;\n"), "x.dbc:4: signal S: a float is 32 bits, not 8");
  EXPECT_EQ(err("BO_ 2 N: 8 A\n SG_ T m1 : 0|8@1+ (1,0) [0|0] \"\" A\n"),
            "x.dbc:4: message N: mN signals without a multiplexer switch (M)");
  EXPECT_EQ(err("BO_ 1 N: 8 A\n"), "x.dbc:4: message id of N used twice");
  EXPECT_EQ(dbc_test_error([] { DbcFile::load("/nonexistent/a.dbc"); }),
            "/nonexistent/a.dbc: cannot read the DBC file (No such file or directory)");
}

TEST(DbcFileTest, ShippedExamplesParse) {
  const DbcFile x = DbcFile::load(dbc_test_source("sim/can/xsens-mti-600.dbc"));
  EXPECT_EQ(x.messages.size(), 7u);
  EXPECT_EQ(x.message("XCID_RateOfTurn")->id, 0x32u);
  const DbcFile b = DbcFile::load(dbc_test_source("sim/can/bosch-mm5.10.dbc"));
  EXPECT_EQ(b.message("MM5_10_TX3")->id, 0x576u);
}

// --- DBC + names -> CanSignalMap ---------------------------------------------------------

json dbc_test_xsens_connection() {
  std::ifstream in(dbc_test_source("sim/can/xsens-mti-600-station.json"));
  json c = json::parse(in).at("imus").at(0).at("connection");
  c["dbc"] = dbc_test_source("sim/can/xsens-mti-600.dbc");
  return c;
}

json dbc_test_mm5_connection() {
  std::ifstream in(dbc_test_source("sim/can/bosch-mm5.10-station.json"));
  json c = json::parse(in).at("imus").at(0).at("connection");
  c["dbc"] = dbc_test_source("sim/can/bosch-mm5.10.dbc");
  return c;
}

const std::string kDbcWhere = "imus[0].connection";

TEST(DbcSignalMapTest, XsensMapsToFramesOpenedBySampleTime) {
  const CanImuConnection c = CanImuConnection::from_json(dbc_test_xsens_connection(), kDbcWhere);
  const CanSignalMap& map = c.map;
  EXPECT_EQ(map.delimiting, CanSignalMap::Delimiting::kOpeningFrame);
  EXPECT_EQ(map.frames.size(), 5u);  // sample time, counter, rates, accelerations, temperature
  EXPECT_EQ(map.frames[map.opening_frame].id, 0x05u);
  EXPECT_EQ(map.frames[map.sequence_frame].id, 0x06u);
  EXPECT_TRUE(map.has_device_time);
  EXPECT_EQ(map.sequence_wrap(), 65536u);
  EXPECT_EQ(c.sequence_modulus, 65536u);
  // rad/s -> deg/s in the field's scale.
  const auto& rates = map.frames[*map.frame_index(0x32)];
  EXPECT_NEAR(rates.signals[0].second.scale, 0.001953125 * 180.0 / std::numbers::pi, 1e-15);
  EXPECT_EQ(map.ids(), (std::vector<canid_t>{0x01, 0x05, 0x06, 0x11, 0x32, 0x34, 0x51}));
  EXPECT_EQ(map.status.size(), 7u);
}

TEST(DbcSignalMapTest, ErrorsNameTheField) {
  auto err = [](json c) {
    return dbc_test_error([&] { CanImuConnection::from_json(c, kDbcWhere); });
  };
  const std::string file = dbc_test_source("sim/can/xsens-mti-600.dbc");
  json c = dbc_test_xsens_connection();
  c["signals"]["gyro_x"] = "XCID_RateOfTurn.X";
  EXPECT_EQ(err(c),
            "imus[0].connection.signals.gyro_x: no signal \"X\" in message "
            "\"XCID_RateOfTurn\" of " +
                file);
  c = dbc_test_xsens_connection();
  c["signals"]["gyro_x"] = "Nope.gyrX";
  EXPECT_EQ(err(c), "imus[0].connection.signals.gyro_x: no message \"Nope\" in " + file);
  c = dbc_test_xsens_connection();
  c["signals"]["gyro_x"] = "XCID_Acceleration.accX";
  EXPECT_EQ(err(c),
            "imus[0].connection.signals.gyro_x: unit \"m/s^2\" of "
            "XCID_Acceleration.accX is not a unit of gyro_x known here (deg/s, rad/s, "
            "mrad/s, deg/h)");
  c = dbc_test_xsens_connection();
  c["signals"]["counter"] = "XCID_RateOfTurn.gyrX";
  EXPECT_EQ(err(c),
            "imus[0].connection.signals.counter: XCID_RateOfTurn.gyrX is not a counter: "
            "an unsigned integer of at most 32 bits with factor 1 and offset 0");
  c = dbc_test_xsens_connection();
  c["signals"].erase("counter");
  c.erase("sample_start");
  EXPECT_EQ(err(c),
            "imus[0].connection.sample_start: is required without signals.counter: the "
            "message that starts each sample (the device sends it first)");
  c = dbc_test_xsens_connection();
  c["signals"].erase("gyro_z");
  EXPECT_NE(err(c).find("imus[0].connection.signals"), std::string::npos) << err(c);
  c = dbc_test_xsens_connection();
  c["map_file"] = "x.json";
  EXPECT_EQ(err(c), "imus[0].connection.map: give one of map, map_file and dbc, not several");
  c = dbc_test_xsens_connection();
  c["dbc"] = "/nonexistent/x.dbc";
  EXPECT_EQ(err(c),
            "imus[0].connection.dbc: /nonexistent/x.dbc: cannot read the DBC file (No "
            "such file or directory)");
  c = dbc_test_xsens_connection();
  c["status"] = json::array({"XCID_Error.Nope"});
  EXPECT_EQ(err(c),
            "imus[0].connection.status[0]: no signal \"Nope\" in message \"XCID_Error\" "
            "of " +
                file);
}

TEST(DbcSignalMapTest, TheSchemaNamesTheField) {
  auto err = [](json c) {
    return dbc_test_error([&] { CanImuConnection::from_json(c, kDbcWhere); });
  };
  json c = dbc_test_xsens_connection();
  c["signals"]["gyro_x"] = "gyrX";
  EXPECT_EQ(err(c).rfind("imus[0].connection.signals.gyro_x", 0), 0u) << err(c);
  c = dbc_test_xsens_connection();
  c["signals"]["counter"] = nullptr;
  EXPECT_EQ(err(c).rfind("imus[0].connection.signals.counter", 0), 0u) << err(c);
  c = dbc_test_xsens_connection();
  c["signals"]["gyro"] = "A.B";
  EXPECT_EQ(err(c).rfind("imus[0].connection.signals", 0), 0u) << err(c);
  c = {{"interface", "can0"},
       {"map_file", dbc_test_source("sim/can/calstand-imu-can.json")},
       {"sample_rate_hz", 200},
       {"sample_start", "X"}};
  EXPECT_EQ(err(c), "imus[0].connection.sample_start: is only for a dbc layout");
  c = dbc_test_xsens_connection();
  c.erase("signals");
  EXPECT_EQ(err(c),
            "imus[0].connection.signals: is required with dbc: the DBC message and "
            "signal of each value");
  c = dbc_test_xsens_connection();
  c["signals"]["gyro_x"] = "XCID_RateOfTurn.gyrX";
  c["signals"]["gyro_y"] = "XCID_RateOfTurn.gyrX";
  EXPECT_EQ(err(c),
            "imus[0].connection.signals.gyro_y: uses payload bits another named signal "
            "of its frame uses");
}

TEST(DbcSignalMapTest, StationLoaderResolvesTheDbcNextToTheStationFile) {
  const core::StationConfig config =
      core::StationConfig::load(dbc_test_source("sim/can/xsens-mti-600-station.json"));
  const std::string dbc = config.imus.at(0).connection.at("dbc").get<std::string>();
  EXPECT_EQ(dbc, std::filesystem::path(dbc_test_source("sim/can/xsens-mti-600.dbc"))
                     .lexically_normal()
                     .string());
  const core::StationConfig mm5 =
      core::StationConfig::load(dbc_test_source("sim/can/bosch-mm5.10-station.json"));
  EXPECT_NO_THROW(CanImuConnection::from_json(mm5.imus.at(0).connection, kDbcWhere));
}

// --- end to end through the assembler ----------------------------------------------------

core::ImuSample dbc_test_sample(std::uint32_t k) {
  core::ImuSample s;
  s.sequence = k;
  s.device_time_s = 10.0 + 0.01 * k;
  s.gyro_dps = {1.5 + 0.1 * k, -20.0, 45.25};
  s.accel_mps2 = {0.5, -9.80665, 2.0 - 0.01 * k};
  s.temperature_c = 31.5;
  return s;
}

TEST(DbcEndToEndTest, XsensSamplesRoundTripAndFaultsBecomeEvents) {
  const CanImuConnection c = CanImuConnection::from_json(dbc_test_xsens_connection(), kDbcWhere);
  CanSampleAssembler a(c.map, c.sequence_modulus, c.sample_rate_hz);
  std::vector<core::ImuSample> out;
  for (std::uint32_t k = 0; k < 5; ++k) {
    for (const auto& f : encode_sample(c.map, dbc_test_sample(k))) a.feed(f, out);
  }
  ASSERT_EQ(out.size(), 5u);
  for (std::uint32_t k = 0; k < 5; ++k) {
    const auto want = dbc_test_sample(k);
    EXPECT_EQ(out[k].sequence, k);
    EXPECT_NEAR(out[k].device_time_s, want.device_time_s, 1e-4);
    // 2^-9 rad/s = 0.112 deg/s per count; 2^-8 m/s^2 per count.
    EXPECT_NEAR((out[k].gyro_dps - want.gyro_dps).norm(), 0.0, 0.1);
    EXPECT_NEAR((out[k].accel_mps2 - want.accel_mps2).norm(), 0.0, 0.004);
    EXPECT_NEAR(out[k].temperature_c, 31.5, 0.002);
  }
  EXPECT_EQ(a.stats().sequence_gaps, 0u);

  // A lost rate frame: the sample is dropped, the next one shows the gap.
  auto frames = encode_sample(c.map, dbc_test_sample(5));
  frames.erase(frames.begin() + 2);
  for (const auto& f : frames) a.feed(f, out);
  for (const auto& f : encode_sample(c.map, dbc_test_sample(6))) a.feed(f, out);
  ASSERT_EQ(out.size(), 6u);
  EXPECT_EQ(out.back().sequence, 6u);
  EXPECT_EQ(a.stats().incomplete_samples, 1u);
  EXPECT_EQ(a.stats().sequence_gaps, 1u);

  // The device's error message, in its own words, once per change.
  can_frame err{};
  err.can_id = 0x01;
  err.len = 1;
  err.data[0] = 1;
  a.feed(err, out);
  a.feed(err, out);
  const auto faults = a.take_device_faults();
  ASSERT_EQ(faults.size(), 1u);
  EXPECT_EQ(faults[0],
            "XCID_Error.ErrorCode = 1: CEI_OutputBufferOverflow: The output buffer is "
            "full, at least one message was dropped.");
  EXPECT_EQ(a.stats().status_frames, 2u);
  const auto& s = a.stats();
  EXPECT_EQ(s.frames, s.unknown_ids + s.bad_frames + s.bad_dlc + s.duplicate_frames +
                          s.late_frames + s.frames_used + s.frames_discarded + s.status_frames +
                          a.pending_frames());
}

TEST(DbcEndToEndTest, Mm510DeliversAbsentChannelsAsNaN) {
  const CanImuConnection c = CanImuConnection::from_json(dbc_test_mm5_connection(), kDbcWhere);
  EXPECT_FALSE(c.map.has_sequence);
  EXPECT_TRUE(c.map.absent[1]);  // pitch rate
  EXPECT_TRUE(c.map.absent[6]);  // temperature
  CanSampleAssembler a(c.map, c.sequence_modulus, c.sample_rate_hz);
  std::vector<core::ImuSample> out;
  // Frames before the first opening frame belong to no sample.
  const auto first = encode_sample(c.map, dbc_test_sample(0));
  a.feed(first[1], out);
  EXPECT_EQ(a.stats().frames_discarded, 1u);
  for (std::uint32_t k = 0; k < 3; ++k)
    for (const auto& f : encode_sample(c.map, dbc_test_sample(k))) a.feed(f, out);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[2].sequence, 2u);                         // samples counted by the station
  EXPECT_NEAR(out[2].device_time_s, 2.0 / 100.0, 1e-12);  // sequence / rate
  EXPECT_TRUE(std::isnan(out[0].gyro_dps.y()));
  EXPECT_TRUE(std::isnan(out[0].temperature_c));
  EXPECT_NEAR(out[0].gyro_dps.x(), 1.5, 0.005);
  EXPECT_NEAR(out[0].gyro_dps.z(), 45.25, 0.005);
  EXPECT_NEAR(out[0].accel_mps2.y(), -9.80665, 0.00125);
  EXPECT_EQ(a.stats().invalid_samples, 0u);

  can_frame diag{};
  diag.can_id = 0x5C0;
  diag.len = 8;
  diag.data[5] = 0x20;  // bit 45
  a.feed(diag, out);
  const auto faults = a.take_device_faults();
  ASSERT_EQ(faults.size(), 1u);
  EXPECT_EQ(faults[0], "ABS_M5_Status.Diag_YRS = 1: yaw rate sensor error present");
}

constexpr const char* kDbcMultiplexed = R"(BU_: IMU
BO_ 1792 IMU_DATA: 8 IMU
 SG_ Page M : 0|8@1+ (1,0) [0|255] "" Station
 SG_ Counter m0 : 8|8@1+ (1,0) [0|255] "" Station
 SG_ GyroX m0 : 16|16@1- (0.01,0) [0|0] "deg/s" Station
 SG_ GyroY m0 : 32|16@1- (0.01,0) [0|0] "deg/s" Station
 SG_ GyroZ m0 : 48|16@1- (0.01,0) [0|0] "deg/s" Station
 SG_ AccX m1 : 8|16@1- (0.001,0) [0|0] "g" Station
 SG_ AccY m1 : 24|16@1- (0.001,0) [0|0] "g" Station
 SG_ AccZ m1 : 40|16@1- (0.001,0) [0|0] "g" Station
 SG_ Temp m2 : 8|16@1- (0.01,0) [0|0] "degC" Station
)";

TEST(DbcEndToEndTest, SimpleMultiplexingSplitsOneIdIntoFrames) {
  DbcTestFile file("calstand-dbc-mux-test.dbc", kDbcMultiplexed);
  json c = {{"interface", "vcan0"},
            {"dbc", file.path},
            {"sample_rate_hz", 100},
            {"signals",
             {{"gyro_x", "IMU_DATA.GyroX"},
              {"gyro_y", "IMU_DATA.GyroY"},
              {"gyro_z", "IMU_DATA.GyroZ"},
              {"accel_x", "IMU_DATA.AccX"},
              {"accel_y", "IMU_DATA.AccY"},
              {"accel_z", "IMU_DATA.AccZ"},
              {"temperature", "IMU_DATA.Temp"},
              {"counter", "IMU_DATA.Counter"}}}};
  const CanImuConnection conn = CanImuConnection::from_json(c, kDbcWhere);
  EXPECT_EQ(conn.map.frames.size(), 3u);
  EXPECT_EQ(conn.map.ids(), (std::vector<canid_t>{0x700}));
  CanSampleAssembler a(conn.map, conn.sequence_modulus, conn.sample_rate_hz);
  std::vector<core::ImuSample> out;
  for (std::uint32_t k = 0; k < 3; ++k)
    for (const auto& f : encode_sample(conn.map, dbc_test_sample(k))) a.feed(f, out);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[1].sequence, 1u);
  EXPECT_NEAR(out[1].gyro_dps.x(), 1.6, 0.005);
  EXPECT_NEAR(out[1].accel_mps2.y(), -9.80665, 0.005);
  EXPECT_NEAR(out[1].temperature_c, 31.5, 0.005);
  can_frame other{};
  other.can_id = 0x700;
  other.len = 8;
  other.data[0] = 7;  // a page the map does not use
  a.feed(other, out);
  EXPECT_EQ(a.stats().unknown_ids, 1u);

  c["signals"]["counter"] = "IMU_DATA.Page";
  EXPECT_EQ(dbc_test_error([&] { CanImuConnection::from_json(c, kDbcWhere); }),
            "imus[0].connection.signals.counter: IMU_DATA.Page is the multiplexer switch itself, "
            "not a value");
}

// The driver over a socket pair: the MM5.10's absent channels are announced, its samples
// arrive, and the ABS's yaw rate sensor bit becomes an event in the DBC's words.
TEST(DbcEndToEndTest, CanImuAnnouncesAbsentChannelsAndReportsDeviceFaults) {
  using namespace std::chrono_literals;
  auto [device_end, driver_end] = SocketPairCan::make_pair();
  core::SteadyClock clock;
  const CanImuConnection c = CanImuConnection::from_json(dbc_test_mm5_connection(), kDbcWhere);
  CanImu imu("mm5.10", c, std::move(driver_end), clock);
  ASSERT_TRUE(imu.configure());
  ASSERT_TRUE(imu.activate());
  for (std::uint32_t k = 0; k < 20; ++k)
    for (const auto& f : encode_sample(c.map, dbc_test_sample(k)))
      ASSERT_EQ(device_end->write(f, 1000ms), "");
  can_frame diag{};
  diag.can_id = 0x5C0;
  diag.len = 8;
  diag.data[5] = 0x20;
  ASSERT_EQ(device_end->write(diag, 1000ms), "");
  std::vector<core::ImuSample> got;
  std::vector<DeviceEvent> events;
  const auto deadline = std::chrono::steady_clock::now() + 5s;
  while ((got.size() < 20 || events.size() < 2) && std::chrono::steady_clock::now() < deadline) {
    auto more = imu.poll();
    got.insert(got.end(), more.begin(), more.end());
    for (auto& e : imu.take_events()) events.push_back(e);
    std::this_thread::sleep_for(2ms);
  }
  imu.deactivate();
  ASSERT_EQ(got.size(), 20u);
  EXPECT_TRUE(std::isnan(got[19].gyro_dps.y()));
  EXPECT_NEAR(got[19].gyro_dps.x(), 1.5 + 0.1 * 19, 0.005);
  bool absent = false, fault = false;
  for (const auto& e : events) {
    absent = absent || e.message ==
                           "not measured by this device, delivered as NaN: gyro_y, "
                           "temperature";
    fault = fault || (e.fault && e.message ==
                                     "device fault: ABS_M5_Status.Diag_YRS = 1: yaw "
                                     "rate sensor error present");
  }
  EXPECT_TRUE(absent);
  EXPECT_TRUE(fault);
  EXPECT_EQ(imu.fault_counters().at("device_faults"), 1u);
}

// An automotive-style layout: an alive counter in each message, no sample counter.
TEST(DbcEndToEndTest, PerMessageCountersAreChecked) {
  DbcTestFile file("calstand-dbc-alive-test.dbc", R"(BU_: S
BO_ 256 RATE: 8 S
 SG_ Wx : 0|16@1- (0.01,0) [0|0] "deg/s" A
 SG_ Wy : 16|16@1- (0.01,0) [0|0] "deg/s" A
 SG_ Wz : 32|16@1- (0.01,0) [0|0] "deg/s" A
 SG_ Alive : 48|4@1+ (1,0) [0|15] "" A
BO_ 257 ACC: 8 S
 SG_ Ax : 0|16@1- (0.001,0) [0|0] "m/s^2" A
 SG_ Ay : 16|16@1- (0.001,0) [0|0] "m/s^2" A
 SG_ Az : 32|16@1- (0.001,0) [0|0] "m/s^2" A
 SG_ T : 48|8@1- (1,0) [0|0] "degC" A
 SG_ Alive : 60|4@1+ (1,0) [0|15] "" A
)");
  const json c = {{"interface", "vcan0"},
                  {"dbc", file.path},
                  {"sample_rate_hz", 100},
                  {"sample_start", "RATE"},
                  {"message_counters", {"RATE.Alive", "ACC.Alive"}},
                  {"signals",
                   {{"gyro_x", "RATE.Wx"},
                    {"gyro_y", "RATE.Wy"},
                    {"gyro_z", "RATE.Wz"},
                    {"accel_x", "ACC.Ax"},
                    {"accel_y", "ACC.Ay"},
                    {"accel_z", "ACC.Az"},
                    {"temperature", "ACC.T"}}}};
  const CanImuConnection conn = CanImuConnection::from_json(c, kDbcWhere);
  ASSERT_EQ(conn.map.message_counters.size(), 2u);
  CanSampleAssembler a(conn.map, conn.sequence_modulus, conn.sample_rate_hz);
  std::vector<core::ImuSample> out;
  for (std::uint32_t k = 14; k < 20; ++k)  // the 4-bit counters wrap at 16
    for (const auto& f : encode_sample(conn.map, dbc_test_sample(k))) a.feed(f, out);
  EXPECT_EQ(out.size(), 6u);
  EXPECT_EQ(a.stats().counter_errors, 0u);
  // A repeated ACC frame (stale counter) and a lost RATE frame: one error each.
  auto frames = encode_sample(conn.map, dbc_test_sample(20));
  a.feed(frames[1], out);  // ACC of a sample with no opening frame: discarded, counter 20 % 16
  a.feed(frames[1], out);  // the same again: counter did not step
  EXPECT_EQ(a.stats().counter_errors, 1u);
  for (const auto& f : encode_sample(conn.map, dbc_test_sample(21))) a.feed(f, out);
  EXPECT_EQ(a.stats().counter_errors, 2u);  // RATE: 19 -> 21
  EXPECT_EQ(out.size(), 7u);
  EXPECT_EQ(a.counters().at("counter_errors"), 2u);
}

// --- the independent peer ----------------------------------------------------------------

/// Runs dbc_peer.py on `request` and returns its frames (candump lines parsed).
std::vector<can_frame> dbc_test_peer_frames(const json& request) {
  DbcTestFile req("calstand-dbc-peer-request.json", request.dump());
  test::ChildProcess peer(
      {test::kPython, dbc_test_source("tests/unit/drivers/can/dbc_peer.py"), req.path});
  std::vector<can_frame> frames;
  while (auto line = peer.read_line()) {
    // "(t) can0 ID#DATA"
    const auto space = line->rfind(' ');
    const auto hash = line->find('#');
    if (space == std::string::npos || hash == std::string::npos) continue;
    const std::string id = line->substr(space + 1, hash - space - 1);
    const std::string data = line->substr(hash + 1);
    can_frame f{};
    f.can_id = static_cast<canid_t>(std::stoul(id, nullptr, 16));
    if (id.size() == 8) f.can_id |= CAN_EFF_FLAG;
    f.len = static_cast<std::uint8_t>(data.size() / 2);
    for (std::size_t i = 0; i < f.len; ++i)
      f.data[i] = static_cast<std::uint8_t>(std::stoul(data.substr(2 * i, 2), nullptr, 16));
    frames.push_back(f);
  }
  return frames;
}

TEST(DbcPeerTest, XsensFramesFromThePeerDecode) {
  const CanImuConnection c = CanImuConnection::from_json(dbc_test_xsens_connection(), kDbcWhere);
  json frames = json::array();
  for (int k = 0; k < 3; ++k) {
    const double t = 1000.0 + 0.01 * k;
    frames.push_back({{"message", "XCID_SampleTime"}, {"values", {{"SampleTime", t}}}});
    frames.push_back(
        {{"message", "XCID_GroupCounter"}, {"values", {{"GroupCounter", (65534 + k) % 65536}}}});
    frames.push_back({{"message", "XCID_RateOfTurn"},
                      {"values", {{"gyrX", 0.5}, {"gyrY", -1.25 * k}, {"gyrZ", 10.0}}}});
    frames.push_back({{"message", "XCID_Acceleration"},
                      {"values", {{"accX", 0.25}, {"accY", -9.8125}, {"accZ", 100.0 + k}}}});
    frames.push_back({{"message", "XCID_Temperature"}, {"values", {{"temp", -12.5}}}});
  }
  const auto got = dbc_test_peer_frames(
      {{"dbc", dbc_test_source("sim/can/xsens-mti-600.dbc")}, {"frames", frames}});
  ASSERT_EQ(got.size(), 15u);
  CanSampleAssembler a(c.map, c.sequence_modulus, c.sample_rate_hz);
  std::vector<core::ImuSample> out;
  for (const auto& f : got) a.feed(f, out);
  ASSERT_EQ(out.size(), 3u);
  const double dps = 180.0 / std::numbers::pi;
  for (std::uint32_t k = 0; k < 3; ++k) {
    EXPECT_EQ(out[k].sequence, (65534u + k) % 65536u);
    EXPECT_NEAR(out[k].device_time_s, 1000.0 + 0.01 * k, 1e-9);
    EXPECT_NEAR(out[k].gyro_dps.x(), 0.5 * dps, 1e-9);  // all exact in 2^-9 rad/s
    EXPECT_NEAR(out[k].gyro_dps.y(), -1.25 * k * dps, 1e-9);
    EXPECT_NEAR(out[k].gyro_dps.z(), 10.0 * dps, 1e-9);
    EXPECT_NEAR(out[k].accel_mps2.x(), 0.25, 1e-12);
    EXPECT_NEAR(out[k].accel_mps2.y(), -9.8125, 1e-12);
    EXPECT_NEAR(out[k].accel_mps2.z(), 100.0 + k, 1e-12);
    EXPECT_NEAR(out[k].temperature_c, -12.5, 1e-12);
  }
  EXPECT_EQ(a.stats().sequence_gaps, 0u);  // 65534, 65535, 0
}

TEST(DbcPeerTest, Mm510FramesFromThePeerDecode) {
  const CanImuConnection c = CanImuConnection::from_json(dbc_test_mm5_connection(), kDbcWhere);
  json frames = json::array();
  frames.push_back({{"message", "MM5_10_TX1"}, {"values", {{"Yaw_Rate", -100.0}, {"AY1", 0.5}}}});
  frames.push_back({{"message", "MM5_10_TX2"}, {"values", {{"Roll_Rate", 12.345}, {"AX1", -1.0}}}});
  frames.push_back({{"message", "MM5_10_TX3"}, {"values", {{"AZ", 1.0}}}});
  const auto got = dbc_test_peer_frames(
      {{"dbc", dbc_test_source("sim/can/bosch-mm5.10.dbc")}, {"frames", frames}});
  ASSERT_EQ(got.size(), 3u);
  CanSampleAssembler a(c.map, c.sequence_modulus, c.sample_rate_hz);
  std::vector<core::ImuSample> out;
  for (const auto& f : got) a.feed(f, out);
  ASSERT_EQ(out.size(), 1u);
  const double g = 9.80665;
  EXPECT_NEAR(out[0].gyro_dps.z(), -100.0, 0.0025);
  EXPECT_NEAR(out[0].gyro_dps.x(), 12.345, 0.0025);
  EXPECT_NEAR(out[0].accel_mps2.y(), 0.5 * g, 0.000128 * g);
  EXPECT_NEAR(out[0].accel_mps2.x(), -1.0 * g, 0.000128 * g);
  EXPECT_NEAR(out[0].accel_mps2.z(), 1.0 * g, 0.000128 * g);
  EXPECT_TRUE(std::isnan(out[0].gyro_dps.y()));
}

TEST(DbcPeerTest, MotorolaOddLayoutsAgreeWithThePeer) {
  // Non-byte-aligned Motorola and Intel signals across byte boundaries, signed and unsigned.
  DbcTestFile file("calstand-dbc-odd-test.dbc", R"(BU_: A
BO_ 291 ODD: 8 A
 SG_ M12 : 3|12@0- (0.5,1) [0|0] "" A
 SG_ M20 : 21|20@0+ (1,0) [0|0] "" A
 SG_ I13 : 45|13@1- (0.25,-3) [0|0] "" A
 SG_ B2 : 63|2@0+ (1,0) [0|0] "" A
)");
  const DbcFile dbc = DbcFile::load(file.path);
  const json values = {{"M12", -700.5}, {"M20", 987654}, {"I13", -1003.25}, {"B2", 2}};
  const auto got = dbc_test_peer_frames(
      {{"dbc", file.path}, {"frames", {{{"message", "ODD"}, {"values", values}}}}});
  ASSERT_EQ(got.size(), 1u);
  const std::span<const std::uint8_t, 8> payload(got[0].data);
  const DbcMessage& m = *dbc.message("ODD");
  for (const auto& [name, v] : values.items())
    EXPECT_DOUBLE_EQ(m.signal(name)->field().decode(payload), v.get<double>()) << name;
}

}  // namespace
}  // namespace calstand::drivers
