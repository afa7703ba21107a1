// The CSV export read back by a small RFC 4180 reader: one row per parameter whose numbers are
// the record's exactly, each with the unit's identity.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "export_test_support.hpp"
#include "exports/calibration_export.hpp"

namespace calstand::analysis {
namespace {

using testing::HandRecord;

// RFC 4180: CRLF records, fields separated by commas, a quoted field may hold commas, line
// breaks and doubled quotes.
std::vector<std::vector<std::string>> read_csv_rows(const std::string& text) {
  std::vector<std::vector<std::string>> rows;
  std::vector<std::string> row;
  std::string f;
  bool quoted = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (quoted) {
      if (c == '"' && i + 1 < text.size() && text[i + 1] == '"') {
        f += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        f += c;
      }
    } else if (c == '"') {
      EXPECT_TRUE(f.empty()) << "quote inside an unquoted field";
      quoted = true;
    } else if (c == ',') {
      row.push_back(f);
      f.clear();
    } else if (c == '\r') {
      EXPECT_TRUE(i + 1 < text.size() && text[i + 1] == '\n') << "CR without LF";
    } else if (c == '\n') {
      EXPECT_TRUE(i > 0 && text[i - 1] == '\r') << "LF without CR";
      row.push_back(f);
      f.clear();
      rows.push_back(row);
      row.clear();
    } else {
      f += c;
    }
  }
  EXPECT_TRUE(row.empty() && f.empty() && !quoted) << "the last record is not terminated";
  return rows;
}

TEST(ExportCsv, EveryParameterReadsBackExactlyWithTheUnitsIdentity) {
  HandRecord h;
  h.model = "gyro_bias,gyro_temp_bias:2,accel_scale,accel_misalignment,k";
  h.customs = {"k=accel:force_{axis}^2"};
  h.values = {{"gyro_bias.x", 0.1 / 3.0},       {"gyro_bias.z", -2.5e-3},
              {"gyro_temp_bias.y2", 1.25e-7},   {"accel_scale.x", 123.456789012345},
              {"accel_misalignment.yx", -4e-4}, {"k.z", 6e-5}};
  h.undetermined = {{"accel_misalignment.zy", "no turn about x, \"held\""}};
  h.serial = "SN,42 \"B\"";  // a comma and quotes: the field must be quoted
  h.runs = {12, 14};
  const solver::Calibration c = testing::hand_calibration(h);
  const nlohmann::json record = testing::hand_record_json(h);
  const ExportResult r = export_calibration(c, ExportFormat::kCsv);
  EXPECT_TRUE(r.warnings.empty());

  const auto rows = read_csv_rows(r.text);
  ASSERT_FALSE(rows.empty());
  const std::vector<std::string> header = {"device",
                                           "device_model",
                                           "serial",
                                           "station",
                                           "runs",
                                           "procedure",
                                           "procedure_sha256",
                                           "created_utc",
                                           "temperature_ref_c",
                                           "parameter",
                                           "value",
                                           "sigma",
                                           "unit",
                                           "status",
                                           "note"};
  ASSERT_EQ(rows[0], header);
  const std::size_t n = record.at("parameters").size();
  ASSERT_EQ(rows.size(), 1 + n + 1);
  const auto column = [&](const std::string& name) {
    return static_cast<std::size_t>(std::find(header.begin(), header.end(), name) - header.begin());
  };
  for (std::size_t i = 0; i < rows.size() - 1; ++i) {
    const auto& row = rows[i + 1];
    ASSERT_EQ(row.size(), header.size()) << i;
    EXPECT_EQ(row[column("device")], "imu0");
    EXPECT_EQ(row[column("device_model")], "test-imu");
    EXPECT_EQ(row[column("serial")], h.serial);
    EXPECT_EQ(row[column("station")], "export-test-station");
    EXPECT_EQ(row[column("runs")], "12;14");
    EXPECT_EQ(row[column("procedure")], "thermal-calibration");
    EXPECT_EQ(row[column("procedure_sha256")], std::string(64, 'a'));
    EXPECT_EQ(row[column("created_utc")], "2024-05-06T07:08:09Z");
    EXPECT_EQ(std::stod(row[column("temperature_ref_c")]), 25.0);
    if (i == n) break;
    const auto& p = record.at("parameters").at(i);
    EXPECT_EQ(row[column("parameter")], p.at("name"));
    // 17 significant digits: the same double.
    EXPECT_EQ(std::stod(row[column("value")]), p.at("value").get<double>()) << p;
    EXPECT_EQ(std::stod(row[column("sigma")]), p.at("sigma").get<double>()) << p;
    EXPECT_EQ(row[column("unit")], p.at("unit"));
    EXPECT_EQ(row[column("status")], "fitted");
  }
  const auto& undetermined = rows.back();
  EXPECT_EQ(undetermined[column("parameter")], "accel_misalignment.zy");
  EXPECT_EQ(undetermined[column("value")], "");
  EXPECT_EQ(undetermined[column("sigma")], "");
  EXPECT_EQ(undetermined[column("unit")], "rad");
  EXPECT_EQ(undetermined[column("status")], "not determined");
  EXPECT_EQ(undetermined[column("note")], "no turn about x, \"held\"");
}

TEST(ExportCsv, ARecordWithoutTemperatureHasAnEmptyReference) {
  HandRecord h;
  h.model = "accel_bias";
  h.values = {{"accel_bias.y", 0.5}};
  h.temperature_ref_c = nullptr;
  h.valid_min_c = nullptr;
  h.valid_max_c = nullptr;
  const auto rows =
      read_csv_rows(export_calibration(testing::hand_calibration(h), ExportFormat::kCsv).text);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[1][8], "");
  EXPECT_EQ(rows[1][9], "accel_bias.y");
  EXPECT_EQ(std::stod(rows[1][10]), 0.5);
}

}  // namespace
}  // namespace calstand::analysis
