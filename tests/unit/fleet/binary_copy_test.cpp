// The rows of the fleet sync's binary COPY (fleet/src/binary_copy.hpp) against the bytes the
// PostgreSQL manual's "Binary Format" section of COPY and the types' send functions give,
// written out by hand here: a 16-bit field count per row, per field a 32-bit length (-1 for
// NULL) and the value in network byte order (int4, int8, float8 as IEEE 754, a uuid's 16
// bytes, text and bytea as they are). The round trip through a server is the fleet tests'.
#include "binary_copy.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <stdexcept>
#include <string>

namespace calstand::fleet::detail {
namespace {

std::string bytes(std::initializer_list<int> b) {
  std::string s;
  for (int c : b) s.push_back(static_cast<char>(c));
  return s;
}

TEST(BinaryCopyRows, IntegersInNetworkOrderWithTheirLengths) {
  BinaryCopyRows rows;
  rows.begin_row(3);
  rows.integer(CopyType::kInt4, "attempt", -2);
  rows.integer(CopyType::kInt8, "local_id", 0x0102030405060708LL);
  rows.integer(CopyType::kInt2, "small", 258);
  EXPECT_EQ(rows.data(), bytes({0, 3,                                            // 3 fields
                                0, 0, 0, 4, 0xff, 0xff, 0xff, 0xfe,              // int4 -2
                                0, 0, 0, 8, 1,    2,    3,    4,    5, 6, 7, 8,  // int8
                                0, 0, 0, 2, 1,    2}));                          // int2 258
}

TEST(BinaryCopyRows, DoublesAsTheirIeeeBitsAndNullAsMinusOne) {
  BinaryCopyRows rows;
  rows.real(CopyType::kFloat8, "time_s", 1.0);   // 0x3ff0000000000000
  rows.real(CopyType::kFloat8, "gx_dps", -0.1);  // 0xbfb999999999999a
  rows.integer(CopyType::kFloat8, "count", 3);   // an integer in a double column: 3.0
  rows.null();
  EXPECT_EQ(rows.data(),
            bytes({0,    0,    0,    8,   0x3f, 0xf0, 0,    0,    0,    0,    0,    0,     //
                   0,    0,    0,    8,   0xbf, 0xb9, 0x99, 0x99, 0x99, 0x99, 0x99, 0x9a,  //
                   0,    0,    0,    8,   0x40, 0x08, 0,    0,    0,    0,    0,    0,     //
                   0xff, 0xff, 0xff, 0xff}));
}

TEST(BinaryCopyRows, TextBlobsAndUuidsAsTheirBytes) {
  BinaryCopyRows rows;
  rows.text(CopyType::kText, "device", "imu0");
  const unsigned char blob[] = {0x00, 0x0a, 0x5c, 0xff};  // NUL, newline, backslash: as they are
  rows.bytes(CopyType::kBytea, "data", blob, sizeof blob);
  rows.text(CopyType::kUuid, "station", "0123abcd-4567-89ef-0123-456789ABCDEF");
  rows.text(CopyType::kInt8, "run_id", "42");  // a fixed field given as text
  EXPECT_EQ(rows.data(),
            bytes({0,    0,    0,    4,    'i',  'm',  'u',  '0',                     //
                   0,    0,    0,    4,    0x00, 0x0a, 0x5c, 0xff,                    //
                   0,    0,    0,    16,   0x01, 0x23, 0xab, 0xcd, 0x45, 0x67, 0x89,  //
                   0xef, 0x01, 0x23, 0x45, 0x67, 0x89, 0xab, 0xcd, 0xef,              //
                   0,    0,    0,    8,    0,    0,    0,    0,    0,    0,    0,    42}));
}

TEST(BinaryCopyRows, RefusesValuesTheColumnCannotHoldNamingIt) {
  BinaryCopyRows rows;
  const auto message = [&](auto write) -> std::string {
    try {
      write();
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(message([&] { rows.integer(CopyType::kInt4, "count", 1LL << 31); }),
            "column count: 2147483648 is beyond an integer");
  EXPECT_EQ(message([&] { rows.real(CopyType::kInt4, "count", 1.5); }),
            "column count: the real 1.5 is not a value of this column");
  EXPECT_EQ(message([&] { rows.text(CopyType::kInt8, "run_id", "4x"); }),
            "column run_id: '4x' is not an integer");
  EXPECT_EQ(message([&] { rows.text(CopyType::kUuid, "station", "0123"); }),
            "column station: '0123' is not a UUID");
  EXPECT_EQ(message([&] { copy_type_of("t.when", "timestamp with time zone"); }),
            "column t.when: type timestamp with time zone has no binary COPY writer here");
  EXPECT_TRUE(rows.data().empty());  // nothing half written
}

TEST(BinaryCopyRows, TypesByTheirSqlNames) {
  EXPECT_EQ(copy_type_of("c", "integer"), CopyType::kInt4);
  EXPECT_EQ(copy_type_of("c", "bigint"), CopyType::kInt8);
  EXPECT_EQ(copy_type_of("c", "double precision"), CopyType::kFloat8);
  EXPECT_EQ(copy_type_of("c", "text"), CopyType::kText);
  EXPECT_EQ(copy_type_of("c", "bytea"), CopyType::kBytea);
  EXPECT_EQ(copy_type_of("c", "uuid"), CopyType::kUuid);
}

}  // namespace
}  // namespace calstand::fleet::detail
