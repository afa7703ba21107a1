// Models from lists (the daemon's JSON requests): errors name the entry at fault.
#include "analysis/run_model.hpp"

#include <gtest/gtest.h>

namespace calstand::analysis {
namespace {

std::string where_of(const std::vector<std::string>& terms,
                     const std::vector<std::string>& customs) {
  try {
    model_from_lists(terms, customs);
  } catch (const core::InputError& e) {
    return e.where();
  }
  return "no error";
}

TEST(ModelFromLists, AnEmptyListIsTheDefaultModel) {
  EXPECT_EQ(model_from_lists({}, {}).text(), solver::Model::parse(kDefaultModel).text());
}

TEST(ModelFromLists, TermsAndCustomsMakeTheSameModelAsTheCommandLine) {
  const solver::Model m =
      model_from_lists({"gyro_bias", "gyro_temp_bias:2"}, {"k=gyro.z:force_z^2"});
  const solver::Model cli =
      solver::Model::parse("gyro_bias,gyro_temp_bias:2", {"k=gyro.z:force_z^2"});
  EXPECT_EQ(m.text(), cli.text());
  EXPECT_EQ(m.size(), cli.size());
}

TEST(ModelFromLists, ErrorsNameTheEntryAtFault) {
  EXPECT_EQ(where_of({"gyro_bias", "gyro_bais"}, {}), "model[1]");
  EXPECT_EQ(where_of({"gyro_temp_bias:12"}, {}), "model[0]");
  EXPECT_EQ(where_of({"gyro_bias,accel_bias"}, {}), "model[0]");
  EXPECT_EQ(where_of({"gyro_bias"}, {"ok=gyro:force_z", "bad=gyro:temperature_rat"}), "custom[1]");
  EXPECT_EQ(where_of({"gyro_bias"}, {"nosensor:force_z"}), "custom[0]");
  EXPECT_EQ(where_of({"gyro_bias", "gyro_bias"}, {}), "model");
}

TEST(ModelFromLists, TheReasonIsKeptWithoutTheCommandLinesOptionName) {
  try {
    model_from_lists({"gyro_bais"}, {});
    FAIL() << "no error";
  } catch (const core::InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("model[0]: ", 0), 0u) << what;
    EXPECT_EQ(what.find("--model"), std::string::npos) << what;
    EXPECT_NE(what.find("gyro_bais"), std::string::npos) << what;
  }
}

TEST(ParseSensorRows, NamesWhereTheBadValueCameFrom) {
  EXPECT_EQ(parse_sensor_rows("gyro"), solver::SensorRows::kGyro);
  EXPECT_EQ(parse_sensor_rows("accel"), solver::SensorRows::kAccel);
  EXPECT_EQ(parse_sensor_rows("both"), solver::SensorRows::kBoth);
  try {
    parse_sensor_rows("all", "sensor");
    FAIL() << "no error";
  } catch (const core::InputError& e) {
    EXPECT_EQ(e.where(), "sensor");
  }
}

}  // namespace
}  // namespace calstand::analysis
