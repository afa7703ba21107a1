// Kalibr imu.yaml export: units, the worst axis, and bad figures.
#include "noise/kalibr.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>
#include <sstream>
#include <string>

#include "core/error.hpp"
#include "noise/run_noise.hpp"

namespace calstand::solver {
namespace {

// "key: value  # comment" lines into key -> value text (comments and blank lines skipped).
std::map<std::string, std::string> parse_yaml(const std::string& text) {
  std::map<std::string, std::string> out;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    const auto hash = line.find('#');
    const std::string body = line.substr(0, hash == 0 ? 0 : line.find("  #"));
    const auto colon = body.find(':');
    if (colon == std::string::npos) continue;
    std::string value = body.substr(colon + 1);
    value.erase(0, value.find_first_not_of(' '));
    out[body.substr(0, colon)] = value;
  }
  return out;
}

TEST(Kalibr, WritesEveryFieldInItsUnit) {
  KalibrImu imu;
  imu.rostopic = "/stim300/imu";
  imu.update_rate_hz = 125.0;
  imu.accelerometer_noise_density = 5.0e-4;
  imu.accelerometer_random_walk = 2.0e-5;
  imu.gyroscope_noise_density = 4.36e-5;
  imu.gyroscope_random_walk = 1.2e-7;
  const std::string yaml = kalibr_yaml(imu);
  const auto kv = parse_yaml(yaml);
  ASSERT_EQ(kv.size(), 6u) << yaml;
  EXPECT_DOUBLE_EQ(std::stod(kv.at("accelerometer_noise_density")), 5.0e-4);
  EXPECT_DOUBLE_EQ(std::stod(kv.at("accelerometer_random_walk")), 2.0e-5);
  EXPECT_DOUBLE_EQ(std::stod(kv.at("gyroscope_noise_density")), 4.36e-5);
  EXPECT_DOUBLE_EQ(std::stod(kv.at("gyroscope_random_walk")), 1.2e-7);
  EXPECT_EQ(kv.at("rostopic"), "\"/stim300/imu\"");
  EXPECT_DOUBLE_EQ(std::stod(kv.at("update_rate")), 125.0);
  EXPECT_NE(yaml.find("gyroscope_noise_density: 4.36e-05  # [rad/s/sqrt(Hz)]"), std::string::npos)
      << yaml;
  EXPECT_NE(yaml.find("[m/s^3/sqrt(Hz)]"), std::string::npos);
}

ChannelNoise channel(ImuChannel c, double n, double k, bool k_resolved = true) {
  ChannelNoise ch;
  ch.channel = c;
  ch.terms.random_walk = {n, 0.0, true};
  ch.terms.rate_random_walk = {k, 0.0, k_resolved};
  return ch;
}

TEST(Kalibr, FromRunNoiseTakesTheWorstAxisInRadians) {
  RunNoise noise;
  noise.sample_rate_hz = 200.0;
  // Gyro N [deg/sqrt(s)] and K [deg/s/sqrt(s)]; accel N [m/s/sqrt(s)], K [m/s^2/sqrt(s)].
  noise.channels = {
      channel(ImuChannel::kGx, 0.002, 1e-5),       channel(ImuChannel::kGy, 0.003, 3e-5),
      channel(ImuChannel::kGz, 0.001, 2e-5),       channel(ImuChannel::kAx, 4e-4, 1e-5),
      channel(ImuChannel::kAy, 6e-4, 2e-5, false), channel(ImuChannel::kAz, 5e-4, 0.0, false)};
  std::vector<std::string> unresolved;
  const KalibrImu imu = kalibr_from_run_noise(noise, "/imu0", &unresolved);
  const double rad = std::numbers::pi / 180.0;
  EXPECT_DOUBLE_EQ(imu.gyroscope_noise_density, 0.003 * rad);
  EXPECT_DOUBLE_EQ(imu.gyroscope_random_walk, 3e-5 * rad);
  EXPECT_DOUBLE_EQ(imu.accelerometer_noise_density, 6e-4);
  EXPECT_DOUBLE_EQ(imu.accelerometer_random_walk, 2e-5);
  EXPECT_DOUBLE_EQ(imu.update_rate_hz, 200.0);
  EXPECT_EQ(unresolved, std::vector<std::string>{"accelerometer_random_walk"});
}

TEST(Kalibr, BadFigures) {
  KalibrImu imu;
  imu.update_rate_hz = 100.0;
  EXPECT_NO_THROW(kalibr_yaml(imu));
  imu.gyroscope_random_walk = -1.0;
  EXPECT_THROW(kalibr_yaml(imu), core::InputError);
  imu.gyroscope_random_walk = std::nan("");
  EXPECT_THROW(kalibr_yaml(imu), core::InputError);
  imu.gyroscope_random_walk = 0.0;
  imu.update_rate_hz = 0.0;
  EXPECT_THROW(kalibr_yaml(imu), core::InputError);
  imu.update_rate_hz = 100.0;
  imu.rostopic = "";
  EXPECT_THROW(kalibr_yaml(imu), core::InputError);
}

}  // namespace
}  // namespace calstand::solver
