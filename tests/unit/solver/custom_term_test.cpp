// Custom terms on some axes only (`NAME=SENSOR.AXES:EXPRESSION`): the parameters of the listed
// axes alone, their regressors on those channels alone, and the text read back as written.
#include "solver/custom_term.hpp"

#include <gtest/gtest.h>

#include "core/error.hpp"
#include "solver/model.hpp"

namespace calstand::solver {
namespace {

std::vector<std::string> parameter_names(const Model& m) {
  std::vector<std::string> out;
  for (const auto& p : m.parameters()) out.push_back(p.name);
  return out;
}

TEST(CustomTerm, AllAxesUnlessTheSensorNamesSome) {
  const CustomTermSpec all = parse_custom_term("k=gyro:force_{axis}^2", "test");
  EXPECT_EQ(all.axes, (std::array<bool, 3>{true, true, true}));
  EXPECT_EQ(all.text(), "k=gyro:force_{axis}^2");
  const CustomTermSpec z = parse_custom_term("k=gyro.z:force_z^2", "test");
  EXPECT_EQ(z.sensor, core::TermSensor::kGyro);
  EXPECT_EQ(z.expression, "force_z^2");
  EXPECT_EQ(z.axes, (std::array<bool, 3>{false, false, true}));
  EXPECT_EQ(z.text(), "k=gyro.z:force_z^2");
  // Axes in any order read back in x, y, z order.
  EXPECT_EQ(parse_custom_term("k=accel.zx:rate_{axis}", "test").text(), "k=accel.xz:rate_{axis}");
  EXPECT_EQ(parse_custom_term("k=accel.xyz:elapsed", "test").text(), "k=accel:elapsed");
}

TEST(CustomTerm, ABadAxisSelectionIsAnInputError) {
  for (const char* text :
       {"k=gyro.w:force_z", "k=gyro.zz:force_z", "k=gyro.:force_z", "k=gyr.z:force_z"}) {
    EXPECT_THROW((void)parse_custom_term(text, std::string("--custom ") + text), core::InputError)
        << text;
  }
}

TEST(CustomTerm, OnlyTheListedAxesHaveParametersAndRegressors) {
  const Model m = Model::parse("gyro_bias", {"k=gyro.xz:force_{axis}^2", "j=accel.y:temperature"});
  EXPECT_EQ(parameter_names(m), (std::vector<std::string>{"gyro_bias.x", "gyro_bias.y",
                                                          "gyro_bias.z", "k.x", "k.z", "j.y"}));
  Signals s;
  s.force_mps2 = Eigen::Vector3d(1.0, 2.0, 3.0);
  s.temperature_c = 40.0;
  Eigen::MatrixXd g(kChannels, static_cast<Eigen::Index>(m.size()));
  m.regressors(s, g);
  Eigen::MatrixXd expected = Eigen::MatrixXd::Zero(kChannels, 6);
  expected(kGx, 0) = expected(kGy, 1) = expected(kGz, 2) = 1.0;
  expected(kGx, 3) = 1.0;  // force_x^2
  expected(kGz, 4) = 9.0;  // force_z^2
  expected(kAy, 5) = 40.0;
  EXPECT_EQ(g, expected);
}

}  // namespace
}  // namespace calstand::solver
