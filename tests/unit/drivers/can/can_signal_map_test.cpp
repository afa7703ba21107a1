#include "drivers/can_signal_map.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <ostream>
#include <string>

#include "../schema_error_field.hpp"
#include "can_test_support.hpp"
#include "core/error.hpp"
#include "drivers/can_sample_assembler.hpp"

namespace calstand::drivers {
namespace {

using can_test::float_map_json;
using nlohmann::json;

const std::string kMapWhere = "imus[0].connection.map";

TEST(CanSignalMapTest, ExampleMapParses) {
  const CanSignalMap map = can_test::example_map();
  ASSERT_EQ(map.frames.size(), 4u);
  EXPECT_EQ(map.ids(), (std::vector<canid_t>{0x101, 0x102, 0x103, 0x104}));
  EXPECT_TRUE(map.has_device_time);
  EXPECT_EQ(map.sequence_wrap(), 256u);
  EXPECT_EQ(map.reassembly_depth, 1u);
  for (const auto& f : map.frames) EXPECT_EQ(f.min_length, 8) << "frame " << f.id;
  EXPECT_EQ(map.frame_index(0x103), std::optional<std::size_t>(2));
  EXPECT_EQ(map.frame_index(0x103 | CAN_EFF_FLAG), std::nullopt);  // not the extended 0x103
}

TEST(CanSignalMapTest, ExtendedIdsCarryTheFlag) {
  json doc = float_map_json();
  doc["signals"]["gyro_x"]["id"] = "0x18FF0001";
  doc["signals"]["gyro_x"]["extended"] = true;
  const auto map = CanSignalMap::from_json(doc, kMapWhere);
  EXPECT_TRUE(map.frame_index(0x18FF0001u | CAN_EFF_FLAG).has_value());
  EXPECT_TRUE(map.frame_index(0x201).has_value());  // temperature stays there alone
}

/// One broken field and the error it must give: where (exact) and a phrase of why.
struct BadMap {
  const char* name;
  const char* pointer;  // JSON pointer to set (or remove when value is null)
  json value;
  const char* where;
  const char* why;
};

// gtest prints a parameter in the test's listing (ctest's names); without this, the struct's
// bytes, pointers included, which change from run to run.
void PrintTo(const BadMap& m, std::ostream* os) { *os << m.name; }

class CanSignalMapErrorTest : public ::testing::TestWithParam<BadMap> {};

TEST_P(CanSignalMapErrorTest, NamesTheFieldAndWhy) {
  const BadMap& c = GetParam();
  json doc = float_map_json();
  const json::json_pointer ptr(c.pointer);
  if (c.value.is_null()) {
    doc[ptr.parent_pointer()].erase(ptr.back());
  } else {
    doc[ptr] = c.value;
  }
  try {
    CanSignalMap::from_json(doc, kMapWhere);
    FAIL() << "accepted a map with " << c.name;
  } catch (const core::InputError& e) {
    EXPECT_EQ(test::error_field(e), kMapWhere + c.where) << e.what();
    EXPECT_NE(std::string(e.what()).find(c.why), std::string::npos) << e.what();
  }
}

INSTANTIATE_TEST_SUITE_P(
    Mistakes, CanSignalMapErrorTest,
    ::testing::Values(
        BadMap{"length beyond 64 bits", "/signals/gyro_x/length_bits", 64,
               ".signals.gyro_x.length_bits", "beyond the 64 bits"},
        BadMap{"length of 65 bits", "/signals/gyro_x/length_bits", 65,
               ".signals.gyro_x.length_bits", "65 is not one of 32, 64"},
        BadMap{"start byte beyond 7", "/signals/gyro_x/start_byte", 8, ".signals.gyro_x.start_byte",
               "8 is greater than the maximum 7"},
        BadMap{"overlapping fields", "/signals/temperature/start_byte", 3, ".signals.temperature",
               "overlaps gyro_x in frame 0x201"},
        BadMap{"a value over the sequence", "/signals/gyro_y/start_byte", 0, ".signals.gyro_y",
               "overlaps sequence"},
        BadMap{"unknown byte order", "/signals/gyro_x/byte_order", "middle",
               ".signals.gyro_x.byte_order", "\"middle\" is not one of \"little\", \"big\""},
        BadMap{"unknown map byte order", "/byte_order", "motorola", ".byte_order",
               "\"motorola\" is not one of"},
        BadMap{"missing signal", "/signals/gyro_z", nullptr, ".signals.gyro_z",
               "missing required property \"gyro_z\""},
        BadMap{"missing sequence", "/signals/sequence", nullptr, ".signals.sequence",
               "missing required property \"sequence\""},
        BadMap{"unknown signal", "/signals/gyro_w", json::object(), ".signals.gyro_w",
               "unknown property \"gyro_w\""},
        BadMap{"typo in a key", "/signals/gyro_x/lenght_bits", 8, ".signals.gyro_x.lenght_bits",
               "unknown property \"lenght_bits\" (did you mean \"length_bits\"?)"},
        BadMap{"missing length", "/signals/gyro_x/length_bits", nullptr,
               ".signals.gyro_x.length_bits", "missing required property"},
        BadMap{"missing type", "/signals/gyro_x/type", nullptr, ".signals.gyro_x.type",
               "missing required property"},
        BadMap{"unknown type", "/signals/gyro_x/type", "int", ".signals.gyro_x.type",
               "\"int\" is not one of \"unsigned\", \"signed\", \"float\""},
        BadMap{"16-bit float", "/signals/gyro_x/length_bits", 16, ".signals.gyro_x.length_bits",
               "16 is not one of 32, 64"},
        BadMap{"no start", "/signals/gyro_x/start_byte", nullptr, ".signals.gyro_x.start_byte",
               "give start_byte or start_bit"},
        BadMap{"two starts", "/signals/gyro_x/start_bit", 8, ".signals.gyro_x.start_byte",
               "not both"},
        BadMap{"11-bit id too big", "/signals/gyro_x/id", "0x800", ".signals.gyro_x.id",
               "beyond the 11-bit ids"},
        BadMap{"id not a number", "/signals/gyro_x/id", "0x10G", ".signals.gyro_x.id",
               "does not match the pattern"},
        BadMap{"missing id", "/signals/gyro_x/id", nullptr, ".signals.gyro_x.id",
               "missing required property"},
        BadMap{"negative length", "/signals/gyro_x/length_bits", -8, ".signals.gyro_x.length_bits",
               "-8 is less than the minimum 1"},
        BadMap{"zero scale", "/signals/gyro_x/scale", 0, ".signals.gyro_x.scale",
               "not allowed (\"0, which would erase the signal\")"},
        BadMap{"scale not a number", "/signals/gyro_x/scale", "1e-5", ".signals.gyro_x.scale",
               "expected a number, got a string"},
        BadMap{"unit mismatch", "/signals/gyro_x/unit", "rad/s", ".signals.gyro_x.unit",
               "\"rad/s\" is not the required value \"deg/s\""},
        BadMap{"sequence over 32 bits", "/signals/sequence/length_bits", 40,
               ".signals.sequence.length_bits", "40 is greater than the maximum 32"},
        BadMap{"signed sequence", "/signals/sequence/type", "signed", ".signals.sequence.type",
               "\"signed\" is not the required value \"unsigned\""},
        BadMap{"sequence with an id", "/signals/sequence/id", "0x201", ".signals.sequence.id",
               "unknown property \"id\""},
        BadMap{"reassembly depth 0", "/reassembly_depth", 0, ".reassembly_depth",
               "0 is less than the minimum 1"},
        BadMap{"signals not an object", "/signals", json::array(), ".signals",
               "expected an object, got an array"}),
    [](const ::testing::TestParamInfo<BadMap>& param) {
      std::string n = param.param.name;
      for (char& ch : n) ch = std::isalnum(static_cast<unsigned char>(ch)) ? ch : '_';
      return n;
    });

TEST(CanSignalMapTest, FileErrorsNameTheFileAndTheField) {
  const std::string dir = ::testing::TempDir();
  const std::string missing = dir + "/calstand-no-such-map.json";
  try {
    CanSignalMap::load(missing, "imus[1].connection.map_file");
    FAIL() << "loaded a missing file";
  } catch (const core::InputError& e) {
    EXPECT_EQ(e.where(), "imus[1].connection.map_file");
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
  }
  const std::string broken = dir + "/calstand-broken-map.json";
  {
    json doc = float_map_json();
    doc["signals"]["accel_y"]["length_bits"] = 72;
    std::ofstream(broken) << doc.dump();
  }
  try {
    CanSignalMap::load(broken, "imus[1].connection.map_file");
    FAIL() << "accepted a 72-bit field";
  } catch (const core::InputError& e) {
    // The station field that names the file, the file, then the path within it.
    EXPECT_EQ(e.where(), "imus[1].connection.map_file " + broken);
    EXPECT_EQ(test::error_field(e), "signals.accel_y.length_bits");
  }
  std::ofstream(broken) << "{ not json";
  EXPECT_THROW(CanSignalMap::load(broken, "m"), core::InputError);
  std::remove(broken.c_str());
}

TEST(CanSignalMapTest, EncodeThenDecodeRoundTripsWithinQuantisation) {
  const CanSignalMap map = can_test::example_map();
  CanSampleAssembler assembler(map, 256, 200.0);
  std::vector<core::ImuSample> out;
  for (std::uint32_t i = 0; i < 300; ++i) {
    const core::ImuSample in = can_test::sample(i, 1.0 + i * 0.005);
    const auto frames = encode_sample(map, in);
    ASSERT_EQ(frames.size(), 4u);
    out.clear();
    for (const auto& f : frames) assembler.feed(f, out);
    ASSERT_EQ(out.size(), 1u) << "sample " << i;
    const core::ImuSample& s = out.front();
    EXPECT_EQ(s.sequence, i % 256);
    // Half a count of each field's scale.
    EXPECT_LE((s.gyro_dps - in.gyro_dps).cwiseAbs().maxCoeff(), 0.5e-5 + 1e-12);
    EXPECT_LE((s.accel_mps2 - in.accel_mps2).cwiseAbs().maxCoeff(), 0.5e-5 + 1e-12);
    EXPECT_NEAR(s.temperature_c, in.temperature_c, 0.005 + 1e-12);
    EXPECT_NEAR(s.device_time_s, in.device_time_s, 0.5e-6 + 1e-12);
  }
  EXPECT_EQ(assembler.stats().samples, 300u);
  EXPECT_EQ(assembler.stats().sequence_gaps, 0u);  // 255 -> 0 is a wrap, not a gap
}

TEST(CanSignalMapTest, FloatMapRoundTripsAtFloatPrecision) {
  const CanSignalMap map = CanSignalMap::from_json(float_map_json(), kMapWhere);
  EXPECT_FALSE(map.has_device_time);
  CanSampleAssembler assembler(map, 256, 100.0);
  std::vector<core::ImuSample> out;
  const core::ImuSample in = can_test::sample(7, 0.0);
  for (const auto& f : encode_sample(map, in)) assembler.feed(f, out);
  ASSERT_EQ(out.size(), 1u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_FLOAT_EQ(static_cast<float>(out[0].gyro_dps[i]), static_cast<float>(in.gyro_dps[i]));
    EXPECT_FLOAT_EQ(static_cast<float>(out[0].accel_mps2[i]), static_cast<float>(in.accel_mps2[i]));
  }
}

}  // namespace
}  // namespace calstand::drivers
