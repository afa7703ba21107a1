#include "core/error_terms.hpp"

#include <gtest/gtest.h>

namespace calstand::core {
namespace {

TEST(ErrorTerms, CatalogueHoldsEveryContractTermOnce) {
  const char* expected[] = {"gyro_bias",
                            "gyro_scale",
                            "gyro_misalignment",
                            "gyro_scale_asymmetry",
                            "gyro_quadratic",
                            "gyro_g_sensitivity",
                            "gyro_temp_bias",
                            "gyro_temp_scale",
                            "earth_rate",
                            "accel_bias",
                            "accel_scale",
                            "accel_misalignment",
                            "accel_scale_asymmetry",
                            "accel_quadratic",
                            "accel_temp_bias",
                            "accel_temp_scale",
                            "accel_lever_arm",
                            "table_tilt"};
  ASSERT_EQ(error_term_catalogue().size(), std::size(expected));
  for (const char* name : expected) {
    const ErrorTermInfo* t = find_error_term(name);
    ASSERT_NE(t, nullptr) << name;
    EXPECT_EQ(t->name, name);
    EXPECT_FALSE(t->effect.empty()) << name;
  }
  EXPECT_EQ(find_error_term("gyro_bais"), nullptr);
}

TEST(ErrorTerms, ParameterNamesFollowTheContract) {
  EXPECT_EQ(parameter_names(*find_error_term("gyro_misalignment")),
            (std::vector<std::string>{"gyro_misalignment.xy", "gyro_misalignment.xz",
                                      "gyro_misalignment.yx", "gyro_misalignment.yz",
                                      "gyro_misalignment.zx", "gyro_misalignment.zy"}));
  EXPECT_EQ(parameter_names(*find_error_term("gyro_g_sensitivity")).size(), 9u);
  EXPECT_EQ(parameter_names(*find_error_term("table_tilt")),
            (std::vector<std::string>{"table_tilt.east", "table_tilt.north"}));
  EXPECT_TRUE(parameter_names(*find_error_term("earth_rate")).empty());
  const auto temp2 = parameter_names(*find_error_term("gyro_temp_bias"), 2);
  EXPECT_EQ(temp2, (std::vector<std::string>{"gyro_temp_bias.x1", "gyro_temp_bias.y1",
                                             "gyro_temp_bias.z1", "gyro_temp_bias.x2",
                                             "gyro_temp_bias.y2", "gyro_temp_bias.z2"}));
  EXPECT_EQ(find_error_term("accel_quadratic")->unit, "ug/g^2");
  EXPECT_EQ(find_error_term("gyro_g_sensitivity")->unit, "(deg/s)/g");
}

TEST(ErrorTerms, ParsesFullNamesIntoAxes) {
  std::string why;
  auto p = parse_parameter_name("gyro_g_sensitivity.xz", &why);
  ASSERT_TRUE(p) << why;
  EXPECT_EQ(p->axis, 0);
  EXPECT_EQ(p->second_axis, 2);
  p = parse_parameter_name("gyro_temp_bias.y2", &why);
  ASSERT_TRUE(p) << why;
  EXPECT_EQ(p->axis, 1);
  EXPECT_EQ(p->order, 2);
  p = parse_parameter_name("table_tilt.north", &why);
  ASSERT_TRUE(p) << why;
  EXPECT_EQ(p->component, "north");
}

TEST(ErrorTerms, RejectsNamesOutsideTheContractWithAReason) {
  std::string why;
  EXPECT_FALSE(parse_parameter_name("gyro_misalignment.xx", &why));
  EXPECT_NE(why.find("unknown component \"xx\" of gyro_misalignment"), std::string::npos) << why;
  EXPECT_FALSE(parse_parameter_name("gyro_bias", &why));
  EXPECT_NE(why.find("<term>.<component>"), std::string::npos) << why;
  EXPECT_FALSE(parse_parameter_name("gyro_offset.x", &why));
  EXPECT_NE(why.find("unknown error term \"gyro_offset\""), std::string::npos) << why;
  EXPECT_FALSE(parse_parameter_name("gyro_temp_bias.x0", &why));
  EXPECT_FALSE(parse_parameter_name("gyro_temp_bias.w1", &why));
  EXPECT_FALSE(parse_parameter_name("gyro_temp_bias.x01", &why));
  EXPECT_FALSE(parse_parameter_name("earth_rate.x", &why));
  EXPECT_NE(why.find("has no parameters"), std::string::npos) << why;
}

}  // namespace
}  // namespace calstand::core
