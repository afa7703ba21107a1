// export_calibration()'s dispatcher: the format names, the options' checks, and the file that
// is written whole or not at all.
#include "exports/calibration_export.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>

#include "core/error.hpp"
#include "core/file_output.hpp"
#include "export_test_support.hpp"

namespace calstand::analysis {
namespace {

std::string export_refusal_where(const std::function<void()>& f) {
  try {
    f();
  } catch (const core::InputError& e) {
    return e.where();
  }
  return "(accepted)";
}

TEST(CalibrationExport, EveryFormatNameParsesAndAnUnknownOneListsThem) {
  EXPECT_EQ(parse_export_format("px4"), ExportFormat::kPx4);
  EXPECT_EQ(parse_export_format("px4-legacy"), ExportFormat::kPx4Legacy);
  EXPECT_EQ(parse_export_format("ardupilot"), ExportFormat::kArduPilot);
  EXPECT_EQ(parse_export_format("openvins"), ExportFormat::kOpenVins);
  EXPECT_EQ(parse_export_format("kalibr"), ExportFormat::kOpenVins);
  EXPECT_EQ(parse_export_format("csv"), ExportFormat::kCsv);
  EXPECT_EQ(export_formats().size(), 6u);
  try {
    parse_export_format("PX4");
    ADD_FAILURE() << "accepted";
  } catch (const core::InputError& e) {
    EXPECT_EQ(e.where(), "--format");
    for (const auto& f : export_formats()) {
      EXPECT_NE(std::string(e.what()).find(f.name), std::string::npos) << f.name;
    }
  }
}

TEST(CalibrationExport, OptionsOutOfRangeAreRefusedNamingTheOption) {
  testing::HandRecord h;
  h.model = "gyro_bias";
  const solver::Calibration c = testing::hand_calibration(h);
  const auto refused = [&](ExportOptions o) {
    return export_refusal_where([&] { export_calibration(c, ExportFormat::kCsv, o); });
  };
  ExportOptions o;
  o.instance = 3;
  EXPECT_EQ(refused(o), "--instance");
  o = {};
  o.px4_gyro_id = -1;
  EXPECT_EQ(refused(o), "--px4-gyro-id");
  o = {};
  o.px4_accel_id = 0x100000000LL;
  EXPECT_EQ(refused(o), "--px4-accel-id");
  o = {};
  o.mav_sysid = 0;
  EXPECT_EQ(refused(o), "--sysid");
  o = {};
  o.rostopic = "two\nlines";
  EXPECT_EQ(refused(o), "--rostopic");
  o = {};
  o.update_rate_hz = -100.0;
  EXPECT_EQ(refused(o), "--update-rate");
  EXPECT_EQ(refused(ExportOptions{}), "(accepted)");
}

TEST(CalibrationExport, TheFileIsReplacedWholeOrLeftAlone) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("calstand-export-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "out.params").string();
  const auto read = [](const std::string& p) {
    std::ifstream f(p);
    return std::string(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
  };
  core::write_file_whole(path, "old\n");
  core::write_file_whole(path, "new text\n");
  EXPECT_EQ(read(path), "new text\n");
  // A target in a folder that does not exist: refused by name, nothing left behind.
  const std::string missing = (dir / "no-such-folder" / "out.params").string();
  EXPECT_EQ(export_refusal_where([&] { core::write_file_whole(missing, "x"); }), missing);
  std::size_t files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) files += e.is_regular_file();
  EXPECT_EQ(files, 1u);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace calstand::analysis
