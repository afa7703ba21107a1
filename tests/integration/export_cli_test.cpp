// calstand export-calibration as a user runs it: every format written from a record file, the
// warnings on stderr, and bad input refused with exit code 2 and nothing written.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>

#include "cli_runner.hpp"

namespace {

using calstand::testing::read_text;
using calstand::testing::run;
using calstand::testing::write_text;

constexpr double kPi = 3.14159265358979323846;

// A record as `calstand calibrate` writes one, with numbers chosen here.
std::string export_record(const std::string& model_terms, const std::string& parameters) {
  return R"({"format": "calstand-calibration/1",
    "device": {"name": "imu0", "model": "adis16488", "serial": "A1234"},
    "station": "lab-2", "runs": [4],
    "procedure": {"name": "thermal-calibration", "sha256": ")" +
         std::string(64, 'b') + R"("},
    "model": [)" +
         model_terms +
         R"(], "custom_terms": [],
    "parameters": [)" +
         parameters + R"(],
    "unidentifiable": [],
    "fit": {"chi2_dof": 1.1, "dof": 30, "residual_rms": {"gyro": 0.001, "accel": 0.001},
            "noise_floor": {"gyro": [0.001, 0.001, 0.001], "accel": [0.001, 0.001, 0.001]}},
    "temperature_ref_c": 25.0, "valid_temperature_c": {"min": -20.0, "max": 60.0},
    "created_utc": "2024-06-01T12:00:00Z", "software": "calstand test"})";
}

std::string record_parameter(const std::string& name, double value, const std::string& unit) {
  std::ostringstream s;
  s.precision(17);
  s << R"({"name": ")" << name << R"(", "value": )" << value << R"(, "sigma": 0.0, "unit": ")"
    << unit << R"("})";
  return s.str();
}

class CliExportCalibration : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = ::testing::TempDir() + "calstand-export-cli-" + std::to_string(::getpid()) + "/";
    std::filesystem::create_directories(dir_);
    record_ = dir_ + "record.json";
    write_text(record_,
               export_record(R"("gyro_bias", "gyro_scale", "gyro_temp_bias:2", "accel_bias",
                                "accel_scale", "accel_misalignment")",
                             record_parameter("gyro_bias.x", 0.04, "deg/s") + "," +
                                 record_parameter("gyro_scale.y", 250.0, "ppm") + "," +
                                 record_parameter("gyro_temp_bias.z2", 3e-6, "deg/s/degC^k") + "," +
                                 record_parameter("accel_bias.z", -0.07, "m/s^2") + "," +
                                 record_parameter("accel_scale.x", 1200.0, "ppm") + "," +
                                 record_parameter("accel_misalignment.yx", 5e-4, "rad")));
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  // The value of parameter `name` in a PX4 .params file (tab-separated) or an ArduPilot
  // .param file (NAME,VALUE).
  static double value_in(const std::string& text, const std::string& name, char separator) {
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) {
      if (line.empty() || line[0] == '#') continue;
      std::istringstream fields(line);
      std::string f;
      std::vector<std::string> all;
      while (std::getline(fields, f, separator)) all.push_back(f);
      const std::size_t name_at = separator == '\t' ? 2 : 0;
      if (all.size() > name_at + 1 && all[name_at] == name) return std::stod(all[name_at + 1]);
    }
    ADD_FAILURE() << name << " not in:\n" << text;
    return std::nan("");
  }

  std::size_t files_in_dir() const {
    std::size_t n = 0;
    for (const auto& e : std::filesystem::directory_iterator(dir_)) n += e.is_regular_file();
    return n;
  }

  std::string dir_;
  std::string record_;
};

TEST_F(CliExportCalibration, WritesEveryFormatAndNamesWhatItLeavesOutOnStderr) {
  const std::string err = dir_ + "stderr.txt";
  auto r = run("export-calibration --record " + record_ + " --format px4 --out " + dir_ +
                   "unit.params --px4-gyro-id 2490378 --px4-accel-id 2490378",
               err);
  ASSERT_EQ(r.exit_code, 0) << r.out << read_text(err);
  EXPECT_NE(r.out.find("written to " + dir_ + "unit.params"), std::string::npos) << r.out;
  std::string warnings = read_text(err);
  EXPECT_NE(warnings.find("calstand: warning: PX4 has no parameter for gyro_scale.x .y .z, "
                          "accel_misalignment.xy"),
            std::string::npos)
      << warnings;
  const std::string px4 = read_text(dir_ + "unit.params");
  EXPECT_NEAR(value_in(px4, "TC_G0_X0_0", '\t'), 0.04 * kPi / 180.0, 1e-12);
  EXPECT_NEAR(value_in(px4, "TC_G0_X2_2", '\t'), 3e-6 * kPi / 180.0, 1e-15);
  EXPECT_NEAR(value_in(px4, "TC_A0_X0_2", '\t'), -0.07, 1e-12);
  EXPECT_NEAR(value_in(px4, "CAL_ACC0_XSCALE", '\t'), 1.0 / 1.0012, 1e-8);

  r = run(
      "export-calibration --record " + record_ + " --format ardupilot --out " + dir_ + "unit.param",
      err);
  ASSERT_EQ(r.exit_code, 0) << r.out << read_text(err);
  warnings = read_text(err);
  EXPECT_NE(warnings.find("ArduPilot has no parameter for gyro_scale"), std::string::npos)
      << warnings;
  const std::string ap = read_text(dir_ + "unit.param");
  EXPECT_NEAR(value_in(ap, "INS_ACCOFFS_Z", ','), -0.07, 1e-12);
  EXPECT_NEAR(value_in(ap, "INS_ACCSCAL_X", ','), 1.0 / 1.0012, 1e-8);
  // 3e-6 (T - 25)^2 about ArduPilot's 35 degC: the quadratic keeps its coefficient, times 1e6.
  EXPECT_NEAR(value_in(ap, "INS_TCAL1_GYR2_Z", ','), 3e-6 * kPi / 180.0 * 1e6, 1e-8);

  r = run("export-calibration --record " + record_ + " --format kalibr --update-rate 250 --out " +
              dir_ + "kalibr_imu_chain.yaml",
          err);
  ASSERT_EQ(r.exit_code, 0) << r.out << read_text(err);
  const std::string yaml = read_text(dir_ + "kalibr_imu_chain.yaml");
  EXPECT_EQ(yaml.rfind("%YAML:1.0\n", 0), 0u);  // the first line, as OpenCV wants it
  EXPECT_NE(yaml.find("\nimu0:\n"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("  update_rate: 250"), std::string::npos) << yaml;
  EXPECT_NE(read_text(err).find("no noise figures"), std::string::npos);

  r = run("export-calibration --record " + record_ + " --format csv --out " + dir_ + "unit.csv",
          err);
  ASSERT_EQ(r.exit_code, 0) << r.out << read_text(err);
  EXPECT_EQ(read_text(err), "");  // a spreadsheet holds everything
  const std::string csv = read_text(dir_ + "unit.csv");
  EXPECT_NE(csv.find("imu0,adis16488,A1234,lab-2,4,thermal-calibration,"), std::string::npos);
  EXPECT_NE(csv.find(",accel_scale.x,1200,0,ppm,fitted,\r\n"), std::string::npos) << csv;
}

TEST_F(CliExportCalibration, BadInputIsExitCode2NamingItAndWritesNothing) {
  const std::string out = dir_ + "out.params";
  auto r = run("export-calibration --record " + record_ + " --format mavlink --out " + out);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("--format: unknown format \"mavlink\" (one of px4, px4-legacy"),
            std::string::npos)
      << r.out;
  EXPECT_FALSE(std::filesystem::exists(out));

  // An existing file stays as it was whatever is refused.
  write_text(out, "earlier\n");
  r = run("export-calibration --record " + dir_ + "missing.json --format px4 --out " + out);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find(dir_ + "missing.json"), std::string::npos) << r.out;

  const std::string bad = dir_ + "bad.json";
  write_text(bad, export_record(R"("gyro_bias")", record_parameter("gyro_bias.x", 0.1, "rad/s")));
  r = run("export-calibration --record " + bad + " --format csv --out " + out);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find(bad + ": parameters[0].unit"), std::string::npos) << r.out;

  const std::string quartic = dir_ + "quartic.json";
  write_text(quartic, export_record(R"("gyro_bias", "gyro_temp_bias:4")",
                                    record_parameter("gyro_temp_bias.x4", 1e-9, "deg/s/degC^k")));
  r = run("export-calibration --record " + quartic + " --format ardupilot --out " + out);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("gyro_temp_bias:4"), std::string::npos) << r.out;

  r = run("export-calibration --record " + record_ + " --format openvins --out " + out);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("--update-rate"), std::string::npos) << r.out;

  r = run("export-calibration --record " + record_ + " --format openvins --update-rate 0 --out " +
          out);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("--update-rate: must be positive"), std::string::npos) << r.out;

  r = run("export-calibration --record " + record_ + " --format px4 --instance 5 --out " + out);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("--instance"), std::string::npos) << r.out;

  EXPECT_EQ(read_text(out), "earlier\n");
  // No temporary left behind: the record, the two bad records and the untouched file.
  EXPECT_EQ(files_in_dir(), 4u);
}

}  // namespace
